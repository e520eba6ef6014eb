"""Yusov's precomputed particle lighting against Harris's, side by side on one scene: JSON out.

    PYOPENGL_PLATFORM=egl .venv/bin/python scripts/bench_precomputed_lighting.py \\
        --json out/bench_precomputed_lighting.json

1. The reference particle's tables (`cloudcore.light.precomputed`): built into an empty cache folder
   (a temporary one), their size, and read back from that cache.
2. The light pass, per active light: Harris's exact method and Yusov's occlusion estimate, alternated
   (best of --repeat each), and the estimate's difference from exact (mean and max absolute, in the
   fraction of light arriving).
3. The eye pass's numpy reference (`ParticleBuffer.seen_from`, every particle from the scene's camera):
   Harris's and Yusov's, alternated.
4. Whole frames on the GL side (full 3D, the scene's camera, --width x --height), one renderer per eye
   pass so that neither re-uploads, frames alternated: the median frame and cloud-pass times.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import platform
import tempfile
import time
from pathlib import Path

import numpy as np

from cloudcore.light import precomputed
from cloudcore.light.illumination import illuminate_clouds
from cloudcore.light.lighting import active_lights, scene_lights
from cloudcore.measure.benchmark import machine, write_report
from cloudcore.particles.buffer import ParticleBuffer
from cloudcore.resources import DEFAULT_SCENE
from cloudcore.scenes.files import load_scene

EYE_PASSES = ("harris", "yusov")
LIGHT_METHODS = ("exact", "occlusion")


def table_costs(phase: str, g: float) -> dict:
    """Build the tables into an empty cache, then read them back from it."""
    held = os.environ.get("XDG_CACHE_HOME")
    with tempfile.TemporaryDirectory() as folder:
        os.environ["XDG_CACHE_HOME"] = folder
        try:
            precomputed._held.clear()
            built = precomputed.reference_tables(phase, g)
            precomputed._held.clear()
            start = time.perf_counter()
            loaded = precomputed.reference_tables(phase, g)
            load_s = time.perf_counter() - start
            files = list(Path(folder).rglob("*.npz"))
            file_bytes = sum(f.stat().st_size for f in files)
        finally:
            if held is None:
                os.environ.pop("XDG_CACHE_HOME", None)
            else:
                os.environ["XDG_CACHE_HOME"] = held
    assert loaded.cached and not built.cached
    return {"build_s": built.build_s, "load_s": load_s, "bytes": built.nbytes, "cache_file_bytes": file_bytes}


def light_pass(scene, repeat: int) -> list[dict]:
    lights, _ = scene_lights(scene.lighting)
    rows = []
    for index, light in enumerate(active_lights(lights)):
        best = dict.fromkeys(LIGHT_METHODS, np.inf)
        results = {}
        for _ in range(repeat):
            for method in LIGHT_METHODS:
                start = time.perf_counter()
                results[method] = np.concatenate(illuminate_clouds(scene.clouds, scene.shading, (light,), method))
                best[method] = min(best[method], time.perf_counter() - start)
        difference = np.abs(results["occlusion"] - results["exact"])
        rows.append(
            {
                "light": index,
                "particles": len(difference),
                "exact_s": best["exact"],
                "occlusion_s": best["occlusion"],
                "occlusion_over_exact": best["occlusion"] / best["exact"],
                "mean_incident": {m: float(r.mean()) for m, r in results.items()},
                "occlusion_mean_abs_difference": float(difference.mean()),
                "occlusion_max_abs_difference": float(difference.max(initial=0.0)),
            }
        )
    return rows


def eye_pass_reference(scene, repeat: int) -> dict:
    lights, ambient = scene_lights(scene.lighting)
    buffers = {
        eye_pass: ParticleBuffer(scene.clouds, dataclasses.replace(scene.shading, eye_pass=eye_pass), lights, ambient)
        for eye_pass in EYE_PASSES
    }
    indices = np.arange(len(buffers["harris"].radii))
    best = dict.fromkeys(EYE_PASSES, np.inf)
    for _ in range(repeat):
        for eye_pass, particles in buffers.items():
            start = time.perf_counter()
            particles.seen_from(scene.camera.position, indices)
            best[eye_pass] = min(best[eye_pass], time.perf_counter() - start)
    return {
        "particles": len(indices),
        **{f"{eye_pass}_s": seconds for eye_pass, seconds in best.items()},
        **{f"{eye_pass}_us_per_particle": 1e6 * s / max(len(indices), 1) for eye_pass, s in best.items()},
        "yusov_over_harris": best["yusov"] / best["harris"],
    }


def gl_frames(scene, width: int, height: int, frames: int) -> dict:
    from cloudcore.gl import FrameRenderer
    from cloudcore.model.settings import FULL_3D

    renderers = {eye_pass: FrameRenderer(width, height) for eye_pass in EYE_PASSES}
    scenes = {e: dataclasses.replace(scene, shading=dataclasses.replace(scene.shading, eye_pass=e)) for e in EYE_PASSES}
    times = {e: {"frame_ms": [], "cloud_ms": []} for e in EYE_PASSES}
    try:
        for frame in range(frames + 1):
            for eye_pass, renderer in renderers.items():
                _, stats = renderer.render(scenes[eye_pass], settings=FULL_3D, read_back=False)
                if frame:  # the first frame uploads the particles
                    times[eye_pass]["frame_ms"].append(stats.frame_ms)
                    times[eye_pass]["cloud_ms"].append(stats.cloud_ms)
    finally:
        for renderer in renderers.values():
            renderer.close()
    medians = {e: {k: float(np.median(v)) for k, v in t.items()} for e, t in times.items()}
    return {
        "width": width,
        "height": height,
        "frames": frames,
        **medians,
        "yusov_over_harris_frame": medians["yusov"]["frame_ms"] / medians["harris"]["frame_ms"],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="?", default=str(DEFAULT_SCENE))
    parser.add_argument("--json", type=Path, help="write the results here as well as to stdout")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--frames", type=int, default=5)
    parser.add_argument("--width", type=int, default=320)
    parser.add_argument("--height", type=int, default=240)
    args = parser.parse_args()

    scene = load_scene(args.scene)
    report = {
        "scene": args.scene,
        "machine": machine(),
        "python": platform.python_version(),
        "particles": scene.particle_count,
        "tables": table_costs(scene.shading.phase, scene.shading.g),
        "light_pass": light_pass(scene, args.repeat),
        "eye_pass_reference": eye_pass_reference(scene, args.repeat),
        "gl_frames": gl_frames(scene, args.width, args.height, args.frames),
    }
    write_report(report, args.json)


if __name__ == "__main__":
    main()
