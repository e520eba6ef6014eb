"""The `RenderSettings` options shared by `render`, `bench` and `record`, made from the settings' `Option`s."""

from __future__ import annotations

from cloudcore.model.errors import SceneError
from cloudcore.model.settings import RenderSettings, setting_options


def _boolean(text: str) -> bool:
    """`true` or `false`, as a sweep value; argparse names this function on refusal."""
    if text not in ("true", "false"):
        raise ValueError(text)
    return text == "true"


def _value_parser(option, default):
    """The parser of a command-line or sweep value of a setting whose default is `default`."""
    if option.parse is not None:
        return option.parse
    return _boolean if isinstance(default, bool) else type(default)


#: --sweep NAME=... -> (settings field, value parser)
SWEEPABLE = {
    option.sweep_name: (name, _value_parser(option, getattr(RenderSettings(), name)))
    for name, option in setting_options().items()
}


def add_settings_arguments(parser, default_mode: str = "auto", only: tuple[str, ...] | None = None) -> None:
    """The settings' options (those named in `only`, if given) on `parser`."""
    defaults = RenderSettings()
    for name, option in setting_options().items():
        if only is not None and name not in only:
            continue
        default = default_mode if name == "mode" else getattr(defaults, name)
        if isinstance(default, bool):  # a switch: its flag turns the default around
            parser.add_argument(
                option.flag,
                dest=name,
                action="store_false" if default else "store_true",
                help=f"do not {option.help}" if default else option.help,
            )
        else:
            parser.add_argument(
                option.flag,
                dest=name,
                type=_value_parser(option, default),
                choices=option.choices or None,
                default=default,
                metavar=None if option.choices else option.sweep_name.upper(),
                help=f"{option.help} (default %(default)s)",
            )


def settings_from(args, **overrides) -> RenderSettings:
    """The settings the arguments name; out-of-domain values are a one-line error."""
    values = {name: getattr(args, name) for name in setting_options()} | overrides
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
