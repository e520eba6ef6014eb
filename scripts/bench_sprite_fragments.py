"""What a fragment of an atlas sprite costs against one of a Gaussian kernel splat: the number behind
`cloudcore.lod.costs.SPRITE_FRAGMENT_COST`. JSON out.

    python scripts/bench_sprite_fragments.py [--repeat 20] [--json out/bench_sprite_fragments.json]

A cloud of a few hundred large particles, seeded, fills the screen from 2 to 12 overdraw at each size; it is
drawn in full 3D once as Gaussian splats and once as sprites of Wang's cumulus rows (the same quads: both
rasterise every fragment of a splat's square, the kernel discards outside its disc, the sprite after its texel
fetch), frames taking turns after a warm-up, the cloud pass timed by the renderer.  The ratio of their medians
is the sprite's cost in kernel fragments: the particles' own work is a few hundredths of the pass.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import time
from pathlib import Path

import numpy as np

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

from cloudcore.gl import FrameRenderer  # noqa: E402
from cloudcore.measure.benchmark import machine, write_report  # noqa: E402
from cloudcore.model.cloud_records import SpriteStyle  # noqa: E402  (the GL imports need the platform above)
from cloudcore.model.scene import Camera, Cloud  # noqa: E402
from cloudcore.model.settings import RenderSettings  # noqa: E402
from cloudcore.resources import DEFAULT_SCENE  # noqa: E402
from cloudcore.scenes.files import load_scene  # noqa: E402

SIZES = ((640, 480), (1280, 800))
#: particles, and their radius against their spread: large splats, so the fragments are the pass
PARTICLES, SPREAD_M, RADIUS_M = 300, 120.0, 60.0
WARMUP = 5


def test_cloud(seed: int = 5) -> Cloud:
    rng = np.random.default_rng(seed)
    centres = rng.normal(size=(PARTICLES, 3)) * SPREAD_M + (0.0, 1000.0, 0.0)
    return Cloud("fill", np.column_stack([centres, np.full(PARTICLES, RADIUS_M)]))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=20)
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    valley = load_scene(DEFAULT_SCENE)
    kernel = test_cloud()
    sprites = dataclasses.replace(kernel, sprite=SpriteStyle(rows=(2, 2, 3)))
    camera = Camera(position=(0.0, 1000.0, 900.0), look_at=(0.0, 1000.0, 0.0), fov_y_deg=50.0)
    rows = []
    for width, height in SIZES:
        with FrameRenderer(width, height) as renderer:
            times = {"kernel": [], "sprite": []}
            for frame in range(WARMUP + args.repeat):
                for name, cloud in (("kernel", kernel), ("sprite", sprites)):
                    scene = dataclasses.replace(valley, clouds=(cloud,), objects=())
                    _, stats = renderer.render(
                        scene, camera=camera, settings=RenderSettings(mode="full"), read_back=False
                    )
                    if frame >= WARMUP:
                        times[name].append(stats.cloud_ms)
            overdraw = renderer.measure_overdraw()[1]
        kernel_ms, sprite_ms = (float(np.median(times[name])) for name in ("kernel", "sprite"))
        rows.append(
            {
                "size": f"{width}x{height}",
                "kernel_ms_median": kernel_ms,
                "sprite_ms_median": sprite_ms,
                "sprite_over_kernel": sprite_ms / kernel_ms,
                "overdraw_analytic": overdraw.analytic,
                "kernel_ms": times["kernel"],
                "sprite_ms": times["sprite"],
            }
        )
    report = {"machine": machine(), "date": time.strftime("%Y-%m-%d"), "particles": PARTICLES, "sizes": rows}
    summary = [{k: v for k, v in row.items() if not k.endswith("_ms")} for row in rows]
    write_report(report, args.json, summary=summary)


if __name__ == "__main__":
    main()
