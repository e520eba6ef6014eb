"""The editor's preview light pass (a dragged slider's) at several grids and slab thicknesses: its time, its light's
error and its look's picture against the exact look, JSON out.

    python scripts/bench_preview.py [--previews 16,0.05 16,0.1 24,0.1] [--hours 10,12.5,15.5,17.5]
                                    [--size 879x683] [--json out/bench_preview.json]

For each hour and each preview (GRID cells across a cloud, slabs of SLABS median radii: `cloudcore.light.shading`'s
`PREVIEW_RASTER_RESOLUTION` and `PREVIEW_SLAB_FRACTION`), on the default scene: the processor time of the sun's
preview light pass (the part a dragged time of day makes again each look, `cloudcore.light.relighting`), the mean
absolute error of its light against the exact pass's, and the PSNR of the look's picture against the exact look at
the same hour, both in full 3D (no impostor left from another light) after a look at 9:00 (the preview then holds
the clouds' shadows on one another of 9:00, as a drag from there does: `IlluminationCache`).
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import time
from pathlib import Path

import numpy as np

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

from cloudcore.gl.frame import FrameRenderer  # noqa: E402  (after the platform above)
from cloudcore.light import shading  # noqa: E402
from cloudcore.light.illumination import IlluminationCache, illuminate_direction, light_directions  # noqa: E402
from cloudcore.light.lighting import scene_lights  # noqa: E402
from cloudcore.light.relighting import EXACT_METHOD, PREVIEW_METHOD  # noqa: E402
from cloudcore.measure.benchmark import machine, write_report  # noqa: E402
from cloudcore.measure.imagecompare import compare  # noqa: E402
from cloudcore.model.settings import FULL_3D  # noqa: E402
from cloudcore.resources import DEFAULT_SCENE  # noqa: E402
from cloudcore.scenes.files import load_scene  # noqa: E402


def picture(renderer, scene, hours: float, method: str) -> np.ndarray:
    """The full-3D picture of `scene` at `hours` lit by `method` (the second frame: nothing left converging)."""
    return [renderer.render(scene, time_of_day=hours, settings=FULL_3D, illumination_method=method)[0] for _ in "ab"][
        -1
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--previews", nargs="+", default=["16,0.05", "16,0.1", "24,0.1"], metavar="GRID,SLABS")
    parser.add_argument("--hours", default="10,12.5,15.5,17.5")
    parser.add_argument("--size", default="879x683", help="the editor's viewport at 1280x800")
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    previews = [(int(grid), float(slabs)) for grid, slabs in (item.split(",") for item in args.previews)]
    scene = load_scene(DEFAULT_SCENE)
    clouds = list(scene.clouds)
    renderer = FrameRenderer(*(int(v) for v in args.size.split("x")), illumination=IlluminationCache())
    rows = []
    try:
        for hours in (float(h) for h in args.hours.split(",")):
            exact = picture(renderer, scene, hours, EXACT_METHOD)
            sun = light_directions(scene_lights(dataclasses.replace(scene.lighting, time_of_day=hours))[0])[0]
            exact_light = np.concatenate(illuminate_direction(clouds, scene.shading, sun, EXACT_METHOD))[:, 0]
            for grid, slabs in previews:
                shading.PREVIEW_RASTER_RESOLUTION, shading.PREVIEW_SLAB_FRACTION = grid, slabs
                # the look before the drag: the cache then holds no preview light of another grid
                renderer.render(scene, time_of_day=9.0, settings=FULL_3D, read_back=False)
                started = time.process_time()
                light = np.concatenate(illuminate_direction(clouds, scene.shading, sun, PREVIEW_METHOD))[:, 0]
                light_cpu_ms = 1e3 * (time.process_time() - started)
                row = {
                    "hours": hours,
                    "grid": grid,
                    "slabs": slabs,
                    "sun_light_pass_cpu_ms": light_cpu_ms,
                    "light_error_mean": float(np.abs(light - exact_light).mean()),
                    "picture_psnr_db": float(compare(picture(renderer, scene, hours, PREVIEW_METHOD), exact).psnr_db),
                    "load_average": os.getloadavg()[0],
                }
                print(row, flush=True)
                rows.append(row)
    finally:
        renderer.close()
    write_report({"machine": machine(), "size": args.size, "rows": rows}, args.json)


if __name__ == "__main__":
    main()
