"""Clouds forming and dissipating (Wang 2004, Listing 1) in rendered frames, full 3D and as impostors.

One cumulus in an empty sky, animated from 1 s to 3 s on the scene clock:
before and after the animation the frame is exactly that of a cloud with no
formation or of no cloud at all; inside it the cloud covers part of the sky,
and its impostor is remade every frame and only then.
"""

import dataclasses

import numpy as np
import pytest

from cloudcore.artist.cloudgen import preset_cloud
from cloudcore.model.cloud_records import Formation
from cloudcore.model.scene import Camera, Scene
from cloudcore.model.settings import FULL_3D, RenderSettings

START_S, DURATION_S = 1.0, 2.0
END_S = START_S + DURATION_S
#: the camera stays within the ring radius of the cloud, so impostor mode draws it as its own impostor
IMPOSTOR = RenderSettings(mode="impostor")
MODES = {"full": FULL_3D, "impostor": IMPOSTOR}


@pytest.fixture(scope="module")
def steady() -> Scene:
    cloud = preset_cloud("cumulus_humilis", "cumulus", (0.0, 1000.0, 0.0), seed=3)
    centre, _ = cloud.bounding_sphere()
    return Scene(camera=Camera((0.0, 1150.0, 1400.0), tuple(centre), 50.0), clouds=(cloud,))


def with_formation(scene: Scene, kind: str) -> Scene:
    cloud = dataclasses.replace(scene.clouds[0], formation=Formation(kind, START_S, DURATION_S))
    return dataclasses.replace(scene, clouds=(cloud,))


def coverage(image: np.ndarray, sky: np.ndarray) -> float:
    """How much of the sky the cloud hides: the mean difference from the sky alone, in 8-bit levels."""
    return float(np.abs(image.astype(float) - sky.astype(float)).mean())


def assert_within_one_level(image, reference):
    assert np.abs(image.astype(int) - reference.astype(int)).max() <= 1


@pytest.mark.parametrize("mode", MODES)
def test_a_forming_cloud_grows_from_nothing_to_the_whole_cloud(renderer, steady, mode):
    settings = MODES[mode]
    sky = renderer.render(dataclasses.replace(steady, clouds=()), settings=settings)[0]
    whole = renderer.render(steady, settings=settings)[0]
    forming = with_formation(steady, "form")

    def frame(time_s):
        return renderer.render(forming, settings=settings, time_s=time_s)[0]

    assert_within_one_level(frame(START_S - 0.5), sky)
    covered = [coverage(frame(START_S + fraction * DURATION_S), sky) for fraction in (0.25, 0.5, 0.75)]
    assert 0.0 < covered[0] < covered[1] < covered[2] < coverage(whole, sky)
    np.testing.assert_array_equal(frame(END_S + 0.5), whole)


@pytest.mark.parametrize("mode", MODES)
def test_a_dissipating_cloud_is_gone_at_the_end(renderer, steady, mode):
    settings = MODES[mode]
    sky = renderer.render(dataclasses.replace(steady, clouds=()), settings=settings)[0]
    whole = renderer.render(steady, settings=settings)[0]
    dissipating = with_formation(steady, "dissipate")

    def frame(time_s):
        return renderer.render(dissipating, settings=settings, time_s=time_s)[0]

    np.testing.assert_array_equal(frame(START_S - 0.5), whole)
    assert 0.0 < coverage(frame(START_S + 0.5 * DURATION_S), sky) < coverage(whole, sky)
    assert_within_one_level(frame(END_S + 0.5), sky)


def test_the_impostor_is_remade_while_the_cloud_forms_and_only_then(renderer, steady):
    forming = with_formation(steady, "form")

    def regenerated(time_s):
        stats = renderer.render(forming, settings=IMPOSTOR, time_s=time_s)[1]
        assert stats.plan.clouds_by_kind["impostor"] == 1
        return stats.plan.regeneration_reasons

    regenerated(0.0)  # whatever the renderer held before, the impostor is now the unformed cloud's
    assert regenerated(0.5) == {}
    for time_s in (1.5, 2.0, 2.5):
        assert regenerated(time_s) == {"lights": 1}
    assert regenerated(END_S + 0.5) == {"lights": 1}  # the last change: to the whole cloud
    assert regenerated(END_S + 1.0) == {}
    assert regenerated(END_S + 2.0) == {}
