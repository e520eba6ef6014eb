"""The `RenderSettings` options shared by `render`, `bench` and `record`."""

from __future__ import annotations

from cloudcore.errors import SceneError
from cloudcore.settings import MODES, TRANSLATION_METRICS, RenderSettings


def _boolean(text: str) -> bool:
    """`true` or `false`, as a sweep value; argparse names this function on refusal."""
    if text not in ("true", "false"):
        raise ValueError(text)
    return text == "true"


#: --sweep NAME=... -> (settings field, value parser)
SWEEPABLE = {
    "tolerance": ("tolerance_deg", float),
    "ring_radius": ("ring_radius", float),
    "impostor_max_size": ("impostor_max_size", int),
    "detail_texels": ("impostor_detail_texels", float),
    "regeneration_budget": ("regeneration_budget", int),
    "mode": ("mode", str),
    "metric": ("translation_metric", str),
    "tolerance_px": ("tolerance_px", float),
    "transition_frames": ("transition_frames", int),
    "frame_budget": ("frame_budget_ms", float),
    "group_clouds": ("group_clouds", _boolean),
    "inside_resolution": ("inside_resolution_scale", float),
    "point_sprites": ("point_sprites", _boolean),
}


def add_settings_arguments(parser, default_mode: str = "auto") -> None:
    defaults = RenderSettings()
    parser.add_argument("--mode", choices=MODES, default=default_mode, help="how clouds are drawn")
    parser.add_argument(
        "--tolerance",
        type=float,
        default=defaults.tolerance_deg,
        help="impostor tolerance, degrees of translation error (default %(default)s)",
    )
    parser.add_argument(
        "--translation-metric",
        choices=TRANSLATION_METRICS,
        default=defaults.translation_metric,
        help="parallax: the angle between the rays to the impostor's near and far points (Harris); "
        "centre: the angle turned around the cloud's centre (default %(default)s)",
    )
    parser.add_argument(
        "--tolerance-px",
        type=float,
        default=defaults.tolerance_px,
        help="impostor tolerance in pixels at the screen's centre; 0: use --tolerance (default %(default)s)",
    )
    parser.add_argument(
        "--transition-frames",
        type=int,
        default=defaults.transition_frames,
        help="frames of crossfade when auto mode changes a cloud's representation (default %(default)s)",
    )
    parser.add_argument(
        "--frame-budget",
        type=float,
        default=defaults.frame_budget_ms,
        help="milliseconds for impostor updates and the cloud pass together; over it, regenerations "
        "wait, most urgent first; 0: none (default %(default)s)",
    )
    parser.add_argument(
        "--no-group-clouds",
        dest="group_clouds",
        action="store_false",
        help="sort each cloud's impostor as a whole even where clouds interpenetrate",
    )
    parser.add_argument(
        "--no-point-sprites",
        dest="point_sprites",
        action="store_false",
        help="draw every splat as a quad, even where a point sprite gives the same picture",
    )
    parser.add_argument(
        "--ring-radius",
        type=float,
        default=defaults.ring_radius,
        help="metres beyond which clouds join the impostor ring; inf for none (default %(default)s)",
    )
    parser.add_argument(
        "--impostor-max-size",
        type=int,
        default=defaults.impostor_max_size,
        help="largest impostor texture side, a power of two (default %(default)s)",
    )
    parser.add_argument(
        "--detail-texels",
        type=float,
        default=defaults.impostor_detail_texels,
        help="texels across a cloud's finest particle radius an impostor needs; 0: screen resolution "
        "only (default %(default)s)",
    )
    parser.add_argument(
        "--regeneration-budget",
        type=int,
        default=defaults.regeneration_budget,
        help="impostors remade per frame at most, the farthest past the tolerance first; 0: no limit "
        "(default %(default)s)",
    )


def settings_from(args, **overrides) -> RenderSettings:
    """The settings the arguments name; out-of-domain values are a one-line error."""
    values = (
        dict(
            mode=args.mode,
            tolerance_deg=args.tolerance,
            ring_radius=args.ring_radius,
            impostor_max_size=args.impostor_max_size,
            impostor_detail_texels=args.detail_texels,
            regeneration_budget=args.regeneration_budget,
            translation_metric=args.translation_metric,
            tolerance_px=args.tolerance_px,
            transition_frames=args.transition_frames,
            group_clouds=args.group_clouds,
            point_sprites=args.point_sprites,
            frame_budget_ms=args.frame_budget,
        )
        | overrides
    )
    try:
        return RenderSettings(**values)
    except (TypeError, ValueError) as error:
        raise SceneError("settings", ",".join(overrides) or "options", str(error)) from None


def parse_sweep(text: str) -> tuple[str, list]:
    """`tolerance=0.05,0.15` -> ("tolerance_deg", [0.05, 0.15]); argparse names this function on refusal."""
    name, _, values = text.partition("=")
    if name not in SWEEPABLE or not values:
        raise ValueError(text)
    field, parse = SWEEPABLE[name]
    return field, [parse(value) for value in values.split(",")]
