"""What leaving the light of turbulent shapes unrelit costs the picture, and what a relight takes (JSON).

    python scripts/wind_relight.py [--json out/wind_relight.json]

The default view at 55 s in full 3D, 320x240, its light made at rest against made at 50 s (`relight_period_s` 600
against 10), for turbulence of 30 and 100 m with one band (a 10 m/s westerly) and with two (6 m/s at the ground to
18 m/s at 3 km veering 250 -> 290 degrees), and what a relight of the default scene takes.
What the wind costs a frame, auto against full 3D, is the suite `wind` (`cloudview bench --suite wind`).
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
from pathlib import Path

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

from cloudcore.gl import FrameRenderer  # noqa: E402
from cloudcore.measure.benchmark import machine, write_report  # noqa: E402
from cloudcore.measure.imagecompare import compare  # noqa: E402
from cloudcore.model.scene import Wind  # noqa: E402
from cloudcore.model.settings import FULL_3D  # noqa: E402
from cloudcore.resources import DEFAULT_SCENE  # noqa: E402
from cloudcore.scenes.files import load_scene  # noqa: E402

#: the winds' bands (altitude m, speed m/s, from degrees): a westerly, and the suite `wind`'s churning bands
ONE_BAND = ((0.0, 10.0, 270.0),)
TWO_BANDS = ((0.0, 6.0, 250.0), (3000.0, 18.0, 290.0))


def relight_error() -> list[dict]:
    """PSNR of the picture lit from the shapes at rest against relit 5 s before, and the ms a
    relight takes (the frame that makes the light again)."""
    scene = load_scene(DEFAULT_SCENE)
    rows = []
    for amplitude in (30.0, 100.0):
        for bands in (ONE_BAND, TWO_BANDS):
            images, relight_ms = {}, 0.0
            for period in (10.0, 600.0):  # relit at 50 s, or the light of the clouds at rest
                wind = Wind(bands=bands, turbulence_m=amplitude, relight_period_s=period)
                with FrameRenderer(320, 240) as renderer:
                    renderer.render(dataclasses.replace(scene, wind=wind), settings=FULL_3D)
                    images[period], stats = renderer.render(
                        dataclasses.replace(scene, wind=wind), settings=FULL_3D, time_s=55.0
                    )
                    relight_ms = stats.illumination_ms if period == 10.0 else relight_ms
            difference = compare(images[600.0], images[10.0])
            rows.append(
                {
                    "turbulence_m": amplitude,
                    "bands": len(bands),
                    "psnr_db": difference.psnr_db,
                    "mean_abs": difference.mean_abs,
                    "relight_ms": relight_ms,
                }
            )
            print(
                f"turbulence {amplitude:.0f} m, {len(bands)} band(s): unrelit against relit "
                f"{difference.psnr_db:.1f} dB (mean {difference.mean_abs:.2f} levels); a relight {relight_ms:.0f} ms",
                flush=True,
            )
    return rows


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", type=Path)
    args = parser.parse_args(argv)
    rows = relight_error()
    write_report({"machine": machine(), "rows": rows}, args.json)
    return 0


if __name__ == "__main__":
    sys.exit(main())
