"""Impostors, the crossfade and the ring against the full-3D reference, rendered at 160x120.

Thresholds (PSNR against full 3D, after the ring has been built and faded in):
default view >= 38 dB (measured 40.5 in impostor mode and 44.6 in auto at this
size; 36.1 before interpenetrating clouds were grouped into one impostor),
into the sun >= 45 dB, inside a cloud >= 50 dB; orbiting, with groups apart,
>= 35.5 dB on the worst frame.

The scene is drawn under the gradient sky these thresholds were measured against: an impostor's error is at
the clouds' silhouettes, and the atmosphere's darker blue behind them (docs/atmosphere.md) reads the same
error 3 to 6 dB lower (default view 37.5 dB in impostor mode, into the sun 43.3, the still eye after the orbit
37.1, 2026-12-07), which says the background changed, not the impostors.
"""

import dataclasses

import numpy as np
import pytest

from cloudcore.lod.costs import LLVMPIPE_COSTS, CostModel
from cloudcore.lod.plan import LodState
from cloudcore.lod.ring import SEGMENTS
from cloudcore.measure.imagecompare import compare
from cloudcore.model.scene import Air, Camera
from cloudcore.model.settings import FULL_3D, RenderSettings
from cloudcore.scenes.files import load_scene
from cloudcore.world.navigation import orbited
from tests.conftest import VALLEY
from tests.render.test_render_golden import inside_a_cloud, into_the_sun
from tests.unit.lod.test_frameplan import FILL_BOUND, UPKEEP_BOUND

#: full 3D all but free, an impostor's quad dear: auto moves every unit to full 3D
FULL_CHEAP = dataclasses.replace(UPKEEP_BOUND, quad_pixels=1.0)

#: enough frames to build all ring segments and fade the ring in
SETTLE_FRAMES = SEGMENTS + RenderSettings().ring_fade_frames + 1


@pytest.fixture(scope="module")
def valley():
    scene = load_scene(VALLEY)
    return dataclasses.replace(scene, lighting=dataclasses.replace(scene.lighting, air=Air(sky="gradient")))


def settled(renderer, scene, camera, settings, costs=None):
    for _ in range(SETTLE_FRAMES):
        image, stats = renderer.render(scene, camera=camera, settings=settings, costs=costs)
    return image, stats


@pytest.mark.parametrize("view, min_psnr_db", [("default", 38.0), ("into_the_sun", 45.0), ("inside_a_cloud", 50.0)])
@pytest.mark.parametrize("mode", ["auto", "impostor"])
def test_impostor_renders_agree_with_full_3d(renderer, valley, view, min_psnr_db, mode):
    camera = {"default": None, "into_the_sun": into_the_sun(valley), "inside_a_cloud": inside_a_cloud(valley)}[view]
    reference, full_stats = renderer.render(valley, camera=camera, settings=FULL_3D)
    image, stats = settled(renderer, valley, camera, RenderSettings(mode=mode))
    difference = compare(image, reference)
    assert difference.psnr_db >= min_psnr_db, f"{view}, {mode}: {difference}"
    assert stats.plan.impostors_drawn > 0
    fewer = stats.particles_drawn < full_stats.particles_drawn
    assert fewer if mode == "impostor" else stats.particles_drawn <= full_stats.particles_drawn
    if view == "inside_a_cloud":
        assert len(renderer.last_plan.of_kind("inside")) == 1


def test_the_default_view_still_is_drawn_from_impostors(renderer, valley):
    """A still eye: every impostor lasts, so auto draws every unit from one (none is cheaper in full 3D), its own or
    the ring's, whichever the plan priced cheaper.  Priced with llvmpipe's costs pinned: a GPU's measured costs plan
    otherwise (on an H200 one cloud stayed in full 3D), and the policy is what is tested here."""
    _, stats = settled(renderer, valley, None, RenderSettings(), LLVMPIPE_COSTS)
    assert stats.plan.clouds_by_kind["impostor"] > 0 and stats.plan.clouds_by_kind["full"] == 0
    assert stats.plan.units_grouped > 0  # the default scene has interpenetrating clouds
    _, again = renderer.render(valley, settings=RenderSettings(), costs=LLVMPIPE_COSTS)
    assert again.plan.impostors_regenerated == 0 and again.plan.ring_segments_built == 0  # nothing moved


@pytest.mark.parametrize("scale", [1.0, 0.5])
def test_the_crossfade_mixes_full_3d_and_impostor_linearly(renderer, valley, scale):
    """When the measured costs turn, the unit crossfades from its impostor to full 3D; at every step the
    frame's mean is the plan's weighted mean of the two ends.

    A blend that brightened or darkened mid-fade (the seam) would leave this line; so would a reduced cloud pass
    (`scale`) whose crossfade layer were not its own size and depth.
    """
    cloud = valley.clouds[5]
    centre, radius = cloud.bounding_sphere()
    scene = dataclasses.replace(valley, clouds=(cloud,), terrain=None)
    # the impostor is made from one eye and seen from another, three quarters of the tolerance round:
    # kept, but far enough from full 3D that switching to it calls for the crossfade
    auto = dataclasses.replace(
        RenderSettings(),
        ring_radius=np.inf,
        transition_frames=5,
        translation_metric="centre",
        tolerance_deg=1.0,
        cloud_resolution_scale=scale,
    )
    made_from = Camera(tuple(centre + [0.0, 0.0, 3.0 * radius]), tuple(centre), 60.0)
    camera = orbited(made_from, 0.75)
    renderer.render(scene, camera=made_from, settings=dataclasses.replace(auto, mode="impostor"))
    ends = [
        renderer.render(scene, camera=camera, settings=s)[0].astype(float).mean()
        for s in (dataclasses.replace(auto, mode="full"), dataclasses.replace(auto, mode="impostor"))
    ]
    assert renderer.last_plan.clouds[0].regenerate is None
    means, weights = [], []
    for frame in range(8):
        costs = FILL_BOUND if frame == 0 else FULL_CHEAP
        blended = renderer.render(scene, camera=camera, settings=auto, costs=costs)[0].astype(float).mean()
        weight = renderer.last_plan.clouds[0].full_weight
        assert blended == pytest.approx(weight * ends[0] + (1 - weight) * ends[1], abs=0.01)
        means.append(blended)
        weights.append(weight)
    assert weights == pytest.approx([0.0, 0.2, 0.4, 0.6, 0.8, 1.0, 1.0, 1.0])
    assert np.max(np.abs(np.diff(means))) < 1.0  # smooth: under one 8-bit level a frame


def test_textures_of_a_dropped_ring_are_reused_not_added(renderer, valley):
    settled(renderer, valley, None, RenderSettings())
    with_ring = renderer.texture_bytes
    _, stats = settled(renderer, valley, None, dataclasses.replace(RenderSettings(), ring_radius=np.inf))
    assert stats.plan.ring_panels_drawn == 0 and stats.texture_bytes <= with_ring


def test_a_ring_rebuilt_in_pieces_shows_what_one_built_whole_does(renderer, valley):
    """Relit, the ring is rebuilt; a particle priced at 1 ms makes every cloud a piece of its own (past
    `RING_FRAME_MS`), each drawn over the last, far to near, into its segment's texture: the rebuilt ring is the
    picture of the first ring at that hour, built a segment a frame."""
    settings, later = RenderSettings(mode="impostor"), valley.lighting.time_of_day + 1.0

    def render(frames, **options):
        for _ in range(frames):
            image, _ = renderer.render(valley, settings=settings, time_of_day=later, **options)
            yield image, renderer.last_plan.ring

    renderer.lod_state = LodState()
    settled(renderer, valley, None, settings)
    first = renderer.last_plan.ring.state.current
    pieces = []
    for frame in render(400, costs=CostModel(particles=1.0)):
        image, ring = frame
        pieces += [ring.build_piece] if ring.build_members else []
        if ring.state.current is not first and ring.state.pending is None:
            break
    rebuilt = ring.state.current
    assert rebuilt is not first and len(pieces) == sum(map(len, rebuilt.segment_members)) > len(
        rebuilt.occupied_segments
    )
    renderer.lod_state = LodState()
    *_, (whole, _) = render(SETTLE_FRAMES)
    difference = compare(image, whole)
    assert difference.psnr_db >= 50.0, difference


def test_orbiting_draws_groups_apart_and_the_still_eye_whole_again(renderer, valley):
    """Auto mode plans a group of interpenetrating clouds as its clouds while the eye moves (their impostors last
    longer than the group's); once the eye stops the group is one impostor again, remade from that eye.  With
    llvmpipe's costs pinned, as above (on an H200's measured costs no group was dearer whole)."""
    settled(renderer, valley, None, RenderSettings(), LLVMPIPE_COSTS)
    cameras, images, opened = [valley.camera], [], set()
    for _ in range(12):
        cameras.append(orbited(cameras[-1], 0.5))
        images.append(renderer.render(valley, camera=cameras[-1], settings=RenderSettings(), costs=LLVMPIPE_COSTS)[0])
        opened |= renderer.last_plan.state.opened
    assert opened and all(len(members) > 1 for members in opened)
    still, stats = settled(renderer, valley, cameras[-1], RenderSettings(), LLVMPIPE_COSTS)
    assert not renderer.last_plan.state.opened and stats.plan.units_grouped > 0
    references = [renderer.render(valley, camera=camera, settings=FULL_3D)[0] for camera in cameras[1:]]
    # measured: 37.0 dB on the worst frame moving (38.1 with groups whole), 40.0 still
    worst = min(compare(image, reference).psnr_db for image, reference in zip(images, references))
    assert worst >= 35.5, f"orbiting: {worst:.1f} dB"
    assert compare(still, references[-1]).psnr_db >= 38.0


def test_the_screen_impostor_of_a_cloud_at_the_side_of_the_view_is_composited_where_its_particles_are(renderer, valley):
    """The eye just inside a unit's sphere, the unit off to the right: its screen impostor's composite is
    cropped to the part of the screen its particles can cover (here about a quarter of it), its texture
    rectangle and corners alike (that the crop holds every particle, tests/unit/lod/test_particle_extent.py)."""
    renderer.render(valley, camera=inside_a_cloud(valley), settings=RenderSettings(mode="impostor"))
    plan = renderer.last_plan
    (unit,) = plan.of_kind("inside")
    centre, radius = plan.units.centres[unit.index], plan.units.radii[unit.index]
    eye = centre + np.array([radius * 1.02, 0.0, 0.0])
    # looking 40 degrees off the direction back to the centre, horizontally: the cloud fills the right
    aside = np.radians(40.0)
    camera = Camera(tuple(eye), tuple(eye + 100.0 * np.array([-np.cos(aside), 0.0, np.sin(aside)])), 60.0)
    reference, _ = renderer.render(valley, camera=camera, settings=FULL_3D)
    image, _ = renderer.render(valley, camera=camera, settings=RenderSettings(mode="impostor"))
    assert renderer.last_plan.of_kind("inside")
    difference = compare(image, reference)
    assert difference.psnr_db >= 42.0, difference  # measured 45.3; a texture rectangle off its corners: far less
