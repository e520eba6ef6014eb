"""The 3D viewport: the engine draws the editor's scene into the window's GL context; the mouse edits it.

Mouse: the left button uses the editor's tool (`app.tools`): Place puts a
particle in the selected cloud on a click, Brush adds (or erases) particles
while held, Move cloud / Move particle drag what they grab parallel to the
placement plane (with Shift held at the press, in the screen's plane).  Right
drag turns the camera, the wheel flies forward.  Keys while the viewport is
hovered: W/S forward/back, A/D sideways, Q/E down/up.

Over the picture it outlines the impostors and ring segments of the frame plan
(`cloudcore.stats.overlays`) when asked, and shows the overdraw heat map
(`cloudcore.stats.heatmap`) in place of the frame when that is on.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np
from imgui_bundle import imgui

from app.editor import Editor, ShownFrame
from app.tools import ViewportTools
from cloudcore.gl.context import WindowContext
from cloudcore.gl.frame import FrameRenderer
from cloudcore.gl.image_texture import ImageTexture
from cloudcore.light.illumination import IlluminationCache
from cloudcore.light.live_air import LiveAir
from cloudcore.light.relighting import EXACT_METHOD, PREVIEW_METHOD, LiveIllumination, Look
from cloudcore.scenes.editing import pick_ray
from cloudcore.stats.heatmap import heat_image, ramp_colours
from cloudcore.stats.overlays import impostor_outlines, ring_outlines, to_pixels
from cloudcore.world.navigation import moved, turned
from cloudcore.world.wind import light_time, reshapes

TURN_DEG_PER_PIXEL = 0.2
#: a frame that shows the picture again while the relighting worker runs waits this long first, or until the
#: worker's look is in (`LiveIllumination.pause`): the window's own drawing (panels, plots, the X server's copy)
#: takes most of a core on llvmpipe, and the worker needs it; the window still follows the mouse at about 20
#: frames a second
RELIGHT_PAUSE_S = 0.03
#: outline colours (RGBA): impostors yellow, crossfading clouds orange, ring panels cyan, the picked particle red
_OUTLINE_COLOURS = {"impostor": (255, 220, 0, 220), "crossfade": (255, 140, 0, 220), "ring": (0, 220, 255, 200)}
_PICKED_COLOUR = (255, 60, 60, 255)
_LEGEND_STEPS = 32


class Viewport:
    def __init__(self, editor: Editor, remember_costs: bool = True):
        """`remember_costs`: auto mode's cost model starts from the last session's on this machine, and this
        one's is kept (`FrameRenderer`); off where runs must start alike (GUI tests, scripted frames)."""
        self.editor = editor
        self.remember_costs = remember_costs
        self.tools = ViewportTools(editor)
        self.renderer: FrameRenderer | None = None
        self.fly_speed = 300.0  # metres per second
        self.measure_overdraw = False
        self.heat_map = False  # show the overdraw counts instead of the frame
        self.show_impostor_outlines = False
        self.show_ring_segments = False
        self.capture_next = False  # a GUI test asks for the next frame's pixels (as shown)
        self.captured: np.ndarray | None = None
        self.outlines_drawn: list = []  # this frame's overlay outlines (`cloudcore.stats.overlays.Outline`)
        self.regenerations_total = 0
        self.relighting = LiveIllumination(IlluminationCache())
        self.relighting.start()
        self.air = LiveAir()
        #: the scene time whose shapes of the clouds a wind reshapes are drawn lit (`FrameRenderer.render`'s
        #: `lit_at`): the clock's period once the worker has its light (`_choose_lit_at`)
        self.lit_at: float | None = None
        self._last_inputs, self._last_stats = None, None  # what the picture shown was drawn from, and its stats
        #: the last frame showed the picture before it again and no path is playing: nothing moves on its own
        self.at_rest = False
        self._shown: int | None = None  # the display texture of the picture shown
        self._heat_texture: ImageTexture | None = None
        self._last_time = time.perf_counter()

    def gui(self) -> None:
        editor = self.editor
        now = time.perf_counter()
        # one clock for flying, brushing and playing paths; a stall (re-shading) is not a leap
        seconds, self._last_time = min(now - self._last_time, 0.25), now
        editor.advance_playback(seconds)
        available = imgui.get_content_region_avail()
        width, height = max(1, int(available.x)), max(1, int(available.y))
        if self.renderer is None:
            self.renderer = FrameRenderer(
                width,
                height,
                context=WindowContext(width, height),
                illumination=self.relighting.cache,
                remember_costs=self.remember_costs,
                air=self.air,
            )
        self.renderer.resize(width, height)
        start = time.perf_counter()
        scene, method = self._scene_as_shown()
        # an exact aerial-perspective volume built since (`LiveAir`) draws the picture again
        air_built = self.air.built
        inputs = (
            scene,
            method,
            editor.camera,
            editor.settings,
            editor.scene_time_s,
            self.lit_at,
            (width, height),
            air_built,
        )
        plan = self.renderer.last_plan
        if (
            inputs == self._last_inputs
            and plan is not None
            and (plan.settled or self.relighting.busy)
            and not (self.measure_overdraw or self.heat_map)
        ):
            # the same inputs and nothing converging, or nothing worth converging to while a new light is on its
            # way (the impostors and ring would be remade for a light already superseded): the same picture,
            # and the cores go to the relighting worker
            stats, reused = self._last_stats, True
            if self.relighting.busy:
                self.relighting.pause(RELIGHT_PAUSE_S)
        else:
            _, stats = self.renderer.render(
                scene,
                camera=editor.camera,
                settings=editor.settings,
                time_s=editor.scene_time_s,
                read_back=False,
                illumination_method=method,
                lit_at=self.lit_at,
            )
            self._last_inputs, self._last_stats, reused = inputs, stats, False
        heat = None
        if self.measure_overdraw or self.heat_map:
            counts, overdraw = self.renderer.measure_overdraw()
            stats = stats.with_overdraw(overdraw)
            heat = heat_image(counts) if self.heat_map else None
        if not reused or self._shown is None:  # a picture shown again is in its display texture already
            self._shown = self.renderer.display_texture()
        texture = self._shown
        # texture coordinates of the image's top left and bottom right corners: the frame's rows are bottom
        # first as GL keeps them (flip v), the heat map's top first
        uv_top_left, uv_bottom_right = imgui.ImVec2(0, 1), imgui.ImVec2(1, 0)
        if heat is not None:
            if self._heat_texture is None:
                self._heat_texture = ImageTexture()
            texture = self._heat_texture.upload(heat[0])
            uv_top_left, uv_bottom_right = imgui.ImVec2(0, 0), imgui.ImVec2(1, 1)
        if self.capture_next:
            self.captured = heat[0][..., :3] if heat is not None else self.renderer.read_display()
            self.capture_next = False
        shown = ShownFrame(
            frame=stats,
            picture_reused=reused,
            relighting=self.relighting.busy,
            shown_time_of_day=scene.lighting.time_of_day,
            shown_illumination=method,
            frame_start_s=now,
            viewport_ms=1e3 * (time.perf_counter() - start),
            viewport_width=width,
            viewport_height=height,
        )
        self.regenerations_total += shown.impostors_regenerated
        self.at_rest = reused and not editor.playing
        editor.record_frame(shown)

        origin = imgui.get_cursor_screen_pos()
        imgui.image(imgui.ImTextureRef(texture), imgui.ImVec2(width, height), uv_top_left, uv_bottom_right)
        self._draw_overlays(origin, (width, height), heat[1] if heat is not None else None)
        imgui.set_cursor_screen_pos(origin)
        clicked = imgui.invisible_button(
            "canvas",
            imgui.ImVec2(width, height),
            imgui.ButtonFlags_.mouse_button_left | imgui.ButtonFlags_.mouse_button_right,
        )
        hovered = imgui.is_item_hovered()
        self._use_tool(origin, (width, height), clicked, seconds)
        self._navigate(hovered, seconds)

    def _scene_as_shown(self):
        """(the editor's scene in the look the viewport can show this frame, its illumination method).

        A dragged slider's look is lit by the coarse raster (`PREVIEW_METHOD`), the scene's own exactly;
        until the worker has it, the last look shown stays (`cloudcore.light.relighting`)."""
        editor = self.editor
        shading, lighting = editor.look
        wanted = Look(shading, lighting, PREVIEW_METHOD if editor.dragged_look is not None else EXACT_METHOD)
        scene = editor.scene
        lit = dataclasses.replace(scene, clouds=self.renderer.drawn_clouds(scene, self._choose_lit_at(scene, wanted)))
        look = self.relighting.look_for(self._with_field_clouds(lit), wanted)
        if self.relighting.failure is not None and self.relighting.failure not in editor.messages:
            editor.messages.append(self.relighting.failure)
        if (look.shading, look.lighting) != (scene.shading, scene.lighting):
            scene = dataclasses.replace(scene, shading=look.shading, lighting=look.lighting)
        return scene, look.method

    def _choose_lit_at(self, scene, look: Look) -> float:
        """The scene time whose shapes the wind gives the clouds are drawn lit: the clock's relight period
        (`cloudcore.world.wind.light_time`) once its light is at hand, else the one drawn before while the relighting
        worker lights the new shapes: the window keeps drawing, where shading them here held it 2 seconds."""
        now = light_time(scene.wind, self.editor.scene_time_s)
        if self.lit_at is None or self.lit_at == now or not reshapes(scene.wind):
            self.lit_at = now
        elif self.relighting.lit(self.renderer.drawn_clouds(scene, now), look):
            self.lit_at = now
        return self.lit_at

    def _with_field_clouds(self, scene):
        """`scene` with the clouds its cloud field has made around the eye (the renderer holds them), so that
        a new look lights them in the relighting worker too, not in the frame that shows it."""
        state = self.renderer.field_state if self.renderer is not None else None
        if state is None or scene.cloud_field is None or state.field != scene.cloud_field:
            return scene
        return dataclasses.replace(scene, clouds=scene.clouds + tuple(c for c in state.cells.values() if c is not None))

    def _use_tool(self, origin, size, clicked: bool, seconds: float) -> None:
        mouse, (width, height) = imgui.get_mouse_pos(), size
        ray = pick_ray(self.editor.camera, width / height, (mouse.x - origin.x) / width, (mouse.y - origin.y) / height)
        left = imgui.MouseButton_.left
        if imgui.is_item_activated() and imgui.is_mouse_clicked(left):
            self.tools.press(ray, screen_plane=imgui.get_io().key_shift)
        elif self.tools.busy and imgui.is_mouse_down(left):
            self.tools.hold(ray, seconds)
        elif imgui.is_mouse_released(left):
            self.tools.release(ray, clicked)

    def _draw_overlays(self, origin, size, heat_top: float | None) -> None:
        editor, plan = self.editor, self.renderer.last_plan
        draw = imgui.get_window_draw_list()
        outlines = []
        if plan is not None and self.show_impostor_outlines:
            outlines += impostor_outlines(plan, editor.camera, size)
        if plan is not None and self.show_ring_segments:
            outlines += ring_outlines(plan, editor.camera, size, editor.settings.ring_elevation_deg)
        for outline in outlines:
            points = [imgui.ImVec2(origin.x + x, origin.y + y) for x, y in outline.points]
            draw.add_polyline(
                points, imgui.IM_COL32(*_OUTLINE_COLOURS[outline.kind]), 1.5, imgui.ImDrawFlags_.closed.value
            )
        self.outlines_drawn = outlines
        picked = editor.picked_particle
        if picked is not None:
            pixels, in_front = to_pixels(editor.scene.clouds[picked[0]].centres[picked[1]], editor.camera, size)
            if in_front[0]:
                x, y = pixels[0]
                draw.add_circle(
                    imgui.ImVec2(origin.x + x, origin.y + y), 6.0, imgui.IM_COL32(*_PICKED_COLOUR), thickness=2.0
                )
        if heat_top is not None:
            self._draw_legend(draw, origin, size, heat_top)

    def _draw_legend(self, draw, origin, size, top: float) -> None:
        """The heat map's ramp from 0 to `top` fragments per pixel, in the viewport's lower left corner."""
        step_width, bar_height = 5.0, 12.0
        left, bottom = origin.x + 10.0, origin.y + size[1] - 10.0
        for step, colour in enumerate(ramp_colours(np.linspace(0.0, 1.0, _LEGEND_STEPS))):
            x = left + step * step_width
            draw.add_rect_filled(
                imgui.ImVec2(x, bottom - bar_height),
                imgui.ImVec2(x + step_width, bottom),
                imgui.IM_COL32(*(int(c) for c in colour), 255),
            )
        white = imgui.IM_COL32(255, 255, 255, 255)
        label_y = bottom - bar_height - imgui.get_text_line_height() - 2.0
        draw.add_text(imgui.ImVec2(left, label_y), white, "0")
        draw.add_text(
            imgui.ImVec2(left + _LEGEND_STEPS * step_width + 6.0, bottom - imgui.get_text_line_height()),
            white,
            f"{top:g} fragments per pixel",
        )

    def _navigate(self, hovered: bool, seconds: float) -> None:
        editor, io = self.editor, imgui.get_io()
        if imgui.is_item_active() and imgui.is_mouse_dragging(imgui.MouseButton_.right):
            delta = io.mouse_delta
            editor.camera = turned(editor.camera, delta.x * TURN_DEG_PER_PIXEL, -delta.y * TURN_DEG_PER_PIXEL)
        if not hovered:
            return
        step = self.fly_speed * seconds
        keys = {
            imgui.Key.w: (step, 0, 0),
            imgui.Key.s: (-step, 0, 0),
            imgui.Key.d: (0, step, 0),
            imgui.Key.a: (0, -step, 0),
            imgui.Key.e: (0, 0, step),
            imgui.Key.q: (0, 0, -step),
        }
        for key, (forward, right, up) in keys.items():
            if imgui.is_key_down(key) and not io.key_ctrl:
                editor.camera = moved(editor.camera, forward, right, up)
        if io.mouse_wheel:
            editor.camera = moved(editor.camera, forward=io.mouse_wheel * self.fly_speed * 0.5)

    def close(self) -> None:
        if self._heat_texture is not None:
            self._heat_texture.close()
            self._heat_texture = None
        if self.renderer is not None:
            self.renderer.close()
            self.renderer = None
        self.relighting.close()
        self.air.close()
