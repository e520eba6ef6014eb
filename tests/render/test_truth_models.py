"""`cloudview truth`'s models: drawn in the truth's world, whose clouds hang in empty space before the sky."""

import dataclasses
from types import SimpleNamespace

import numpy as np
import pytest

from cloudcore.cli.truth import model_renders
from cloudcore.gl import FrameRenderer
from cloudcore.light.splat_look import LOOK_SETTINGS
from cloudcore.model.scene import Camera, Cloud, Lighting, Scene
from cloudcore.model.settings import FULL_3D, RenderSettings

pytestmark = pytest.mark.gl

SIZE = (48, 36)


def far_cloud_scene() -> Scene:
    """A cloud 12 km off under the evening's physical sky: the air between it and the eye is most of its light."""
    rng = np.random.default_rng(3)
    centre = np.array([0.0, 2000.0, -12000.0])
    particles = np.column_stack([centre + rng.normal(0.0, 250.0, (60, 3)), np.full(60, 180.0)])
    return Scene(
        camera=Camera((0.0, 500.0, 0.0), tuple(centre), 12.0),
        lighting=Lighting(time_of_day=17.0),
        clouds=(Cloud("far", particles),),
    )


def test_the_truth_s_models_are_drawn_without_the_air_the_truth_lacks():
    scene = far_cloud_scene()
    looks = {name: getattr(RenderSettings(), name) for name in LOOK_SETTINGS}
    args = SimpleNamespace(width=SIZE[0], height=SIZE[1], models=("harris-exact",), time_of_day=None, **looks)
    ((model, _, _),) = model_renders(scene, scene.camera, args).values()
    with FrameRenderer(*SIZE) as renderer:
        with_air, _ = renderer.render(scene, illumination_method="exact", settings=FULL_3D)
        without_air, _ = renderer.render(
            scene,
            illumination_method="exact",
            settings=dataclasses.replace(FULL_3D, light_shafts=False, aerial_perspective=False),
        )
    # the air is there to leave out: it moves the cloud's pixels by several levels (8 measured)
    assert np.abs(with_air.astype(int) - without_air.astype(int)).max() > 4
    np.testing.assert_array_equal(model, without_air)
