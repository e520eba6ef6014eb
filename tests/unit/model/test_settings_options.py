"""One schema for the settings: the command line, the sweeps and the LOD panel are made from each field's Option."""

import argparse
import dataclasses
import math

import pytest

from cloudcore.cli.settings_args import SWEEPABLE, add_settings_arguments, parse_sweep, settings_from
from cloudcore.model.errors import SceneError
from cloudcore.model.settings import RenderSettings, setting_options


def parsed(*argv: str) -> RenderSettings:
    parser = argparse.ArgumentParser()
    add_settings_arguments(parser)
    return settings_from(parser.parse_args(list(argv)))


def other_value(name: str):
    """A valid value of setting `name` that is not its default."""
    default = getattr(RenderSettings(), name)
    option = setting_options()[name]
    if option.choices:
        return next(choice for choice in option.choices if choice != default)
    if isinstance(default, bool):
        return not default
    if isinstance(default, int):
        return {"impostor_min_size": 32, "impostor_max_size": 256}.get(name, default + 1)
    return {"inside_resolution_scale": 0.5, "cloud_resolution_scale": 0.5}.get(name, default + 0.25)


def test_no_options_give_the_default_settings():
    assert parsed() == RenderSettings()


@pytest.mark.parametrize("name", list(setting_options()))
def test_every_option_sets_its_own_field_and_no_other(name):
    option, value = setting_options()[name], other_value(name)
    argv = [option.flag] if isinstance(value, bool) else [option.flag, str(value)]
    assert parsed(*argv) == dataclasses.replace(RenderSettings(), **{name: value})


@pytest.mark.parametrize("name", list(setting_options()))
def test_every_option_can_be_swept_under_its_flags_words(name):
    option, value = setting_options()[name], other_value(name)
    text = str(value).lower() if isinstance(value, bool) else str(value)
    assert parse_sweep(f"{option.sweep_name}={text}") == (name, [value])
    assert SWEEPABLE[option.sweep_name][0] == name


def test_flags_and_sweep_names_are_unique_and_switches_say_what_they_turn():
    options = setting_options().values()
    assert len({o.flag for o in options}) == len({o.sweep_name for o in options}) == len(options)
    for name, option in setting_options().items():
        if getattr(RenderSettings(), name) is True:
            assert option.flag.startswith("--no-"), name


def test_an_infinite_ring_radius_means_no_ring():
    assert math.isinf(parsed("--ring-radius", "inf").ring_radius) and not parsed("--ring-radius", "inf").uses_ring


def test_an_out_of_range_value_is_one_line_naming_the_problem():
    with pytest.raises(SceneError, match="tolerance_deg must be within"):
        parsed("--tolerance", "-1")


def test_every_panel_widget_has_a_range_that_holds_its_default():
    for name, option in setting_options().items():
        default = getattr(RenderSettings(), name)
        if option.label is None or option.choices or isinstance(default, bool):
            continue
        assert option.low <= default <= option.high, name
        assert option.display, name


def test_the_cloud_pass_scale_may_be_chosen_per_frame_and_is_refused_out_of_range_in_one_line():
    assert parsed("--cloud-resolution", "auto").cloud_resolution_scale == "auto"
    assert parse_sweep("cloud_resolution=1,0.25,auto") == ("cloud_resolution_scale", [1.0, 0.25, "auto"])
    for value in (0.0, 1.5, math.nan, "often", True):
        with pytest.raises(ValueError, match=r"^cloud_resolution_scale must be 'auto' or within \[0.125, 1\], got"):
            RenderSettings(cloud_resolution_scale=value)
    with pytest.raises(SceneError, match="cloud_resolution_scale must be 'auto' or within"):
        parsed("--cloud-resolution", "2")
