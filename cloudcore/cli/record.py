"""`cloudview record SCENE --camera-path NAME --out F.mp4`: each frame of a camera path, headless, to H.264 and/or PNGs.

Frame i shows the path at i / fps seconds, the scene clock (the wind, forming clouds, objects on their paths)
at --clock-rate times that from the path's first key (a time-lapse: the clouds move faster than the camera);
--stats writes one CSV row per
frame (`cloudcore.measure.recording.COLUMNS`).  Ctrl-C stops after the frame being
drawn: the video is finished properly, so it plays with the frames so far,
and the exit status is 130.  The same arguments give the same frames.  --workers N (or --cluster) draws runs
of frames on N processes (`cloudcore.cli.workers`): the same frames in full 3D, auto mode's within its own
run-to-run differences (docs/workers.md).
"""

from __future__ import annotations

import argparse
import csv
import itertools
import math
import os
import signal
import sys
from contextlib import ExitStack, closing, contextmanager
from pathlib import Path
from types import SimpleNamespace

from cloudcore.cli.render import add_scene_argument, pixel_count, write_output
from cloudcore.cli.settings_args import add_settings_arguments, settings_from
from cloudcore.cli.workers import Job, add_workers_arguments, run_job, spread
from cloudcore.maths.paths import camera_on_path
from cloudcore.measure.recording import COLUMNS, frame_row, frame_times
from cloudcore.model.errors import SceneError
from cloudcore.runtime.collector import freeze_what_is_set_up
from cloudcore.scenes.files import load_scene


def add_parser(commands) -> None:
    parser = commands.add_parser("record", help="render every frame of a camera path to a video and/or PNGs")
    add_scene_argument(parser)
    parser.add_argument("--camera-path", required=True, help="camera path of the scene to fly")
    parser.add_argument(
        "--out", type=video_path, help="H.264 video to write (.mp4, .mkv, .mov); needs an even width and height"
    )
    parser.add_argument("--frames-dir", type=Path, help="folder to write frame_00000.png, frame_00001.png, ... into")
    parser.add_argument("--stats", type=Path, help="one row of frame statistics per frame (CSV)")
    parser.add_argument("--fps", type=frame_rate, default=30.0, help="frames per second (default 30)")
    parser.add_argument("--frames", type=frame_count, help="record only the first N frames")
    parser.add_argument(
        "--clock-rate",
        type=clock_rate,
        default=1.0,
        help="scene seconds a second of the path: > 1 a time-lapse of the wind and the clouds (default 1)",
    )
    parser.add_argument("--width", type=pixel_count, default=640)
    parser.add_argument("--height", type=pixel_count, default=480)
    parser.add_argument(
        "--no-overdraw",
        action="store_true",
        help="leave the overdraw columns empty (measuring replays each frame's cloud draws)",
    )
    add_workers_arguments(parser, "frames")
    # many frames: impostors pay off
    add_settings_arguments(parser, default_mode="auto")
    parser.set_defaults(run=run)


#: frames of a piece of a recording on workers (`cloudview record --workers`)
FRAMES_PER_PIECE = 8

#: the containers ffmpeg picks by a file's suffix that hold H.264
VIDEO_SUFFIXES = (".mp4", ".m4v", ".mkv", ".mov")


def video_path(text: str) -> Path:
    """A video to write, its suffix a container of H.264: refused with the arguments (ffmpeg guesses the container
    from the suffix, and without one it failed in a traceback, leaving an empty file)."""
    path = Path(text)
    if path.suffix.lower() not in VIDEO_SUFFIXES:
        raise argparse.ArgumentTypeError(f"{text!r} is not a video file name: end it in {', '.join(VIDEO_SUFFIXES)}")
    return path


def frame_rate(text: str) -> float:
    """Frames per second, finite and > 0; argparse names this function in its refusal."""
    value = float(text)
    if not (math.isfinite(value) and value > 0):
        raise ValueError(text)
    return value


def clock_rate(text: str) -> float:
    """Scene seconds a second of the camera path, finite and > 0; argparse names this function in its refusal."""
    return frame_rate(text)


def frame_count(text: str) -> int:
    """A number of frames, >= 1; argparse names this function in its refusal."""
    value = int(text)
    if value < 1:
        raise ValueError(text)
    return value


def run(args) -> int:
    if args.out is None and args.frames_dir is None:
        raise SceneError("record", "output", "give --out FILE.mp4, --frames-dir DIR, or both")
    if args.out is not None and (args.width % 2 or args.height % 2):
        raise SceneError(
            str(args.out), "size", f"H.264 (yuv420p) needs an even width and height, got {args.width}x{args.height}"
        )
    scene = load_scene(args.scene)
    try:
        path = scene.camera_path(args.camera_path)
    except KeyError as error:
        raise SceneError(args.scene, "camera_paths", error.args[0]) from None
    settings = settings_from(args)
    try:
        times = frame_times(path.duration, args.fps, args.frames)
    except ValueError as error:
        raise SceneError(args.scene, f"camera_paths ({args.camera_path})", str(error)) from None

    # headless: EGL must be chosen before OpenGL is first imported
    os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
    import imageio.v3 as iio

    frame_ms = []
    with _stop_on_interrupt() as stop, ExitStack() as outputs:
        # every output is made before the renderer starts, so an unwritable one fails at once
        if args.out:
            write_output(args.out, lambda p: p.open("wb").close())
        if args.frames_dir:
            write_output(args.frames_dir, lambda folder: folder.mkdir(exist_ok=True))
        table = (
            outputs.enter_context(write_output(args.stats, lambda p: p.open("w", newline=""))) if args.stats else None
        )
        rows = csv.DictWriter(table, COLUMNS) if table is not None else None
        if rows is not None:
            rows.writeheader()
        video = outputs.enter_context(_video(args.out, (args.width, args.height), args.fps)) if args.out else None
        # here one frame a piece keeps Ctrl-C and the bar to a frame; a worker draws runs of consecutive frames, so
        # that auto mode's impostors and crossfades carry from frame to frame as they do here, but at a run's start
        run = FRAMES_PER_PIECE if spread(args) else 1
        frames = list(enumerate(times))
        job = Job(
            "record",
            RecordFrames,
            (args.scene, args.camera_path, settings, args.width, args.height, not args.no_overdraw, args.clock_rate),
            pieces=[frames[start : start + run] for start in range(0, len(frames), run)],
            unit="frame",
            label=lambda index: f"frames {index * run}-{min((index + 1) * run, len(frames)) - 1}",
            size=len,
        )
        # closed first (exits run last in, first out): a stop kills the workers still drawing, then the video ends
        runs = outputs.enter_context(closing(run_job(job, args.workers, args.cluster, args.gpus_per_task)))
        for (index, t), (image, stats) in zip(frames, itertools.chain.from_iterable(runs)):
            if video is not None:
                video.send(image)
            if args.frames_dir:
                iio.imwrite(args.frames_dir / f"frame_{index:05d}.png", image)
            if rows is not None:
                rows.writerow(frame_row(index, t, stats))
                table.flush()  # a run cut short, even by a kill, keeps its rows
            frame_ms.append(stats.frame_ms)
            if stop.requested:
                break
    written = ", ".join(str(p) for p in (args.out, args.frames_dir, args.stats) if p)
    summary = (
        f"{len(frame_ms)} frames ({len(frame_ms) / args.fps:.2f} s at {args.fps:g} fps, "
        f"{args.width}x{args.height}) to {written}; frame {sum(frame_ms) / len(frame_ms):.1f} ms mean"
    )
    if stop.requested:
        print(f"cloudview: interrupted: wrote {summary}", file=sys.stderr)
        return 130
    print(f"wrote {summary}")
    return 0


class RecordFrames:
    """One GL context drawing frames of a camera path: a worker of `cloudcore.cli.workers`, called with a run of
    (frame number, seconds along the path), giving (image, frame statistics) of each."""

    def __init__(
        self, scene_file: str, path_name: str, settings, width: int, height: int, overdraw: bool, clock_rate: float
    ):
        from cloudcore.gl import FrameRenderer

        self.scene = load_scene(scene_file)
        self.path = self.scene.camera_path(path_name)
        self.settings, self.overdraw, self.clock_rate = settings, overdraw, clock_rate
        self.renderer = FrameRenderer(width, height, remember_costs=True)
        self.drawn = 0

    def __call__(self, frames: list[tuple[int, float]]) -> list:
        return [self.frame(t) for _, t in frames]

    def frame(self, t: float):
        camera = camera_on_path(self.path, t, self.scene.camera.fov_y_deg)
        image, stats = self.renderer.render(
            self.scene, camera=camera, settings=self.settings, time_s=self.path.keys[0, 0] + self.clock_rate * t
        )
        if self.overdraw:
            stats = stats.with_overdraw(self.renderer.measure_overdraw()[1])
        if self.drawn == 0:  # the renderer set up: out of the collector's full passes (`cloudcore.runtime.collector`)
            freeze_what_is_set_up()
        self.drawn += 1
        return image, stats

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.renderer.close()


@contextmanager
def _stop_on_interrupt():
    """Ctrl-C sets `requested` instead of raising, so the frame being drawn and written finishes whole.

    (A KeyboardInterrupt inside the write to ffmpeg would cut a frame short and
    make imageio-ffmpeg kill the encoder, leaving an unplayable file.)  A second
    Ctrl-C raises as usual.
    """
    stop = SimpleNamespace(requested=False)

    def request(signum, frame):
        stop.requested = True
        signal.signal(signal.SIGINT, previous)

    previous = signal.signal(signal.SIGINT, request)
    try:
        yield stop
    finally:
        signal.signal(signal.SIGINT, previous)


@contextmanager
def _video(path: Path, size: tuple[int, int], fps: float):
    """An imageio-ffmpeg H.264 writer taking (height, width, 3) uint8 frames; closed, the file is complete."""
    import imageio_ffmpeg

    # macro_block_size 2: sizes are even, so imageio-ffmpeg never rescales the frames
    writer = imageio_ffmpeg.write_frames(
        str(path), size, fps=fps, codec="libx264", pix_fmt_out="yuv420p", macro_block_size=2
    )
    writer.send(None)  # starts ffmpeg
    try:
        yield writer
    finally:
        writer.close()  # ffmpeg encodes what it holds and writes the index
