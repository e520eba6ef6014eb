"""The `cloudview` command: the editor, or a headless tool named by a subcommand.

Headless subcommands never import the GUI; bad input is one line on stderr and
exit status 2.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
from importlib import metadata

from cloudcore.model.errors import SceneError


class _OneLineParser(argparse.ArgumentParser):
    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message} (see --help)\n")


def version_line() -> str:
    """`cloudview --version`: ours, then the Python and the libraries that decide whether it runs."""

    def installed(name: str) -> str:
        try:
            return metadata.version(name)
        except metadata.PackageNotFoundError:
            return "not installed"

    libraries = ", ".join(
        f"{name} {installed(name)}" for name in ("pyrender-maintained", "PyOpenGL", "numpy", "imgui-bundle")
    )
    return f"cloudview {installed('cloudview')} (Python {platform.python_version()}; {libraries})"


def build_parser() -> tuple[argparse.ArgumentParser, argparse._SubParsersAction]:
    from cloudcore.cli import bench, check, compare, record, render, shade, truth, vdb_export, vdb_import

    # raw text: the version stays one line however narrow the terminal
    parser = _OneLineParser(
        prog="cloudview",
        description="Real-time volumetric particle clouds.",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=version_line())
    commands = parser.add_subparsers(dest="command", parser_class=_OneLineParser, metavar="COMMAND")
    shade.add_parser(commands)
    render.add_parser(commands)
    compare.add_parser(commands)
    check.add_parser(commands)
    bench.add_parser(commands)
    record.add_parser(commands)
    truth.add_parser(commands)
    vdb_import.add_parser(commands)
    vdb_export.add_parser(commands)
    return parser, commands


def main(argv=None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    parser, commands = build_parser()
    if not argv or (argv[0] not in commands.choices and argv[0] not in ("-h", "--help", "--version")):
        return _editor(argv)
    args = parser.parse_args(argv)
    try:
        _check_frame_memory(args)
        return int(args.run(args) or 0)
    except SceneError as error:
        print(f"cloudview: error: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("cloudview: interrupted", file=sys.stderr)
        return 130


def _check_frame_memory(args) -> None:
    """A command's frame size (`--width` and `--height`, or `--size`) fits in this machine's memory: refused
    before any work, where the kernel killed a frame too large after minutes, without a word."""
    from cloudcore.scenes.limits import frame_memory_problem

    if hasattr(args, "width") and hasattr(args, "height"):
        size = args.width, args.height
    elif isinstance(getattr(args, "size", None), tuple):
        size = args.size
    else:
        return
    problem = frame_memory_problem(*size)
    if problem is not None:
        raise SceneError("--width/--height" if hasattr(args, "width") else "--size", "size", problem)


def _editor(argv: list[str]) -> int:
    """`cloudview [SCENE]`: the editor window (imported only here: headless commands never load the GUI)."""
    if not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        print(
            "cloudview: error: the editor needs a display (none is set); on a headless machine try "
            "`xvfb-run -a cloudview`, or the headless commands: "
            "cloudview render|record|bench|compare|check|truth|import|export --help",
            file=sys.stderr,
        )
        return 2
    from app.main import main as editor_main

    return editor_main(argv)
