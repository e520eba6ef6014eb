"""The robustness matrix of docs/robustness.md (issue 9): each row is an extreme input, rendered headless.

Every row ends in a finite image (no NaN or Inf in any float buffer the frame
leaves: the RGBA16F frame, the R32F overdraw counts of its cloud draws, the
RGBA16F impostor textures and ring panels it drew from), a bounded frame time,
or a clear refusal (a `SceneError` naming the field, a `ValueError` naming the
problem).  Beyond finiteness each row checks what the extreme should do
(nothing drawn, everything drawn, no regeneration...).

`./run tests tests/robustness/test_robustness.py -s` prints one line of measurements per
frame: the numbers in the doc's table.  The 1.2-million-particle and
10-minute rows are benchmarks (scripts/bench_many_particles.py,
scripts/bench_longrun.py), not tests.
"""

import dataclasses
import math

import numpy as np
import pytest
from scipy.optimize import brentq

from cloudcore.gl.context import WindowContext
from cloudcore.gl.frame import FrameRenderer
from cloudcore.light.lighting import scene_lights
from cloudcore.lod.plan.unit_plans import TEXTURED
from cloudcore.lod.ring import SEGMENTS
from cloudcore.lod.splat_coverage import splats_in_frustum
from cloudcore.model.errors import SceneError
from cloudcore.model.scene import Camera, Cloud, Light, Lighting, Scene, Terrain
from cloudcore.model.settings import FULL_3D, RenderSettings
from cloudcore.scenes.files import scene_from_dict
from cloudcore.stats.frame_stats import FrameStats
from cloudcore.world.camera import NEAR_PLANE_M, frustum_planes, projection_matrix, view_matrix
from cloudcore.world.sun import elevation_deg, sun_direction
from cloudcore.world.terrain import height_at

#: a sanity bound, not a timing test: llvmpipe on two shared cores draws these 160x120 frames in milliseconds
FRAME_TIME_LIMIT_MS = 20_000.0
#: below this a frame is the clear sky's to half-float precision (RGBA16F near 1 resolves 2^-11)
HALF_FLOAT_ATOL = 2.0**-10
#: a cloud that changes some pixel by more than this (linear light; a few 8-bit levels) is visible
VISIBLE = 0.01
MODES = {"full": FULL_3D, "auto": RenderSettings(), "impostor": RenderSettings(mode="impostor")}

CLOUD_CENTRE = np.array([0.0, 800.0, 0.0])
EYE = (0.0, 600.0, 1500.0)


def puff(count: int = 150, radius: float = 30.0, spread: float = 80.0, seed: int = 0) -> np.ndarray:
    """Particle rows (x, y, z, radius) normally spread around CLOUD_CENTRE."""
    centres = np.random.default_rng(seed).normal(size=(count, 3)) * spread + CLOUD_CENTRE
    return np.column_stack([centres, np.full(count, radius)])


BASE = Scene(
    camera=Camera(EYE, tuple(CLOUD_CENTRE), 55.0),
    lighting=Lighting(time_of_day=15.5),
    clouds=(Cloud("puff", puff()),),
    terrain=Terrain(size=(3000.0, 3000.0), resolution=17, height=300.0, seed=3),
)


def with_particles(particles: np.ndarray, **cloud_fields) -> Scene:
    return dataclasses.replace(BASE, clouds=(Cloud("puff", particles, **cloud_fields),))


def float_buffers(renderer: FrameRenderer) -> dict[str, np.ndarray]:
    """Every float buffer the last frame left behind, by name, as float32 arrays."""
    buffers = {"frame": renderer.context.read_linear_rgb(), "overdraw": renderer.measure_overdraw()[0]}
    plan = renderer.last_plan
    store = renderer._impostors  # the renderer has no public handle on its store; the store's lookups are public
    for cloud in plan.of_kind(*TEXTURED):
        for layer in range(cloud.layers):
            buffers[f"impostor {cloud.index}/{layer}"] = store.cloud_impostor(cloud.members, layer)[0].read()
    for generation, _ in plan.ring.draws if plan.ring is not None else ():
        for segment in generation.occupied_segments:
            buffers[f"ring panel {segment}"] = store.ring_panel(generation, segment, 30.0)[0].read()
    return buffers


@dataclasses.dataclass
class Frame:
    linear: np.ndarray  # the RGBA16F frame's RGB, linear light
    stats: FrameStats
    kinds: list  # each cloud's kind in the frame plan
    overdraw_max: float


def render_checked(
    renderer: FrameRenderer, row: str, scene: Scene, settings: RenderSettings = FULL_3D, *, camera: Camera | None = None
) -> Frame:
    """Render one frame and check the matrix's promise: every float buffer finite, the frame time bounded."""
    _, stats = renderer.render(scene, camera=camera, settings=settings, read_back=False)
    buffers = float_buffers(renderer)
    for name, pixels in buffers.items():
        bad = np.count_nonzero(~np.isfinite(pixels))
        assert bad == 0, f"{row}: {bad} NaN/Inf values in the {name} buffer"
    numbers = {key: value for key, value in stats.as_dict().items() if isinstance(value, (int, float))}
    assert all(math.isfinite(value) for value in numbers.values()), numbers
    assert 0.0 <= stats.frame_ms < FRAME_TIME_LIMIT_MS
    frame = Frame(
        buffers["frame"], stats, [cloud.kind for cloud in renderer.last_plan.clouds], float(buffers["overdraw"].max())
    )
    print(
        f"\nROW {row} [{settings.mode}]: {len(buffers)} float buffers finite; frame max {frame.linear.max():.4g}, "
        f"min {frame.linear.min():.4g}; overdraw max {frame.overdraw_max:g}; {stats.frame_ms:.1f} ms; "
        f"{stats.particles_drawn} particles drawn; plan {frame.kinds}"
    )
    return frame


def clear_sky(renderer, scene: Scene = BASE, settings: RenderSettings = FULL_3D, camera=None) -> np.ndarray:
    """The frame without its clouds: what an invisible cloud must leave exactly."""
    return render_checked(renderer, "no clouds", dataclasses.replace(scene, clouds=()), settings, camera=camera).linear


def cloud_added(frame: Frame, clear: np.ndarray) -> float:
    """The most the clouds changed any pixel of the frame, in linear light."""
    added = float(np.abs(frame.linear - clear).max())
    print(f"  the clouds change the clear frame by at most {added:.4g}")
    return added


def refusal(document: dict, field: str) -> str:
    """The message `scene_from_dict` refuses `document` with; it must name `field`."""
    with pytest.raises(SceneError) as refused:
        scene_from_dict(document, "robustness.toml")
    assert refused.value.field == field and len(str(refused.value).splitlines()) == 1
    print(f"\nREFUSED {field}: {refused.value}")
    return str(refused.value)


# ---------------------------------------------------------------- the clouds' optics and sizes


@pytest.mark.parametrize("mode", ["full", "impostor"])
@pytest.mark.parametrize("tau", [0.0, 1e-12, 8.0, 50.0, 1e3, 1e6])
def test_optical_depth(renderer, tau, mode):
    settings = MODES[mode]
    frame = render_checked(renderer, f"optical depth {tau:g}", with_particles(puff(), optical_depth=tau), settings)
    added = cloud_added(frame, clear_sky(renderer, settings=settings))
    if tau == 0.0:
        assert added == 0.0  # transparent particles are not drawn at all
    elif tau < 1e-6:
        assert added < HALF_FLOAT_ATOL
    else:
        assert added > VISIBLE


def test_optically_thick_clouds_saturate_instead_of_growing(renderer):
    """Beyond tau ~ 10 every particle is opaque and forward-scatters what it stops: 1e3 and 1e6 look the same."""
    thick, thicker = (
        render_checked(renderer, f"optical depth {tau:g}", with_particles(puff(), optical_depth=tau))
        for tau in (1e3, 1e6)
    )
    np.testing.assert_allclose(thick.linear, thicker.linear, atol=HALF_FLOAT_ATOL)


def test_albedo_0_and_1(renderer):
    clear = clear_sky(renderer)
    absorbing, scattering = (
        render_checked(renderer, f"albedo {albedo:g}", with_particles(puff(), albedo=albedo)) for albedo in (0.0, 1.0)
    )
    cloud = np.abs(scattering.linear - clear).max(axis=2) > VISIBLE
    assert cloud.mean() > 0.01
    # albedo 0 only absorbs (plus the ambient term): the same cloud is darker than at albedo 1
    assert absorbing.linear[cloud].mean() < scattering.linear[cloud].mean()
    assert absorbing.linear.max() <= scattering.linear.max() + HALF_FLOAT_ATOL


@pytest.mark.parametrize("mode", ["full", "auto"])
@pytest.mark.parametrize("radius", [1e-6, 1e6])
def test_particle_radius(renderer, radius, mode):
    """1e-6 m splats cover no pixel; 1e6 m ones hold the eye, 1.5 km from their centres, where they fade out (for the
    eye: their shadows would darken the whole ground, so these are drawn without the clouds' shadows)."""
    settings = dataclasses.replace(MODES[mode], cloud_shadows=False) if radius > 1e3 else MODES[mode]
    particles = puff()
    particles[:, 3] = radius
    frame = render_checked(renderer, f"radius {radius:g} m", with_particles(particles), settings)
    assert cloud_added(frame, clear_sky(renderer, settings=settings)) < HALF_FLOAT_ATOL
    if radius > 1e3 and mode == "auto":
        assert frame.kinds == ["inside"]


def test_one_particle(renderer):
    frame = render_checked(renderer, "1 particle", with_particles(puff(count=1, radius=120.0)))
    assert cloud_added(frame, clear_sky(renderer)) > VISIBLE
    assert frame.overdraw_max == 1.0


def test_a_thousand_coincident_particles(renderer):
    particles = np.tile([*CLOUD_CENTRE, 120.0], (1000, 1))
    frame = render_checked(renderer, "1000 coincident particles", with_particles(particles))
    assert cloud_added(frame, clear_sky(renderer)) > VISIBLE
    assert frame.overdraw_max == 1000.0  # every splat drawn, none lost to the sort or the shading


# ---------------------------------------------------------------- where the camera is


def looking_from(eye, at=CLOUD_CENTRE + [0.0, 0.0, -500.0], fov: float = 55.0) -> Camera:
    return Camera(tuple(float(v) for v in eye), tuple(float(v) for v in at), fov)


@pytest.mark.parametrize("mode", ["full", "auto"])
def test_camera_inside_a_particle(renderer, mode):
    """The particle holding the eye fades out (`cloudcore.particles.buffer`); the others in view are drawn."""
    camera = looking_from(BASE.clouds[0].particles[0, :3])
    frame = render_checked(renderer, "camera at a particle's centre", BASE, MODES[mode], camera=camera)
    expected_kind = kind_with_the_eye_inside(renderer, mode)
    particles = BASE.clouds[0].particles
    in_view = splats_in_frustum(
        frustum_planes(projection_matrix(camera.fov_y_deg, renderer.size[0] / renderer.size[1]) @ view_matrix(camera)),
        particles[:, :3],
        particles[:, 3],
    )
    assert in_view[0] and frame.stats.particles_drawn == np.count_nonzero(in_view) - 1
    assert cloud_added(frame, clear_sky(renderer, settings=MODES[mode], camera=camera)) > VISIBLE
    assert frame.kinds == [expected_kind]


def kind_with_the_eye_inside(renderer, mode: str) -> str:
    """How the one unit the eye is in is drawn, asked right after the frame: in full 3D in full mode, as a
    screen impostor in impostor mode, and in auto mode as the cheaper of the two by the plan's own prices (a
    unit seen for the first time)."""
    if mode != "auto":
        return {"full": "full", "impostor": "inside"}[mode]
    (cloud,) = renderer.last_plan.clouds
    return "full" if cloud.full_ms <= cloud.impostor_ms else "inside"


@pytest.mark.parametrize("mode", ["full", "auto", "impostor"])
def test_camera_at_a_cloud_centre(renderer, mode):
    centre, _ = BASE.clouds[0].bounding_sphere()
    camera = looking_from(centre)
    frame = render_checked(renderer, "camera at the cloud's centre", BASE, MODES[mode], camera=camera)
    expected_kind = kind_with_the_eye_inside(renderer, mode)
    assert cloud_added(frame, clear_sky(renderer, settings=MODES[mode], camera=camera)) > VISIBLE
    assert frame.kinds == [expected_kind]


def test_camera_exactly_at_an_impostor_s_creation_point(renderer):
    settings = dataclasses.replace(MODES["impostor"], tolerance_deg=1.0)
    scene = with_particles(puff())  # a cloud the renderer has not seen: its impostor is made at EYE
    first = render_checked(renderer, "impostor made here", scene, settings)
    assert first.stats.plan.impostors_regenerated == 1
    render_checked(renderer, "0.4 degrees aside", scene, settings, camera=looking_from((10.0, 600.0, 1500.0)))
    back = render_checked(renderer, "back at the creation point", scene, settings)
    assert back.stats.plan.impostors_regenerated == 0
    np.testing.assert_array_equal(back.linear, first.linear)


@pytest.mark.parametrize("mode", ["full", "auto"])
def test_particle_at_the_near_plane(renderer, mode):
    """A particle of radius 0.5 m centred on the near plane: its flat splat lies in that plane and is clipped
    whole (finite, nothing drawn); 5 cm further it is drawn.  Particles of 2 m and more are faded out there."""
    camera = looking_from(EYE, CLOUD_CENTRE)
    forward = (CLOUD_CENTRE - EYE) / np.linalg.norm(CLOUD_CENTRE - EYE)
    clear = clear_sky(renderer, settings=MODES[mode], camera=camera)
    for distance, drawn in ((NEAR_PLANE_M, False), (NEAR_PLANE_M + 0.05, True)):
        particle = [*(np.array(EYE) + distance * forward), 0.5]
        frame = render_checked(
            renderer,
            f"particle {distance:g} m from the eye",
            with_particles(np.array([particle])),
            MODES[mode],
            camera=camera,
        )
        assert (cloud_added(frame, clear) > VISIBLE) == drawn


@pytest.mark.parametrize("mode", ["full", "auto"])
def test_camera_below_the_terrain(renderer, mode):
    ground = float(height_at(BASE.terrain, EYE[0], EYE[2]))
    camera = looking_from((EYE[0], ground - 50.0, EYE[2]), CLOUD_CENTRE)
    render_checked(renderer, "camera 50 m below the terrain", BASE, MODES[mode], camera=camera)


@pytest.mark.parametrize("mode", ["full", "auto", "impostor"])
def test_camera_ten_thousand_km_away(renderer, mode):
    """1e7 m is beyond the 100 km far plane: the cloud is culled (or in an empty ring panel), nothing drawn."""
    camera = looking_from(CLOUD_CENTRE + [1e7, 0.0, 0.0], CLOUD_CENTRE)
    frame = render_checked(renderer, "camera 1e7 m away", BASE, MODES[mode], camera=camera)
    assert cloud_added(frame, clear_sky(renderer, settings=MODES[mode], camera=camera)) == 0.0
    assert frame.kinds == ["culled"]


@pytest.mark.parametrize("fov", [1.0, 170.0])
def test_field_of_view(renderer, fov):
    camera = looking_from(EYE, CLOUD_CENTRE, fov)
    frame = render_checked(renderer, f"field of view {fov:g} degrees", BASE, camera=camera)
    assert cloud_added(frame, clear_sky(renderer, camera=camera)) > VISIBLE


@pytest.mark.parametrize("fov", [0.5, 175.0])
def test_field_of_view_outside_1_to_170_degrees_is_refused(fov):
    assert "must be within [1.0, 170.0]" in refusal({"camera": {"fov_y_deg": fov}}, "camera.fov_y_deg")


# ---------------------------------------------------------------- the sun and the phase function


def sunrise_hours() -> float:
    """The hour the sun's centre crosses the horizon in the morning (elevation exactly 0, to 1e-12 h)."""
    return brentq(lambda hours: elevation_deg(sun_direction(hours)), 4.0, 7.0, xtol=1e-12)


SUNS = {
    "zenith": Lighting(time_of_day=None, lights=(Light((0.0, 1.0, 0.0)),)),
    "horizon": Lighting(time_of_day=None, lights=(Light((1.0, 0.0, 0.0)),)),
    "below the horizon": Lighting(time_of_day=None, lights=(Light((0.0, -1.0, 0.0)),)),
    "sunrise": Lighting(time_of_day=sunrise_hours()),
    "midnight": Lighting(time_of_day=0.0),
}


@pytest.mark.parametrize("mode", ["full", "impostor"])
@pytest.mark.parametrize("sun", SUNS)
def test_sun_position(renderer, sun, mode):
    scene = dataclasses.replace(BASE, lighting=SUNS[sun])
    frame = render_checked(renderer, f"sun {sun}", scene, MODES[mode])
    assert cloud_added(frame, clear_sky(renderer, scene, MODES[mode])) > 0.0


@pytest.mark.parametrize("phase", ["henyey-greenstein", "cornette-shanks"])
@pytest.mark.parametrize("g", [0.0, 0.99, -0.99])
def test_phase_asymmetry(renderer, phase, g):
    """Looking straight into the light, where a g = 0.99 lobe peaks at (1 + g) / (1 - g)^2 ~ 2e4 times its mean.

    The scattering cap (`cloudcore.light.shading.scattering_coefficient`) keeps every particle's colour within
    its opacity times (light + ambient), so the composited frame never exceeds light + ambient.
    """
    into_light = tuple((CLOUD_CENTRE - EYE) / np.linalg.norm(CLOUD_CENTRE - EYE))
    lighting = Lighting(time_of_day=None, lights=(Light(into_light),))
    scene = dataclasses.replace(BASE, shading=dataclasses.replace(BASE.shading, phase=phase, g=g), lighting=lighting)
    frame = render_checked(renderer, f"{phase} g {g:g}, into the light", scene)
    assert cloud_added(frame, clear_sky(renderer, scene)) > VISIBLE
    assert frame.linear.max() <= 1.0 + scene_lights(lighting)[1].max() + HALF_FLOAT_ATOL


def test_phase_asymmetry_of_one_is_refused():
    assert "must be within [-0.999, 0.999]" in refusal({"shading": {"g": 1.0}}, "shading.g")


# ---------------------------------------------------------------- level of detail


def test_impostor_tolerance_0_remakes_on_any_move(renderer):
    settings = dataclasses.replace(MODES["impostor"], tolerance_deg=0.0)
    render_checked(renderer, "tolerance 0", BASE, settings)
    still = render_checked(renderer, "tolerance 0, eye still", BASE, settings)
    assert still.stats.plan.impostors_regenerated == 0, still.stats.plan.regeneration_reasons
    moved = render_checked(
        renderer,
        "tolerance 0, eye 1 mm aside",
        BASE,
        settings,
        camera=looking_from(np.add(EYE, [1e-3, 0.0, 0.0]), CLOUD_CENTRE),
    )
    assert moved.stats.plan.regeneration_reasons == {"translation": 1}


def test_impostor_tolerance_90_keeps_the_impostor_a_quarter_turn_round(renderer):
    settings = dataclasses.replace(MODES["impostor"], tolerance_deg=90.0)
    render_checked(renderer, "tolerance 90", BASE, settings)
    offset = np.array(EYE) - CLOUD_CENTRE
    turned = CLOUD_CENTRE + [
        offset[2] * math.sin(math.radians(80.0)),
        offset[1],
        offset[2] * math.cos(math.radians(80.0)),
    ]
    frame = render_checked(
        renderer, "tolerance 90, eye 80 degrees round", BASE, settings, camera=looking_from(turned, CLOUD_CENTRE)
    )
    assert frame.stats.plan.impostors_regenerated == 0


def settle_ring(renderer, row: str, settings: RenderSettings) -> Frame:
    """Frames from one eye until a new ring is built (one segment a frame) and faded in."""
    for _ in range(SEGMENTS + settings.ring_fade_frames):
        frame = render_checked(renderer, row, BASE, settings)
    return frame


def test_ring_radius_0_puts_the_cloud_on_the_ring(renderer):
    settings = dataclasses.replace(MODES["impostor"], ring_radius=0.0)  # auto mode would price the ring
    frame = settle_ring(renderer, "ring radius 0", settings)
    assert frame.kinds == ["ring"]
    assert cloud_added(frame, clear_sky(renderer)) > VISIBLE  # on panels at 10 m, but drawn


def test_ring_radius_larger_than_the_scene_holds_nothing(renderer):
    settings = dataclasses.replace(MODES["impostor"], ring_radius=1e9)
    frame = settle_ring(renderer, "ring radius 1e9 m", settings)
    assert frame.kinds == ["impostor"] and frame.stats.plan.ring_panels_drawn == 0  # an empty ring costs nothing
    assert cloud_added(frame, clear_sky(renderer)) > VISIBLE


def test_negative_ring_radius_is_refused():
    with pytest.raises(ValueError, match="ring_radius must be >= 0"):
        RenderSettings(ring_radius=-1.0)


# ---------------------------------------------------------------- the window


@pytest.fixture
def window_renderer(renderer):
    """A renderer inside a context someone else made current, as the editor's viewport has: here, the session
    renderer's EGL context (a second EGL context in the process would break the first)."""
    renderer.context.make_current()
    window = FrameRenderer(64, 48, context=WindowContext(64, 48))
    yield window
    renderer.context.make_current()
    window.close()


@pytest.mark.parametrize("mode", ["full", "auto"])
def test_window_resized_to_1x1(window_renderer, mode):
    render_checked(window_renderer, "window 64x48", BASE, MODES[mode])
    window_renderer.resize(1, 1)
    frame = render_checked(window_renderer, "window 1x1", BASE, MODES[mode])
    assert frame.linear.shape == (1, 1, 3)
    inside = render_checked(
        window_renderer, "window 1x1, camera in the cloud", BASE, MODES[mode], camera=looking_from(CLOUD_CENTRE)
    )
    assert inside.linear.shape == (1, 1, 3)
    window_renderer.resize(64, 48)
    assert render_checked(window_renderer, "window back to 64x48", BASE, MODES[mode]).linear.shape == (48, 64, 3)


def test_a_minimised_window_s_0x0_frame_is_refused(window_renderer):
    """The viewport asks for at least 1x1 (app/viewport.py); the engine itself refuses 0x0 in words."""
    with pytest.raises(ValueError, match="framebuffer size must be positive, got 0x0"):
        FrameRenderer(0, 0)
    with pytest.raises(ValueError, match="framebuffer size must be positive, got 0x0"):
        window_renderer.resize(0, 0)


def test_a_refused_resize_leaves_the_renderer_usable(window_renderer):
    with pytest.raises(ValueError):
        window_renderer.resize(0, 0)
    assert render_checked(window_renderer, "after a refused resize", BASE).linear.shape == (48, 64, 3)
