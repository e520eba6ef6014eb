"""The `cloudview` command: the editor, or a headless tool named by a subcommand.

Headless subcommands never import the GUI; bad input is one line on stderr and
exit status 2.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from cloudcore.errors import SceneError

DEFAULT_SCENE = Path(__file__).resolve().parents[2] / "resources" / "scenes" / "valley.toml"


class _OneLineParser(argparse.ArgumentParser):
    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message} (see --help)\n")


def build_parser() -> tuple[argparse.ArgumentParser, argparse._SubParsersAction]:
    from cloudcore.cli import bench, compare, render, shade

    parser = _OneLineParser(prog="cloudview", description="Real-time volumetric particle clouds.")
    commands = parser.add_subparsers(dest="command", parser_class=_OneLineParser, metavar="COMMAND")
    shade.add_parser(commands)
    render.add_parser(commands)
    compare.add_parser(commands)
    bench.add_parser(commands)
    return parser, commands


def main(argv=None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    parser, commands = build_parser()
    if not argv or (argv[0] not in commands.choices and not argv[0].startswith("-")):
        argv = _main_job(argv)
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 0
    try:
        return int(args.run(args) or 0)
    except SceneError as error:
        print(f"cloudview: error: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("cloudview: interrupted", file=sys.stderr)
        return 130


def _main_job(argv: list[str]) -> list[str]:
    """`cloudview [SCENE]`: the editor once it exists; until then the most complete headless job."""
    scene = Path(argv[0] if argv else DEFAULT_SCENE)
    out = Path("out") / f"{scene.stem}.png"
    print(f"cloudview: the editor is not built yet; rendering {scene} headless to {out} instead.",
          file=sys.stderr)
    return ["render", str(scene), "--out", str(out), *argv[1:]]
