"""The 3D viewport: the engine draws the editor's scene into the window's GL context; clicks place particles.

Mouse: left click places a particle in the selected cloud (on the plane at the
placement altitude), right drag turns the camera, middle drag or wheel flies.
Keys while the viewport is hovered: W/S forward/back, A/D sideways, Q/E down/up.
"""

from __future__ import annotations

import time

import numpy as np
from imgui_bundle import imgui

from app.editor import Editor
from cloudcore.editing import add_particle, pick_ray, point_at_altitude
from cloudcore.gl.context import WindowContext
from cloudcore.gl.frame import FrameRenderer
from cloudcore.navigation import moved, turned

TURN_DEG_PER_PIXEL = 0.2


class Viewport:
    def __init__(self, editor: Editor):
        self.editor = editor
        self.renderer: FrameRenderer | None = None
        self.fly_speed = 300.0  # metres per second
        self.measure_overdraw = False
        self.capture_next = False  # a GUI test asks for the next frame's pixels
        self.captured: np.ndarray | None = None
        self.regenerations_total = 0
        self._last_time = time.perf_counter()

    def gui(self) -> None:
        editor = self.editor
        available = imgui.get_content_region_avail()
        width, height = max(1, int(available.x)), max(1, int(available.y))
        if self.renderer is None:
            self.renderer = FrameRenderer(width, height, context=WindowContext(width, height))
        self.renderer.resize(width, height)
        start = time.perf_counter()
        _, stats = self.renderer.render(editor.scene, camera=editor.camera, settings=editor.settings,
                                        time_s=editor.scene_time_s, read_back=False)
        if self.measure_overdraw:
            stats |= self.renderer.measure_overdraw()[1]
        texture = self.renderer.display_texture()
        if self.capture_next:
            self.captured, self.capture_next = self.renderer.read_display(), False
        stats["viewport_ms"] = 1e3 * (time.perf_counter() - start)
        self.regenerations_total += stats.get("impostors_regenerated", 0)
        editor.record_frame(stats)

        origin = imgui.get_cursor_screen_pos()
        # GL keeps rows bottom first: flip v
        imgui.image(imgui.ImTextureRef(texture), imgui.ImVec2(width, height), imgui.ImVec2(0, 1), imgui.ImVec2(1, 0))
        imgui.set_cursor_screen_pos(origin)
        clicked = imgui.invisible_button("canvas", imgui.ImVec2(width, height),
                                         imgui.ButtonFlags_.mouse_button_left | imgui.ButtonFlags_.mouse_button_right)
        hovered = imgui.is_item_hovered()
        mouse = imgui.get_mouse_pos()
        if clicked and imgui.is_mouse_released(imgui.MouseButton_.left):
            self._place_particle((mouse.x - origin.x) / width, (mouse.y - origin.y) / height, width / height)
        self._navigate(hovered)

    def _place_particle(self, x: float, y: float, aspect: float) -> None:
        editor = self.editor
        if editor.selected_cloud is None:
            editor.messages.append("select or add a cloud before placing particles")
            return
        origin, direction = pick_ray(editor.camera, aspect, x, y)
        point = point_at_altitude(origin, direction, editor.placement_altitude)
        if point is None:
            editor.messages.append(f"that ray never reaches the placement altitude ({editor.placement_altitude:g} m)")
            return
        editor.edit(add_particle(editor.scene, editor.selected_cloud, point, editor.particle_radius))

    def _navigate(self, hovered: bool) -> None:
        now = time.perf_counter()
        seconds, self._last_time = min(now - self._last_time, 0.25), now
        editor, io = self.editor, imgui.get_io()
        if imgui.is_item_active() and imgui.is_mouse_dragging(imgui.MouseButton_.right):
            delta = io.mouse_delta
            editor.camera = turned(editor.camera, delta.x * TURN_DEG_PER_PIXEL, -delta.y * TURN_DEG_PER_PIXEL)
        if not hovered:
            return
        step = self.fly_speed * seconds
        keys = {imgui.Key.w: (step, 0, 0), imgui.Key.s: (-step, 0, 0), imgui.Key.d: (0, step, 0),
                imgui.Key.a: (0, -step, 0), imgui.Key.e: (0, 0, step), imgui.Key.q: (0, 0, -step)}
        for key, (forward, right, up) in keys.items():
            if imgui.is_key_down(key) and not io.key_ctrl:
                editor.camera = moved(editor.camera, forward, right, up)
        if io.mouse_wheel:
            editor.camera = moved(editor.camera, forward=io.mouse_wheel * self.fly_speed * 0.5)

    def close(self) -> None:
        if self.renderer is not None:
            self.renderer.close()
            self.renderer = None

