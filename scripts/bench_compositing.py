"""Full 3D's splats composited by the raster against the compute pass (`compositing`), side by side (JSON).

    python scripts/bench_compositing.py [--sizes 640x480,1600x1200] [--repeat 4] [--json out/bench_compositing.json]

The default scene's view and two views along its flythrough, inside the first cloud (9 s) and past it
(20 s), in full 3D with the GPU's order, each way rendered `--repeat` times in turn; the cloud pass's
median GPU time (`FrameStats.cloud_gpu_ms`, the first frame of each way left out: its programs are built
then) and the compute picture against the raster's (`cloudcore.measure.imagecompare`).  On llvmpipe
"auto" keeps the raster untried; this says by how much, and on a GPU what the trial would find.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

from cloudcore.gl import FrameRenderer  # noqa: E402  (the GL imports need the platform)
from cloudcore.measure.benchmark import machine, write_report  # noqa: E402
from cloudcore.measure.imagecompare import compare  # noqa: E402
from cloudcore.paths import sample  # noqa: E402
from cloudcore.resources import DEFAULT_SCENE  # noqa: E402
from cloudcore.scene import Camera  # noqa: E402
from cloudcore.scenefile import load_scene  # noqa: E402
from cloudcore.settings import RenderSettings  # noqa: E402

WAYS = ("raster", "compute")


def views(scene) -> dict[str, Camera | None]:
    keys = scene.camera_path("flythrough").keys
    along = {f"flythrough {t:g} s": sample(keys, t) for t in (9.0, 20.0)}
    return {"default view": None} | {name: Camera(tuple(at[:3]), tuple(at[3:]), 60.0) for name, at in along.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="640x480,1600x1200")
    parser.add_argument("--repeat", type=int, default=4)
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    scene = load_scene(DEFAULT_SCENE)
    rows = []
    for size in args.sizes.split(","):
        width, height = (int(n) for n in size.split("x"))
        renderer = FrameRenderer(width, height)
        try:
            for name, camera in views(scene).items():
                times, images = {way: [] for way in WAYS}, {}
                for _ in range(args.repeat + 1):
                    for way in WAYS:
                        settings = RenderSettings(mode="full", splat_order="gpu", compositing=way)
                        images[way], stats = renderer.render(scene, camera=camera, settings=settings)
                        assert stats.compositing == way, f"{way} was not used: {stats.compositing!r}"
                        times[way].append(stats.cloud_gpu_ms)
                raster, compute = (float(np.median(times[way][1:])) for way in WAYS)
                difference = compare(images["raster"], images["compute"])
                rows.append(
                    {
                        "view": name,
                        "size": size,
                        "raster_cloud_ms": raster,
                        "compute_cloud_ms": compute,
                        "compute_over_raster": compute / raster,
                        "psnr_db": difference.psnr_db,
                        "max_abs": difference.max_abs,
                    }
                )
        finally:
            renderer.close()
    report = {"machine": machine(), "date": time.strftime("%Y-%m-%d"), "repeat": args.repeat, "rows": rows}
    write_report(report, args.json, summary=rows)


if __name__ == "__main__":
    main()
