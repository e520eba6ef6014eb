"""`cloudview check SCENE_OR_DIR... --goldens DIR`: screenshot tests of every view of every scene.

Each view (the scene's `[camera]` as `default`, then its `[[views]]`) is
rendered headless and compared with `DIR/<scene>/<view>.png`; one line per
view.  Exit status: 0 when every view passes, 1 when any fails (a missing,
unreadable or wrong-sized golden fails too), 2 on bad input (a scene that
does not load, two scenes of one name, an unwritable folder).  `--update`
writes the goldens whose pixels changed instead, and exits 0.  --workers N (or --cluster) renders the views on
N processes (`cloudcore.cli.workers`), with the same lines and images.
"""

from __future__ import annotations

import os
import shlex
import sys
from contextlib import closing
from pathlib import Path

from cloudcore.cli.compare import decibels
from cloudcore.cli.render import pixel_count
from cloudcore.cli.workers import Job, add_workers_arguments, run_job
from cloudcore.measure.screenshot_check import (
    DEFAULT_MAX_DIFF,
    DEFAULT_MIN_PSNR_DB,
    DEFAULT_SIZE,
    Tolerance,
    check_view,
    golden_path,
    keep_images,
    update_golden,
    write_report,
)
from cloudcore.model.errors import SceneError
from cloudcore.scenes.files import load_scene


def add_parser(commands) -> None:
    parser = commands.add_parser("check", help="screenshot tests: render every view of scenes, compare with goldens")
    parser.add_argument(
        "scenes",
        nargs="+",
        metavar="SCENE_OR_DIR",
        help="scene files (.toml), or folders: every *.toml in them (recovery copies left out)",
    )
    parser.add_argument(
        "--goldens", required=True, type=Path, metavar="DIR", help="golden PNGs: DIR/<scene>/<view>.png"
    )
    parser.add_argument(
        "--update", action="store_true", help="write the goldens instead of failing (only those whose pixels changed)"
    )
    parser.add_argument(
        "--report", type=Path, metavar="DIR", help="write expected, actual and diff images and DIR/index.html here"
    )
    parser.add_argument(
        "--tolerance-psnr",
        type=decibels,
        default=DEFAULT_MIN_PSNR_DB,
        metavar="DB",
        help=f"lowest PSNR that passes, for views that set none (default {DEFAULT_MIN_PSNR_DB:g})",
    )
    parser.add_argument(
        "--max-diff",
        type=levels,
        default=DEFAULT_MAX_DIFF,
        metavar="LEVELS",
        help=f"largest difference of a channel, of 255, for views that set none (default {DEFAULT_MAX_DIFF})",
    )
    parser.add_argument(
        "--size",
        type=frame_size,
        default=DEFAULT_SIZE,
        metavar="WxH",
        help=f"frame size of every view (default {size_text(DEFAULT_SIZE)})",
    )
    add_workers_arguments(parser, "views")
    parser.set_defaults(run=run)


def levels(text: str) -> int:
    """A difference in 8-bit levels; argparse names this function in its refusal."""
    value = int(text)
    if not 0 <= value <= 255:
        raise ValueError(text)
    return value


def frame_size(text: str) -> tuple[int, int]:
    """`320x240` -> (320, 240); argparse names this function in its refusal."""
    width, separator, height = text.lower().partition("x")
    if not separator:
        raise ValueError(text)
    return pixel_count(width), pixel_count(height)


def size_text(size: tuple[int, int]) -> str:
    return f"{size[0]}x{size[1]}"


def scene_files(arguments: list[str]) -> list[tuple[str, Path]]:
    """(scene name, file) of every scene the arguments name, in order; a name is a file's stem, and its goldens'
    folder, so two scenes of one name are refused."""
    files = []
    for argument in arguments:
        path = Path(argument)
        if path.is_dir():
            found = sorted(file for file in path.glob("*.toml") if not file.name.endswith(".recovery.toml"))
            if not found:
                raise SceneError(path, "(folder)", "holds no scene (*.toml)")
            files.extend(found)
        else:
            files.append(path)
    named: dict[str, Path] = {}
    for file in files:
        if file.stem in named and named[file.stem].resolve() != file.resolve():
            raise SceneError(file, "(name)", f"has the name of {named[file.stem]}: their goldens would be one folder")
        named.setdefault(file.stem, file)
    return list(named.items())


def run(args) -> int:
    # every scene is loaded before anything renders: bad input stops the check at once (exit 2)
    files = scene_files(args.scenes)
    scenes = [(name, load_scene(file)) for name, file in files]
    if args.goldens.exists() and not args.goldens.is_dir():
        raise SceneError(args.goldens, "--goldens", "is not a folder")
    default_tolerance = Tolerance(args.tolerance_psnr, args.max_diff)
    update_command = shlex.join(
        ["cloudview", "check", *args.scenes, "--goldens", str(args.goldens), "--size", size_text(args.size), "--update"]
    )
    cases = [(name, scene, view) for name, scene in scenes for view in scene.all_views]
    job = Job(
        "check",
        CheckViews,
        (tuple(file for _, file in files), args.size),
        # (scene, view) by number: a worker reads the scenes from their files
        pieces=[(number, view) for number, (_, scene) in enumerate(scenes) for view in range(len(scene.all_views))],
        unit="view",
        label=lambda index: f"view {cases[index][0]}/{cases[index][2].name}",
        bar={"delay": 1.0, "leave": False, "disable": None, "file": sys.stderr},
    )

    os.environ.setdefault("PYOPENGL_PLATFORM", "egl")  # headless: before OpenGL is first imported
    from tqdm import tqdm

    checks, entries, written = [], [], 0
    with closing(run_job(job, args.workers, args.cluster, args.gpus_per_task)) as renders:
        for (name, _, view), actual in zip(cases, renders):
            golden = golden_path(args.goldens, name, view.name)
            check = check_view(name, view.name, actual, golden, default_tolerance.for_view(view))
            note = ""
            if args.update:
                # compared first, so that the line and the report say what changed
                changed = update_golden(check, actual)
                written += changed
                note = "golden written" if changed else "golden unchanged"
                line = f"{check.label}: {note}" + (f" (was {check.status}: {check.detail})" if changed else "")
            else:
                line = check.line(update_command)
            tqdm.write(line, file=sys.stdout)
            checks.append(check)
            if args.report:
                entries.append(keep_images(args.report, check, actual, note))
    failed = sum(not check.passed for check in checks)
    if args.update:
        print(f"{written} of {len(checks)} goldens changed, in {args.goldens}")
    else:
        print(f"{len(checks)} views: {len(checks) - failed} passed, {failed} failed")
    if args.report:
        print(f"report: {write_report(args.report, entries, 'cloudview check ' + shlex.join(args.scenes))}")
    return 0 if args.update or failed == 0 else 1


class CheckViews:
    """One GL context drawing the views of scenes: a worker of `cloudcore.cli.workers`, called with (scene
    number, view number), giving the view's image."""

    def __init__(self, scene_files: tuple[Path, ...], size: tuple[int, int]):
        from cloudcore.gl.views import ViewRenderer

        self.scenes = [load_scene(file) for file in scene_files]
        self.size = size
        self.renderer = ViewRenderer()

    def __call__(self, piece: tuple[int, int]):
        scene_number, view_number = piece
        scene = self.scenes[scene_number]
        return self.renderer.render(scene, scene.all_views[view_number], self.size)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.renderer.close()
