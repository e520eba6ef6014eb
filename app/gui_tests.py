"""GUI tests run by the Dear ImGui Test Engine inside the real editor (`python -m app SCENE --self-test OUT.json`).

Each test clicks and types into the real widgets; GL work stays on the main
thread (tests only set flags and yield frames).  `tests/test_gui.py` runs the
editor under Xvfb and checks the results file.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from imgui_bundle import hello_imgui, imgui
from imgui_bundle.imgui import test_engine as te
from imgui_bundle.imgui.test_engine_checks import CHECK

#: frames to let the renderer catch up after an edit (illumination runs on the next frame)
SETTLE = 4


def install(params, editor, viewport, panels, results_path: Path, outcome: dict) -> None:
    registered: list = []

    def capture(ctx) -> np.ndarray:
        viewport.capture_next = True
        while viewport.capture_next:
            ctx.yield_()
        return viewport.captured

    def use_window(ctx, name: str) -> None:
        """Bring a panel's tab to the front (items in hidden tabs cannot be reached), then address it."""
        hello_imgui.get_runner_params().docking_params.focus_dockable_window(name)
        ctx.yield_(2)
        ctx.set_ref(name)

    def click_viewport(ctx, x: float, y: float) -> None:
        rect = ctx.item_info("//Viewport/canvas").rect_full
        ctx.mouse_move_to_pos(imgui.ImVec2(rect.min.x + x * (rect.max.x - rect.min.x),
                                           rect.min.y + y * (rect.max.y - rect.min.y)))
        ctx.mouse_click(0)
        ctx.yield_(SETTLE)

    def place_particles_by_clicking(ctx):
        use_window(ctx, "Clouds")
        ctx.item_input_value("Altitude (m)", 900.0)
        before = editor.scene.particle_count
        click_viewport(ctx, 0.5, 0.35)
        click_viewport(ctx, 0.6, 0.3)
        CHECK(editor.scene.particle_count == before + 2)
        use_window(ctx, "Scene")
        ctx.item_click("Undo")
        CHECK(editor.scene.particle_count == before + 1)
        ctx.item_click("Undo")
        CHECK(editor.scene.particle_count == before)
        ctx.item_click("Redo")
        CHECK(editor.scene.particle_count == before + 1)

    def time_of_day_changes_the_picture(ctx):
        use_window(ctx, "Lighting")
        ctx.item_input_value("Time of day", 12.0)
        ctx.yield_(SETTLE)
        noon = capture(ctx)
        ctx.item_input_value("Time of day", 19.0)
        CHECK(abs(editor.time_of_day - 19.0) < 1e-3)
        ctx.yield_(SETTLE)
        evening = capture(ctx)
        changed = (np.abs(noon.astype(int) - evening.astype(int)).max(axis=2) > 20).mean()
        outcome["time_of_day_changed_fraction"] = float(changed)
        CHECK(bool(changed > 0.3))  # the sky and the clouds both change

    def tolerance_drives_regeneration(ctx):
        use_window(ctx, "LOD")
        ctx.item_input_value("Tolerance (deg)", 5.0)
        use_window(ctx, "Camera")
        ctx.item_input_value("Orbit step (deg)", 0.5)
        ctx.yield_(SETTLE)
        before = viewport.regenerations_total
        ctx.item_click("Orbit left")
        ctx.yield_(SETTLE)
        lenient = viewport.regenerations_total - before
        use_window(ctx, "LOD")
        ctx.item_input_value("Tolerance (deg)", 0.1)
        ctx.yield_(SETTLE)
        before = viewport.regenerations_total
        use_window(ctx, "Camera")
        ctx.item_click("Orbit left")
        ctx.yield_(SETTLE)
        strict = viewport.regenerations_total - before
        outcome["regenerations"] = {"tolerance 5": lenient, "tolerance 0.1": strict}
        CHECK(lenient == 0 and strict > 0)

    def save_and_reopen(ctx):
        target = results_path.with_name("saved_by_gui.toml")
        use_window(ctx, "Scene")
        ctx.item_input_value("File", str(target))
        ctx.item_click("Save as")
        CHECK(target.exists() and not editor.dirty)
        saved = editor.scene
        use_window(ctx, "Lighting")
        ctx.item_input_value("Time of day", 6.0)
        CHECK(editor.dirty)
        use_window(ctx, "Scene")
        ctx.item_click("Open")
        CHECK(editor.scene == saved and not editor.dirty)

    def malformed_scene_keeps_the_current_one(ctx):
        bad = results_path.with_name("malformed.toml")
        bad.write_text("[camera]\nposition = [0, 1]\n")
        current = editor.scene
        use_window(ctx, "Scene")
        ctx.item_input_value("File", str(bad))
        ctx.item_click("Open")
        ctx.yield_()
        CHECK(editor.scene is current)
        CHECK(any("could not open" in m and "malformed.toml" in m for m in editor.messages))

    tests = [place_particles_by_clicking, time_of_day_changes_the_picture, tolerance_drives_regeneration,
             save_and_reopen, malformed_scene_keeps_the_current_one]

    def register():
        engine = hello_imgui.get_imgui_test_engine()
        io = te.get_io(engine)
        io.config_run_speed = te.TestRunSpeed.fast
        io.config_log_to_tty = True
        io.config_saved_settings = False
        io.config_watchdog_kill_test = 120.0
        for function in tests:
            test = te.register_test(engine, "editor", function.__name__)
            test.test_func = function
            registered.append((function.__name__, test))
        te.queue_tests(engine, te.TestGroup.tests)

    def finish_when_done():
        if outcome.get("done") or not registered:
            return
        engine = hello_imgui.get_imgui_test_engine()
        pending = (te.TestStatus.queued, te.TestStatus.running, te.TestStatus.unknown)
        if not te.is_test_queue_empty(engine) or any(t.output.status in pending for _, t in registered):
            return
        statuses = {name: t.output.status.name for name, t in registered}
        outcome.update(done=True, exit_code=0 if all(s == "success" for s in statuses.values()) else 1)
        report = {"tests": statuses, **{k: v for k, v in outcome.items() if k not in ("done",)},
                  "logs": {name: t.output.log.get_text() for name, t in registered
                           if t.output.status != te.TestStatus.success}}
        results_path.write_text(json.dumps(report, indent=2) + "\n")
        hello_imgui.get_runner_params().app_shall_exit = True

    params.use_imgui_test_engine = True
    params.callbacks.register_tests = register
    params.callbacks.before_imgui_render = finish_when_done
