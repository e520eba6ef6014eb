"""The editor's window: hello_imgui with a docking layout, the viewport and the panels.

    python -m app [SCENE] [--window-size WIDTHxHEIGHT] [--self-test RESULTS.json [--tests NAME,...]]
    python -m app [SCENE] --frames N [--screenshot PNG] [--window-screenshot PNG] [--frame-stats JSON]

The docking layout is remembered between runs (hello_imgui's settings file in
the user's config folder).  With --self-test the Dear ImGui Test Engine drives
the real widgets (the GUI tests of a source checkout, `tests/gui/editor_tests.py`),
writes its results and exits 0 when every test passed, 1 otherwise.  With --frames the editor quits after N frames,
optionally leaving the viewport's last picture at its own size (what
`cloudview render` of the same view gives: `tests/gui/test_editor_matches_render.py`),
a screenshot of the whole window, and the per-frame statistics with the time
between window frames (`scripts/bench_editor.py` summarises them).

Keys: Ctrl+S saves, Ctrl+Z / Ctrl+Y (or Ctrl+Shift+Z) undo and redo, Delete
removes the picked particle or else the selected cloud, F3 (or Ctrl+T) shows
or hides the statistics.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import sys
import time
from pathlib import Path

# the window's GLX context needs PyOpenGL's default platform, not the headless EGL one
if os.environ.get("PYOPENGL_PLATFORM") == "egl":
    del os.environ["PYOPENGL_PLATFORM"]

from imgui_bundle import hello_imgui, imgui, immapp  # noqa: E402

from app.editor import Editor  # noqa: E402
from app.panels import Panels  # noqa: E402
from app.panels.widgets import labels_in_full  # noqa: E402
from app.viewport import Viewport  # noqa: E402
from cloudcore.model.errors import SceneError  # noqa: E402
from cloudcore.resources import DEFAULT_SCENE  # noqa: E402
from cloudcore.runtime.collector import freeze_what_is_set_up  # noqa: E402

#: the GUI tests --self-test runs: a test suite, so it lives with the tests, not in the product
GUI_TESTS = Path(__file__).resolve().parents[1] / "tests" / "gui" / "editor_tests.py"


def runner_params(
    editor: Editor,
    viewport: Viewport,
    panels: Panels,
    testing: bool,
    window_size: tuple[int, int] = (1280, 800),
    scripted: bool = False,
) -> hello_imgui.RunnerParams:
    """The editor's window, panels and per-frame work; `testing`: GUI tests drive it, `scripted`: it quits after
    a count of frames (neither waits for input between frames)."""
    params = hello_imgui.RunnerParams()
    params.app_window_params.window_title = "cloudview"
    params.app_window_params.window_geometry.size = window_size
    params.imgui_window_params.default_imgui_window_type = (
        hello_imgui.DefaultImGuiWindowType.provide_full_screen_dock_space
    )
    params.imgui_window_params.show_menu_bar = False
    # a CPU rasteriser pays for every multisample; the splats are smooth already
    options = hello_imgui.OpenGlOptions()
    options.anti_aliasing_samples = 0
    params.renderer_backend_options.open_gl_options = options
    # hello_imgui's idling, switched on and off each frame (below)
    params.fps_idling.enable_idling = False
    params.ini_folder_type = hello_imgui.IniFolderType.app_user_config_folder
    params.ini_filename = "cloudview/layout.ini"
    params.ini_disable = testing  # tests start from the code's layout and leave no file behind

    left = hello_imgui.DockingSplit("MainDockSpace", "Left", imgui.Dir.left, 0.3)
    bottom = hello_imgui.DockingSplit("Left", "LeftBottom", imgui.Dir.down, 0.45)
    params.docking_params.docking_splits = [left, bottom]
    windows = [hello_imgui.DockableWindow("Viewport", "MainDockSpace", viewport.gui)]
    for label, dock, function in panels.windows():
        windows.append(hello_imgui.DockableWindow(label, dock, with_labels_in_full(function)))
    params.docking_params.dockable_windows = windows

    frames = 0

    def every_frame():
        nonlocal frames
        frames += 1
        if frames == 3:  # the viewport's renderer made and drawn: its setup out of the collector's full passes
            freeze_what_is_set_up()
        shortcuts(editor)
        panels.poll_recording()
        editor.autosave()
        # at rest (the last frame showed the same picture again, no path playing) the window waits for input, up
        # to a ninth of a second, between frames, instead of drawing them as fast as it can: an idle editor took
        # a whole core on llvmpipe.  Input, an edit, playing or a relit picture drawing wakes it at once
        hello_imgui.get_runner_params().fps_idling.enable_idling = not (testing or scripted) and viewport.at_rest

    def before_exit():
        panels.close()
        viewport.close()

    params.callbacks.pre_new_frame = every_frame
    params.callbacks.before_exit = before_exit
    return params


def with_labels_in_full(draw):
    """A panel's `draw`, its widgets leaving their labels room (`labels_in_full`)."""

    def drawn() -> None:
        with labels_in_full():
            draw()

    return drawn


def shortcuts(editor: Editor) -> None:
    io = imgui.get_io()
    if io.key_ctrl and imgui.is_key_pressed(imgui.Key.s):
        editor.save()
    if io.key_ctrl and imgui.is_key_pressed(imgui.Key.z):
        editor.redo() if io.key_shift else editor.undo()
    if io.key_ctrl and imgui.is_key_pressed(imgui.Key.y):
        editor.redo()
    # Delete in a text field edits the text; held down it must not delete one thing after another
    if not io.want_text_input and imgui.is_key_pressed(imgui.Key.delete, repeat=False):
        editor.delete_selection()
    if imgui.is_key_pressed(imgui.Key.f3, repeat=False) or (
        io.key_ctrl and imgui.is_key_pressed(imgui.Key.t, repeat=False)
    ):
        statistics = hello_imgui.get_runner_params().docking_params.dockable_window_of_name("Statistics")
        statistics.is_visible = not statistics.is_visible


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="cloudview", description="the cloudview editor")
    parser.add_argument("scene", nargs="?", type=Path, default=DEFAULT_SCENE)
    parser.add_argument(
        "--window-size",
        type=window_size,
        default=(1280, 800),
        metavar="WIDTHxHEIGHT",
        help="the window's size in pixels (default 1280x800)",
    )
    parser.add_argument(
        "--self-test",
        type=Path,
        metavar="RESULTS.json",
        help="run the GUI tests with the Dear ImGui Test Engine, write results, exit",
    )
    parser.add_argument("--tests", metavar="NAME,...", help="with --self-test: run only these GUI tests")
    parser.add_argument("--frames", type=int, help="quit after this many frames")
    parser.add_argument(
        "--screenshot",
        type=Path,
        help="with --frames: save the viewport's last picture here (PNG, the viewport's size)",
    )
    parser.add_argument(
        "--window-screenshot", type=Path, help="with --frames: save the whole window here (PNG) at the end"
    )
    parser.add_argument("--frame-stats", type=Path, help="with --frames: write every frame's statistics (JSON)")
    args = parser.parse_args(argv)
    if args.self_test is not None and not GUI_TESTS.is_file():
        print(
            f"cloudview: error: --self-test: no GUI tests at {GUI_TESTS} (they come with a source checkout)",
            file=sys.stderr,
        )
        return 2
    try:
        editor = Editor.open(args.scene)
    except SceneError as error:
        print(f"cloudview: error: {error}", file=sys.stderr)
        return 2
    viewport = Viewport(editor, remember_costs=args.self_test is None and args.frames is None)
    panels = Panels(editor, viewport)
    params = runner_params(
        editor,
        viewport,
        panels,
        testing=args.self_test is not None,
        window_size=args.window_size,
        scripted=args.frames is not None,
    )
    outcome = {}
    if args.self_test is not None:
        gui_tests = _imported(GUI_TESTS)
        gui_tests.install(
            params,
            gui_tests.EditorUnderTest(editor, viewport, panels, args.self_test, outcome),
            only=None if args.tests is None else args.tests.split(","),
        )
    if args.frames is not None:
        _quit_after(params, args.frames, editor, viewport, outcome)
    immapp.run(params, immapp.AddOnsParams(with_implot=True))
    if args.screenshot is not None or args.window_screenshot is not None:
        import imageio.v3 as iio

        if args.screenshot is not None and viewport.captured is not None:
            iio.imwrite(args.screenshot, viewport.captured)
        if args.window_screenshot is not None:
            iio.imwrite(args.window_screenshot, hello_imgui.final_app_window_screenshot())
    if args.frame_stats is not None:
        args.frame_stats.write_text(json.dumps(outcome.get("frames", []), indent=1) + "\n")
    return outcome.get("exit_code", 0)


def _imported(path: Path):
    """The module of a file outside the package (the GUI tests), imported under its own name."""
    spec = importlib.util.spec_from_file_location(path.stem, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[path.stem] = module
    spec.loader.exec_module(module)
    return module


def window_size(text: str) -> tuple[int, int]:
    """WIDTHxHEIGHT, both >= 1; argparse names this function in its refusal."""
    width, height = (int(side) for side in text.lower().split("x"))
    if width < 1 or height < 1:
        raise ValueError(text)
    return width, height


def _quit_after(params, frames: int, editor: Editor, viewport: Viewport, outcome: dict) -> None:
    """Quit after `frames` viewport frames, each recorded with the time since the window's previous frame;
    the last one's picture is kept (`Viewport.captured`)."""
    recorded = outcome.setdefault("frames", [])
    previous = {"stats": None, "time": time.perf_counter()}

    def count():
        now = time.perf_counter()
        if editor.last_stats is not None and editor.last_stats is not previous["stats"]:
            recorded.append(editor.last_stats.as_dict() | {"window_frame_ms": 1e3 * (now - previous["time"])})
        previous.update(stats=editor.last_stats, time=now)
        if len(recorded) == frames - 1:
            viewport.capture_next = True
        if len(recorded) >= frames:
            hello_imgui.get_runner_params().app_shall_exit = True

    params.callbacks.before_imgui_render = count
