"""The viewport's left-mouse tools: place a particle, brush particles on or off, move a cloud or a particle.

The viewport turns the mouse into a ray each frame and calls `press`, `hold`
and `release`; the maths is `cloudcore.scenes.editing`.  A brush stroke and a drag
are each one undo step (`Editor.begin_gesture`).
"""

from __future__ import annotations

import numpy as np

from app.editor import Editor
from cloudcore.scenes.editing import (
    BrushStroke,
    add_particle,
    add_particles,
    delete_particles,
    drag_offset,
    drag_plane_normal,
    particles_within,
    pick_particle,
    point_at_altitude,
    point_on_cloud,
    point_on_plane,
    translated,
)


class ViewportTools:
    def __init__(self, editor: Editor):
        self.editor = editor
        self._stroke: BrushStroke | None = None
        self._stroke_missed = False
        # a drag: (scene it started from, cloud, particle or None, grabbed point, plane normal)
        self._drag: tuple | None = None

    @property
    def busy(self) -> bool:
        """A stroke or a drag is under way."""
        return self._stroke is not None or self._drag is not None

    def press(self, ray, screen_plane: bool) -> None:
        """The left button went down on the viewport; `screen_plane` drags in the screen's plane."""
        tool = self.editor.tool
        if tool == "brush":
            self._start_stroke(ray)
        elif tool in ("move_cloud", "move_particle"):
            self._start_drag(ray, tool == "move_particle", screen_plane)

    def hold(self, ray, seconds: float) -> None:
        """The left button is still down, `seconds` after the last frame."""
        if not self.editor.history.in_gesture:  # undone or redone mid-gesture: the rest of it is void
            self._stroke = self._drag = None
        if self._stroke is not None:
            self._dab(ray, self._stroke.due(seconds))
        elif self._drag is not None:
            start, cloud, particle, grabbed, normal = self._drag
            offset = drag_offset(*ray, grabbed, normal)
            if offset is not None:  # beyond the plane's horizon the thing stays where it last was
                self.editor.change(lambda: translated(start, cloud, offset, particle))

    def release(self, ray, clicked: bool) -> None:
        """The left button came up; `clicked`: without leaving the viewport (a click, for Place)."""
        editor = self.editor
        if self._drag is not None:
            cloud, particle = self._drag[1:3]
            editor.end_gesture()
            if particle is not None:
                editor.pick(cloud, particle)
            self._drag = None
        elif self._stroke is not None:
            editor.end_gesture()
            self._stroke = None
        elif clicked and editor.tool == "place":
            self._place(ray)

    def _target_point(self, ray) -> np.ndarray | None:
        """Where Place and Brush put particles: on the selected cloud, or on the altitude plane."""
        editor = self.editor
        if editor.on_cloud_surface:
            return point_on_cloud(editor.scene.clouds[editor.selected_cloud], *ray)
        return point_at_altitude(*ray, editor.placement_altitude)

    def _why_missed(self) -> str:
        editor = self.editor
        if editor.on_cloud_surface:
            return "the mouse is not over a particle of the selected cloud"
        return f"that ray never reaches the placement altitude ({editor.placement_altitude:g} m)"

    def _place(self, ray) -> None:
        editor = self.editor
        if editor.selected_cloud is None:
            editor.messages.append("select or add a cloud before placing particles")
            return
        point = self._target_point(ray)
        if point is None:
            editor.messages.append(self._why_missed())
            return
        editor.change(lambda: add_particle(editor.scene, editor.selected_cloud, point, editor.particle_radius))

    def _start_stroke(self, ray) -> None:
        editor = self.editor
        if editor.selected_cloud is None:
            editor.messages.append("select or add a cloud before brushing")
            return
        try:
            stroke = BrushStroke(editor.next_stroke_seed(), editor.brush_rate)
        except ValueError as error:
            editor.messages.append(f"cannot brush: {error}")
            return
        editor.begin_gesture()
        self._stroke, self._stroke_missed = stroke, False
        self._dab(ray, self._stroke.due(0.0))

    def _dab(self, ray, count: int) -> None:
        if not count:
            return
        editor = self.editor
        point = self._target_point(ray)
        if point is None:
            if not self._stroke_missed:  # once a stroke, not once a frame
                editor.messages.append(self._why_missed())
            self._stroke_missed = True
            return
        cloud = editor.selected_cloud
        if editor.brush_erases:
            erased = particles_within(editor.scene.clouds[cloud], point, editor.brush_radius)
            editor.edit(delete_particles(editor.scene, cloud, erased))
        else:
            centres = self._stroke.dab(point, editor.brush_radius, count)
            editor.change(lambda: add_particles(editor.scene, cloud, centres, editor.particle_radius))

    def _start_drag(self, ray, one_particle: bool, screen_plane: bool) -> None:
        editor = self.editor
        hit = pick_particle(editor.scene, *ray)
        if hit is not None:
            cloud, particle, grabbed = hit
            editor.selected_cloud = cloud
        elif one_particle:
            editor.messages.append("no particle under the mouse to move")
            return
        elif editor.selected_cloud is None or not len(editor.scene.clouds[editor.selected_cloud].particles):
            editor.messages.append("select a cloud with particles to move")
            return
        else:
            # beside the cloud: grab the plane through its centre, so the drag still moves it
            cloud, particle = editor.selected_cloud, None
            centre, _ = editor.scene.clouds[cloud].bounding_sphere()
            grabbed = point_on_plane(*ray, centre, drag_plane_normal(editor.camera, screen_plane))
            if grabbed is None:
                editor.messages.append("the mouse is beyond the horizon of the cloud's plane: nothing to grab")
                return
        editor.begin_gesture()
        self._drag = (
            editor.scene,
            cloud,
            particle if one_particle else None,
            grabbed,
            drag_plane_normal(editor.camera, screen_plane),
        )
