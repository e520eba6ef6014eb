"""`cloudview compare A.png B.png`: PSNR, mean and max difference of two images, and a diff image.

Both images become 8-bit RGB before comparing: grey is repeated into three channels, alpha is
dropped (colour is compared, not coverage), and 16-bit images are reduced to 8 bits by `>> 8`.
Float or other images are refused. Of an animation only the first frame is read.

Exit status: 0 when PSNR >= --tolerance-psnr (identical images always are), 1 when below it,
2 on bad input (missing or unreadable file, not an image, sizes differ).
"""

from __future__ import annotations

import math
from pathlib import Path

from cloudcore.measure.imagecompare import compare, diff_image, load_rgb8
from cloudcore.model.errors import SceneError

DEFAULT_TOLERANCE_DB = 40.0  # the golden render tests' threshold


def add_parser(commands) -> None:
    parser = commands.add_parser("compare", help="compare two images: PSNR, mean and max difference")
    parser.add_argument("a", type=Path, metavar="A.png", help="first image (PNG, 8- or 16-bit)")
    parser.add_argument("b", type=Path, metavar="B.png", help="second image, the same size")
    parser.add_argument(
        "--tolerance-psnr",
        type=decibels,
        default=DEFAULT_TOLERANCE_DB,
        metavar="DB",
        help=f"lowest PSNR that passes (default {DEFAULT_TOLERANCE_DB:g} dB)",
    )
    parser.add_argument(
        "--diff", type=Path, metavar="OUT.png", help="write the amplified per-pixel difference here (red on black)"
    )
    parser.set_defaults(run=run)


def decibels(text: str) -> float:
    """A PSNR threshold; NaN would make every comparison fail, so it is refused."""
    value = float(text)
    if math.isnan(value):
        raise ValueError(text)
    return value


def run(args) -> int:
    a, b = load_rgb8(args.a), load_rgb8(args.b)
    if a.shape != b.shape:
        raise SceneError(args.b, "(size)", f"is {b.shape[1]}x{b.shape[0]}, but {args.a} is {a.shape[1]}x{a.shape[0]}")
    difference = compare(a, b)
    if args.diff:
        import imageio.v3 as iio

        try:
            args.diff.parent.mkdir(parents=True, exist_ok=True)
            iio.imwrite(args.diff, diff_image(a, b))
        except OSError as error:
            raise SceneError(args.diff, "--diff", f"cannot write: {error.strerror or error}") from None
    within = difference.psnr_db >= args.tolerance_psnr
    if difference.max_abs == 0:
        verdict = "identical"
    else:
        side = "within" if within else "outside"
        verdict = f"{difference}; {side} the {args.tolerance_psnr:g} dB tolerance"
    print(f"{args.a} vs {args.b}: {verdict}")
    return 0 if within else 1
