"""The editor's frame times: the window at a size (default 1280x720) on a scene, auto mode, camera still. JSON out.

    python scripts/bench_editor.py [cloudcore/resources/scenes/valley.toml] [--size 1280x720] [--frames 150]
                                   [--warm-up 10] [--json out/bench_editor.json]
    python scripts/bench_editor.py [SCENE] [--size 1280x720] --idle 10 [--json out/bench_editor_idle.json]

Runs the real editor (`python -m app SCENE --frames N --frame-stats ...`), under
`xvfb-run` when there is no display, and summarises its per-frame statistics
after the warm-up frames (the first shades every cloud): the time between
window frames (what the user feels: render, GUI and swap), the viewport's share
(the engine's frame and its display copy) and the engine's passes, each as
mean, median and 95th percentile in milliseconds.

With `--idle SECONDS` it runs the editor as an artist does (no frame count), leaves it untouched past its warm-up
(`--idle-warm-up`, 8 s: shading, impostors, then hello_imgui's 3 s of full speed after the last input) and
reports the cores its process kept busy over SECONDS more (Linux's /proc), under its own Xvfb without a display.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from cloudcore.measure.benchmark import machine, write_report
from cloudcore.resources import DEFAULT_SCENE

ROOT = Path(__file__).resolve().parents[1]
_TIMES = ("window_frame_ms", "viewport_ms", "frame_ms", "cloud_ms", "world_ms", "impostor_update_ms")


def run_editor(scene: Path, size: str, frames: int, stats_file: Path, home: Path) -> None:
    command = [
        sys.executable,
        "-m",
        "app",
        str(scene),
        "--window-size",
        size,
        "--frames",
        str(frames),
        "--frame-stats",
        str(stats_file),
    ]
    if not os.environ.get("DISPLAY"):
        if shutil.which("xvfb-run") is None:
            sys.exit("bench_editor: no display and no xvfb-run (install xvfb)")
        width, height = (int(side) for side in size.split("x"))
        command = ["xvfb-run", "-a", "-s", f"-screen 0 {width + 64}x{height + 64}x24"] + command
    # a private HOME: the benchmark neither reads nor rewrites the user's panel layout
    env = {k: v for k, v in os.environ.items() if k != "PYOPENGL_PLATFORM"} | {"HOME": str(home)}
    subprocess.run(command, check=True, cwd=ROOT, env=env)


def idle_cores(scene: Path, size: str, warm_up_s: float, seconds: float, home: Path) -> float:
    """The CPU time the editor's process took over `seconds` of wall time, left alone after `warm_up_s`."""
    env = {k: v for k, v in os.environ.items() if k != "PYOPENGL_PLATFORM"} | {"HOME": str(home)}
    server = None
    if not os.environ.get("DISPLAY"):
        if shutil.which("Xvfb") is None:
            sys.exit("bench_editor: no display and no Xvfb (install xvfb)")
        width, height = (int(side) for side in size.split("x"))
        read, write = os.pipe()
        server = subprocess.Popen(
            ["Xvfb", "-displayfd", str(write), "-screen", "0", f"{width + 64}x{height + 64}x24"], pass_fds=(write,)
        )
        os.close(write)
        with os.fdopen(read) as display:
            env["DISPLAY"] = f":{display.readline().strip()}"
    command = [sys.executable, "-m", "app", str(scene), "--window-size", size]
    editor = subprocess.Popen(command, cwd=ROOT, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        time.sleep(warm_up_s)
        before, started = _cpu_seconds(editor.pid), time.perf_counter()
        time.sleep(seconds)
        return (_cpu_seconds(editor.pid) - before) / (time.perf_counter() - started)
    finally:
        editor.terminate()
        editor.wait(timeout=30)
        if server is not None:
            server.terminate()
            server.wait(timeout=30)


def _cpu_seconds(pid: int) -> float:
    """User and system time of process `pid` and its threads (llvmpipe's among them), in seconds."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def summarise(frames: list[dict], warm_up: int) -> dict:
    measured = frames[warm_up:]
    if not measured:
        raise SystemExit(f"bench_editor: only {len(frames)} frames recorded, none after {warm_up} warm-up frames")
    summary = {
        "frames": len(measured),
        "viewport": [measured[-1]["viewport_width"], measured[-1]["viewport_height"]],
        "particles_drawn_mean": float(np.mean([f["particles_drawn"] for f in measured])),
    }
    for key in _TIMES:
        values = np.array([f[key] for f in measured], dtype=np.float64)
        summary[key] = {
            "mean": float(values.mean()),
            "median": float(np.median(values)),
            "p95": float(np.percentile(values, 95)),
        }
    summary["fps_mean"] = 1e3 / summary["window_frame_ms"]["mean"]
    return summary


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="?", type=Path, default=DEFAULT_SCENE)
    parser.add_argument("--size", default="1280x720", help="the window, WIDTHxHEIGHT (default 1280x720)")
    parser.add_argument("--frames", type=int, default=150)
    parser.add_argument("--warm-up", type=int, default=10, help="first frames left out (default 10)")
    parser.add_argument("--json", type=Path, help="write the results here as well as to stdout")
    parser.add_argument("--idle", type=float, metavar="SECONDS", help="the cores an untouched editor keeps busy")
    parser.add_argument("--idle-warm-up", type=float, default=8.0, metavar="SECONDS")
    args = parser.parse_args()
    if args.idle is not None:
        with tempfile.TemporaryDirectory(prefix="bench-editor-") as folder:
            cores = idle_cores(args.scene.resolve(), args.size, args.idle_warm_up, args.idle, Path(folder))
        report = {"scene": str(args.scene), "window": args.size, "machine": machine(), "cpus": os.cpu_count()}
        write_report(report | {"idle_seconds": args.idle, "idle_cores_busy": cores}, args.json)
        return
    with tempfile.TemporaryDirectory(prefix="bench-editor-") as folder:
        stats_file = Path(folder) / "frames.json"
        run_editor(args.scene.resolve(), args.size, args.frames, stats_file, Path(folder))
        frames = json.loads(stats_file.read_text())
    report = {
        "scene": str(args.scene),
        "window": args.size,
        "mode": "auto",
        "machine": machine(),
        "cpus": os.cpu_count(),
        **summarise(frames, args.warm_up),
    }
    write_report(report, args.json)


if __name__ == "__main__":
    main()
