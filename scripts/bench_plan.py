"""The frame planner's own time, replayed without drawing, per mode and case (JSON); and whether a change plans alike.

    python scripts/bench_plan.py [--cases flythrough,harris_circle_12800] [--frames 300] [--against REV]
                                 [--cpu-time] [--json out/bench_plan.json]

Each case of the benchmark suite `lod` (`cloudview bench --suite lod`; Harris's figure 8 among them:
`harris_circle_N`, `harris_through_N`, `harris` for all) is planned frame by frame in a closed loop, as
`cloudcore.gl.FrameRenderer` plans it but with nothing drawn: the units of the scene's clouds (and of its
cloud field for the eye), the objects' poses, the clouds' lighting keys, the state each plan leaves fed into
the next, and the frame's measured times replaced by the plan's own prediction, the cloud pass's 10% dearer
(so the cost fit and auto mode's choice by measured frame times move as they do on a real run, and the same
inputs give the same plans anywhere).  The frames after the case's warm-up are timed in `PASSES` passes.

`--against REV` runs this very script again over `cloudcore` of git revision REV (a worktree in a temporary
directory, on PYTHONPATH) in a child process after this one's cases, the cases' scenes and views made here and
handed to it pickled (so a revision from before the suite replays the same ones), and counts the frames whose plans
differ in any field the GL side reads or the statistics report (`plans_differing`: 0 for a change meant only to be
faster); the first difference of each case is printed.  REV must have the plan's package and
`cloud_extents` and the engine's packages (`cloudcore.model`, `cloudcore.world`: the pickled scenes name their
modules; from revision ebde165 on); the planner before them is measured in docs/performance.md,
"The plan at Harris's scale".  Reports the median and the least of each way's passes, in ms a frame.  The
units' geometry is `ParticleBuffer`'s (`cloud_extents`), without its light.
"""

from __future__ import annotations

import argparse
import base64
import dataclasses
import json
import math
import os
import pickle
import re
import subprocess
import sys
import tempfile
import time
import zlib
from pathlib import Path
from types import SimpleNamespace

import numpy as np

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

from cloudcore.artist.formation import formation_state  # noqa: E402
from cloudcore.artist.particle_styles import particle_styles  # noqa: E402
from cloudcore.field.state import FieldState, update_field  # noqa: E402
from cloudcore.lod.plan import LodState, plan_frame  # noqa: E402
from cloudcore.lod.units import lod_units  # noqa: E402
from cloudcore.world.objects import object_poses  # noqa: E402

try:
    from cloudcore.particles.buffer import cloud_extents  # noqa: E402
except ImportError:  # a revision before the particles' package (issue 55), replayed by --against: the light's
    from cloudcore.light.eye_scattering import cloud_extents  # noqa: E402
from cloudcore.model.scene import Lighting  # noqa: E402
from cloudcore.model.settings import RenderSettings  # noqa: E402

MODES = ("full", "impostor", "auto")
PASSES = 5


def particles_of(clouds) -> SimpleNamespace:
    """What `lod_units` and the plan read of a `ParticleBuffer`, without its light (nothing is drawn)."""
    counts = np.array([len(c.particles) for c in clouds], dtype=np.int64)
    centres = np.concatenate([c.centres for c in clouds]).reshape(-1, 3) if clouds else np.zeros((0, 3))
    radii = np.concatenate([c.radii for c in clouds]) if clouds else np.zeros(0)
    starts = np.concatenate([[0], np.cumsum(counts)])
    styles = particle_styles(clouds, Lighting())
    finest, bounding_centres, bounding_radii = cloud_extents(clouds, radii, starts, styles)
    return SimpleNamespace(
        styles=styles,
        cloud_starts=starts,
        centres=centres,
        radii=radii,
        finest_radii=finest,
        bounding_centres=bounding_centres,
        bounding_radii=bounding_radii,
    )


def planned_frames(scene, views, size, mode: str):
    """Yield (plan, the call's arguments) of every frame of `views` planned in a closed loop in `mode`."""
    settings = RenderSettings(mode=mode)
    state, field_state, units_source = LodState(), FieldState(), None
    spheres, serial_of, last_keys = None, {}, None
    for time_s, camera in views:
        clouds, fades = scene.clouds, (1.0,) * len(scene.clouds)
        if scene.cloud_field is not None:
            frame, field_state = update_field(scene.cloud_field, camera.position, field_state)
            clouds, fades = clouds + frame.clouds, fades + frame.fade_keys
        if (clouds, settings.group_clouds) != units_source:
            particles = particles_of(clouds)
            units = lod_units(particles, settings.group_clouds, len(scene.clouds))
            units_source = (clouds, settings.group_clouds)
            spheres = None
        # a serial per cloud in the order first seen, as the renderer's lighting keys (an id differs run to run;
        # the cloud is held so that its id is not reused)
        serials = [serial_of.setdefault(id(cloud), (len(serial_of), cloud))[0] for cloud in clouds]
        keys = tuple((s, formation_state(c.formation, time_s), fade) for s, c, fade in zip(serials, clouds, fades))
        keys = last_keys if keys == last_keys else keys  # the renderer's keys are the same tuple while unchanged
        last_keys = keys
        if spheres is None and scene.objects:
            from cloudcore.world.objects import mesh_sphere, object_mesh

            spheres = [mesh_sphere(object_mesh(o)) for o in scene.objects]
        poses = object_poses(scene.objects, time_s, spheres) if scene.objects else ()
        arguments = (units, camera, size, settings, state, keys, poses)
        keywords = {
            "cloud_particles": lambda c, p=particles: p.centres[p.cloud_starts[c] : p.cloud_starts[c + 1]],
            "cloud_splats": lambda c, p=particles: (
                p.centres[p.cloud_starts[c] : p.cloud_starts[c + 1]],
                p.radii[p.cloud_starts[c] : p.cloud_starts[c + 1]],
            ),
        }
        plan = plan_frame(*arguments, **keywords)
        yield plan, (arguments, keywords)
        model = plan.costs
        state = plan.state.measured(
            [(plan.update_work, model.ms(plan.update_work)), (plan.cloud_work, 1.1 * model.ms(plan.cloud_work))],
            fit=plan.priced,
        )


#: how far apart two numbers of plans alike may be, relatively: a change meant only to be faster may round
#: differently in the last bits (a closed form in place of a difference of products), and the frames it plans after
#: (the cost fit reads the plan's predictions) carry that on
PLAN_TOLERANCE = 1e-9
NUMBER = re.compile(r"((?<![\w.])-?\d+(?:\.\d*)?(?:e[-+]?\d+)?)")


def canonical(plan) -> str:
    """What of a plan the GL side reads or the statistics report, as text: two plans alike give the same, or
    numbers within `PLAN_TOLERANCE` (`differing_part`)."""
    ring = plan.ring
    ring_text = (
        None
        if ring is None
        else (
            ring.build_segment,
            ring.build_piece,
            ring.build_members,
            [(sorted(g.members), g.segment_members, g.eye, g.texture_size, w) for g, w in ring.draws],
        )
    )
    drawn = [tuple(plan.clouds[i]) for i in plan.draw_order]
    kinds = [(c.index, c.kind, c.members) for c in plan.clouds]
    stats = dataclasses.asdict(plan.stats())
    state = plan.state
    return repr(
        (
            drawn,
            kinds,
            [
                (i.kind, int(i.index), float(i.depth), int(i.layer), float(i.near), float(i.far))
                for i in plan.draw_items
            ],
            ring_text,
            plan.inside_size,
            plan.objects_with_world,
            plan.update_work,
            plan.cloud_work,
            plan.priced,
            plan.tolerance_deg,
            plan.accepted_error,
            sorted(stats.items()),
            sorted(state.records.items()),
            sorted(state.representations.items()),
            (state.frame_choice, state.drawn_as, state.frames_drawn_as, state.frame_index, state.opened),
        )
    )


def replay(chosen, frames: int, clock=time.perf_counter) -> list[dict]:
    """Per case ((name, scene, views, size, warmup), as `cloudcore.cli.bench_suite.built_cases` makes them) and
    mode: the plans' texts frame by frame (`canonical`), and the passes timed by `clock` (seconds)."""
    rows = []
    for name, scene, views, size, warmup in chosen:
        views = views[: warmup + frames]
        for mode in MODES:
            calls, texts = [], []
            for index, (plan, call) in enumerate(planned_frames(scene, views, size, mode)):
                if index >= warmup:
                    calls.append(call)
                    texts.append(canonical(plan))
            times = []
            for _ in range(PASSES):
                start = clock()
                for arguments, keywords in calls:
                    plan_frame(*arguments, **keywords)
                times.append(1e3 * (clock() - start) / max(len(calls), 1))
            rows.append(
                {
                    "case": name,
                    "mode": mode,
                    "clouds": len(scene.clouds),
                    "frames": len(calls),
                    "plan_ms_median": float(np.median(times)),
                    "plan_ms_least": float(np.min(times)),
                    "texts": base64.b64encode(zlib.compress("\n".join(texts).encode())).decode(),
                }
            )
    return rows


def against(revision: str, chosen: list, frames: int, cpu_time: bool = False) -> list[dict]:
    """This script's rows of the cases `chosen` over `cloudcore` at git `revision` (a temporary worktree), in a
    child process (timed in its CPU time where `cpu_time`)."""
    from cloudcore.measure.benchmark import revision_trees

    root = Path(__file__).resolve().parent.parent
    with tempfile.TemporaryDirectory() as folder, revision_trees({"tree": revision}, root) as trees:
        out, cases = Path(folder) / "rows.json", Path(folder) / "cases.pickle"
        cases.write_bytes(pickle.dumps(chosen))
        env = {**os.environ, "PYTHONPATH": str(trees["tree"])}
        subprocess.run(
            [sys.executable, __file__, "--cases-from", str(cases), "--frames", str(frames), "--rows", str(out)]
            + (["--cpu-time"] if cpu_time else []),
            env=env,
            check=True,
        )
        return json.loads(out.read_text())


def _same_part(index: int, ours: str, theirs: str) -> bool:
    """Whether the `index`th parts of two plans' texts split at their numbers (odd: a number) are alike."""
    if index % 2 == 0:
        return ours == theirs
    return math.isclose(float(ours), float(theirs), rel_tol=PLAN_TOLERANCE, abs_tol=1e-300)


def differing_part(ours: str, theirs: str) -> int | None:
    """Where two plans' texts (`canonical`) first differ, as a character offset in `ours`, but for numbers within
    `PLAN_TOLERANCE` of each other (None: alike)."""
    if ours == theirs:
        return None
    our_parts, their_parts = NUMBER.split(ours), NUMBER.split(theirs)
    offset = 0
    for index, (a, b) in enumerate(zip(our_parts, their_parts)):
        if not _same_part(index, a, b):
            return offset
        offset += len(a)
    return None if len(our_parts) == len(their_parts) else offset


def plan_texts(row: dict) -> list[str]:
    """A row's plans' texts, frame by frame."""
    return zlib.decompress(base64.b64decode(row["texts"])).decode().split("\n")


def first_difference(ours: list[str], theirs: list[str]) -> str:
    """Where the first frame two rows' plans differ starts to differ, in their text."""
    for frame, (a, b) in enumerate(zip(ours, theirs)):
        at = differing_part(a, b)
        if at is not None:
            return (
                f"frame {frame}: ...{a[max(0, at - 120) : at + 200]}... against ...{b[max(0, at - 120) : at + 200]}..."
            )
    return ""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", default="flythrough")
    parser.add_argument("--frames", type=int, default=300, help="frames planned per case after its warm-up")
    parser.add_argument("--against", help="a git revision whose cloudcore is replayed beside the working tree's")
    parser.add_argument("--json", type=Path)
    # on a machine other processes load, the wall clock counts their time too: 8-10 times the plan's own at a load
    # of 10-13 on 2 cores (docs/performance.md, "Issue 51's Must show")
    parser.add_argument("--cpu-time", action="store_true", help="time the plans in this process's CPU time")
    parser.add_argument("--rows", type=Path, help=argparse.SUPPRESS)  # the child's rows, for --against
    parser.add_argument("--cases-from", type=Path, help=argparse.SUPPRESS)  # the child's cases, for --against
    args = parser.parse_args()
    if args.cases_from:  # the child of --against: the cases as the parent's tree made them
        chosen = pickle.loads(args.cases_from.read_bytes())
    else:
        from cloudcore.cli.bench_suite import built_cases

        chosen = built_cases("lod", args.cases.split(","))
    rows = replay(chosen, args.frames, time.process_time if args.cpu_time else time.perf_counter)
    if args.rows:
        args.rows.write_text(json.dumps(rows))
        return
    theirs = against(args.against, chosen, args.frames, args.cpu_time) if args.against else []
    report = []
    for row in rows:
        other = next((r for r in theirs if (r["case"], r["mode"]) == (row["case"], row["mode"])), None)
        line = {k: v for k, v in row.items() if k != "texts"}
        if other is not None:
            texts, their_texts = plan_texts(row), plan_texts(other)
            differing = sum(differing_part(a, b) is not None for a, b in zip(texts, their_texts))
            line |= {
                "against": args.against,
                "against_plan_ms_median": other["plan_ms_median"],
                "against_plan_ms_least": other["plan_ms_least"],
                "plans_differing": differing,
            }
            if differing:
                print(f"{row['case']} {row['mode']}: {first_difference(texts, their_texts)}", file=sys.stderr)
        report.append(line)
        print(
            f"{row['case']} {row['mode']:8s} {row['clouds']} clouds: {line['plan_ms_median']:.3f} ms a frame"
            + (
                f" against {line['against_plan_ms_median']:.3f} at {args.against},"
                f" {line['plans_differing']} plans differ"
                if other is not None
                else ""
            ),
            file=sys.stderr,
            flush=True,
        )
    from cloudcore.measure.benchmark import machine, write_report

    write_report({"machine": machine(), "date": time.strftime("%Y-%m-%d"), "rows": report}, args.json, summary=report)


if __name__ == "__main__":
    main()
