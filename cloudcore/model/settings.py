"""How clouds are drawn: one settings object for the GUI, the command line and the benchmarks.

`mode` picks the representation: "full" draws every particle every frame (the
reference picture), "impostor" draws every cloud from a cached texture, "auto"
chooses per cloud, each frame, the representation predicted cheapest within
the tolerance (`cloudcore.lod.plan`, with the measured `cloudcore.lod.costs`),
crossfading over `transition_frames` when it changes, and the ring beyond
`ring_radius`.

Each field that is set from outside the engine carries an `Option` (its
command-line flag, help, and editor widget): `cloudcore.cli.settings_args`
makes the options and sweep names of `render`, `record` and `bench` from them,
and `app.panels.lod` the LOD panel's widgets, so a setting is named in one place.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, fields

MODES = ("auto", "full", "impostor")
#: the names of `cloudcore.lod.impostors.TRANSLATION_METRICS` (kept here so settings import no geometry)
TRANSLATION_METRICS = ("parallax", "centre")
#: how full-3D splats are composited (`cloudcore.light.volume_blending`)
BLENDINGS = ("plain", "volume")
#: where splats are chosen and sorted, the two ways `cloudcore.gl.measured_way` picks between by measurement
SPLAT_ORDER_WAYS = ("cpu", "gpu")
#: what composites full 3D's plain splats chosen on the GPU, the two ways `cloudcore.gl.measured_way` picks between
COMPOSITING_WAYS = ("raster", "compute")
#: the smallest fraction of the screen's resolution per axis the cloud pass may take (a texel for an 8x8 block;
#: `cloudcore.maths.depth_upsampling`)
LOWEST_SCALE = 0.125
#: where full-3D draws and impostor regenerations choose and order their particles (`cloudcore.gl.splats`; "auto":
#: `cloudcore.gl.measured_way`)
SPLAT_ORDERS = ("auto", *SPLAT_ORDER_WAYS)
#: what composites full 3D's plain splats chosen on the GPU: the raster, or a compute pass over screen tiles
#: binned on the GPU (`cloudcore.gl.tile_binning`); "auto": `cloudcore.gl.measured_way`, per mode
COMPOSITINGS = ("auto", *COMPOSITING_WAYS)
#: how the eye pass shades a Gaussian splat across its pixels (`cloudcore.light.splat_look`): one colour and the
#: kernel's opacity profile, or each pixel by the view ray's chord through the particle's sphere (Yusov 2014, 5.4)
PARTICLE_SHADINGS = ("per_particle", "per_pixel")
#: the largest amplitude of the detail noise: at 1 the noise takes a pixel's optical depth from 0 to twice its own
MAX_DETAIL_NOISE = 1.0
#: metres: the largest feature size of the detail noise (a cloud's size; beyond, the noise is no detail)
MAX_DETAIL_NOISE_SCALE_M = 10000.0


@dataclass(frozen=True)
class Option:
    """How a setting is named and shown outside the engine.

    `flag` is its command-line option; a setting that is on by default is
    spelled `--no-...` and turns it off.  `help` is one sentence saying what
    the setting does (for a switch, when on), for --help and the widget's
    tooltip.  `choices` are a string setting's values.  With
    a `label` the LOD panel shows it: a combo (choices), a checkbox (bool) or
    a slider over [`low`, `high`] showing `display` (a printf format), or
    `zero_display` at 0 where 0 means "off".
    """

    flag: str
    help: str
    choices: tuple[str, ...] = ()
    label: str | None = None
    low: float = 0.0
    high: float = 1.0
    display: str = ""
    zero_display: str = ""
    #: how the command line and sweeps read a value (None: as the default's type)
    parse: Callable[[str], object] | None = None

    @property
    def sweep_name(self) -> str:
        """The setting's name in `cloudview bench --sweep NAME=...`: the flag's words."""
        return self.flag.removeprefix("--").removeprefix("no-").replace("-", "_")


#: `cloud_resolution_scale`'s value that lets the plan choose the cloud pass's scale frame by frame
AUTO_SCALE = "auto"


def cloud_resolution_value(text: str) -> float | str:
    """A command-line or sweep value of `cloud_resolution_scale`: "auto", or a number; argparse names this function
    on refusal."""
    return AUTO_SCALE if text == AUTO_SCALE else float(text)


def _setting(default, **option):
    return field(default=default, metadata={"option": Option(**option)})


@dataclass(frozen=True)
class RenderSettings:
    mode: str = _setting(
        "auto",
        flag="--mode",
        help="how clouds are drawn: full 3D, impostors, or chosen per cloud by predicted error and cost",
        choices=MODES,
        label="Mode",
    )
    #: degrees of translation error past which an impostor is regenerated; see `translation_metric`.
    #: SkyWorks' default is 0.125 (0.9 of a pixel at 480 lines and 60 degrees).  1 saved little of the default
    #: flythrough's cloud pass for its error there, but on a cumulus field the project was not tuned on it cost
    #: its worst frame 5 dB (docs/journal.md#point-sprites-third-session)
    tolerance_deg: float = _setting(
        0.5,
        flag="--tolerance",
        help="an impostor is remade once its translation error passes this many degrees; by default the "
        "parallax between its near and far points (Harris), 0.125 about one pixel",
        label="Tolerance (deg)",
        high=5.0,
        display="%.3f",
    )
    #: "parallax": the angle between the rays to the impostor's near and far points (Harris, SkyWorks);
    #: "centre": the angle the eye has turned around the cloud's centre (stricter by about D / 2R)
    translation_metric: str = _setting(
        "parallax",
        flag="--translation-metric",
        help="parallax: the angle between the rays to the impostor's near and far points (Harris); "
        "centre: the angle turned around the cloud's centre",
        choices=TRANSLATION_METRICS,
        label="Translation error",
    )
    #: pixels: when > 0, the tolerance is this many pixels at the screen's centre instead of tolerance_deg
    tolerance_px: float = _setting(
        0.0, flag="--tolerance-px", help="impostor tolerance in pixels at the screen's centre; 0: use --tolerance"
    )
    #: metres: clouds wholly beyond this horizontal distance join Wang's ring of 8 impostors; inf: no ring
    ring_radius: float = _setting(
        4000.0, flag="--ring-radius", help="metres beyond which clouds join the impostor ring; inf for none"
    )
    #: impostor texture sides, powers of two
    impostor_min_size: int = _setting(
        16, flag="--impostor-min-size", help="smallest impostor texture side, a power of two"
    )
    impostor_max_size: int = _setting(
        512, flag="--impostor-max-size", help="largest impostor texture side, a power of two"
    )
    #: texels across the radius of a cloud's finest particle that an impostor texture must give; a finer
    #: texture only resamples smooth Gaussians, so none is made (0: the screen's resolution alone decides)
    impostor_detail_texels: float = _setting(
        2.0,
        flag="--detail-texels",
        help="an impostor texture is never finer than this many texels across the radius of its cloud's "
        "smallest particle; 0: the screen's resolution alone decides",
        label="Texels per particle",
        high=8.0,
        display="%.1f",
    )
    #: impostors remade per frame at most; those past their tolerance wait, the farthest past it first
    #: (0: no limit, every impostor past its tolerance is remade at once)
    regeneration_budget: int = _setting(
        0,
        flag="--regeneration-budget",
        help="impostors remade per frame at most, those farthest past the tolerance first; 0: no limit",
        label="Regeneration budget",
        high=32,
        display="%d",
        zero_display="no limit",
    )
    #: milliseconds the impostor updates and the cloud pass may take together, as the measured cost model
    #: predicts them; over it, regenerations wait (most urgent first) and the error drawn exceeds the
    #: tolerance by what the statistics report (0: no budget)
    frame_budget_ms: float = _setting(
        0.0,
        flag="--frame-budget",
        help="milliseconds for impostor updates and the cloud pass together, as the measured costs predict "
        "them; over it, regenerations wait, most urgent first, and the error drawn grows past the "
        "tolerance (the statistics say by how much); 0: none",
        label="Frame budget (ms)",
        high=200.0,
        display="%.0f ms",
        zero_display="none",
    )
    #: frames over which a cloud crossfades when auto mode changes its representation (no pop)
    transition_frames: int = _setting(
        6,
        flag="--transition-frames",
        help="frames of crossfade when auto mode moves a cloud between full 3D and its impostor",
        label="Transition (frames)",
        low=1,
        high=60,
        display="%d",
    )
    #: draw interpenetrating clouds as one unit (one impostor, one sort: `cloudcore.lod.units`); off, each
    #: cloud's impostor is sorted as a whole, Harris's approximation
    group_clouds: bool = _setting(
        True,
        flag="--no-group-clouds",
        help="draw interpenetrating clouds as one unit: one impostor, one far-to-near sort",
        label="Group interpenetrating clouds",
    )
    #: auto mode plans a group apart, its clouds each a unit of its own, while the eye moves and their impostors
    #: cost less than the group's (`cloudcore.lod.plan.choice.groups_cheaper_apart`); still, or with the eye in its
    #: sphere, a group is whole.  Side by side it saved clouds' time at a small cost in PSNR along the default
    #: flythrough and much more orbiting the default view, where the blobs of clouds are sorted whole while the eye
    #: moves (docs/journal.md#the-level-of-detail-by-error-and-cost)
    groups_apart_in_motion: bool = _setting(
        True,
        flag="--no-groups-apart-in-motion",
        help="auto mode: while the eye moves, draw a group of interpenetrating clouds as its clouds where that is "
        "cheaper (their impostors last longer); still, the group again",
        label="Groups apart in motion",
    )
    #: per axis: the screen impostor of a cloud the eye is inside has this fraction of the screen's pixels
    #: (Harris's quarter).  An eighth saved a little of the default flythrough's cloud pass, but under a
    #: stratocumulus deck, whose one unit's sphere holds the eye, it blurred its underside
    #: (docs/journal.md#point-sprites-third-session)
    inside_resolution_scale: float = _setting(
        0.25,
        flag="--inside-resolution",
        help="per axis, the fraction of the screen's resolution of the screen impostor of a cloud the eye is in",
        label="Screen impostor scale",
        low=0.05,
        high=1.0,
        display="%.3f",
    )
    #: per axis: the whole cloud pass (splats, impostors, ring panels, crossfades, screen impostors' composites) is
    #: drawn at this fraction of the screen's resolution and upsampled against the world's depth (Yusov 2014, 5.4;
    #: `cloudcore.maths.depth_upsampling`); 1 draws it at the screen's, as before; "auto": the plan chooses per frame
    #: between the screen's and `pricing.AUTO_CLOUD_SCALE` by their predicted cost (`choice.cloud_pass_scale`;
    #: full 3D, which prices nothing, draws at the screen's).  1 by default: in full 3D a quarter cut the frame to
    #: 0.17-0.77 within the tolerance, but auto mode already draws what costs fill at a reduced cost and on llvmpipe
    #: lost 14-22% of its frame to the pass's wait for the world's depth and its composite (docs/performance.md,
    #: "The cloud pass at a reduced resolution")
    cloud_resolution_scale: float | str = _setting(
        1.0,
        flag="--cloud-resolution",
        help="per axis, the fraction of the screen's resolution the cloud pass is drawn at, then upsampled against "
        "the world's depth; 1: the screen's; auto: chosen per frame by its predicted cost",
        label="Cloud pass scale",
        low=LOWEST_SCALE,
        high=1.0,
        display="%.3f",
        parse=cloud_resolution_value,
    )
    #: "per_particle": a splat is one colour, its opacity the kernel's profile (Harris); "per_pixel": each pixel of
    #: a splat by the view ray's chord through the particle's sphere, its opacity from the chord's optical depth
    #: and the sun's light by the depth into the particle toward the sun (Yusov 2014, 5.4;
    #: `cloudcore.light.splat_look`).  Per particle by default: per pixel is closer to the path-traced truth at
    #: realistic albedo, but on a software rasteriser it costs more than the frame gains in error, and the shipped
    #: scenes keep their pictures (docs/shading.md, "Per-pixel shading and detail noise")
    particle_shading: str = _setting(
        "per_particle",
        flag="--particle-shading",
        help="per_particle: one colour a splat; per_pixel: each pixel by the view ray's chord through the "
        "particle's sphere, lit by its depth into the particle toward the sun",
        choices=PARTICLE_SHADINGS,
        label="Particle shading",
    )
    #: the amplitude of 3D noise in each particle's own frame that modulates a splat's optical depth per pixel
    #: (Yusov 2014, 5.4 and his future work; `cloudcore.light.splat_look`); 0: off, today's picture
    detail_noise: float = _setting(
        0.0,
        flag="--detail-noise",
        help="the amplitude of the 3D noise that varies each splat's optical depth per pixel (0: none, 1: from "
        "none to twice its own)",
        label="Detail noise",
        high=MAX_DETAIL_NOISE,
        display="%.2f",
        zero_display="off",
    )
    #: metres: the detail noise's feature size (its lattice's spacing), a fraction of the particles' (25-60 m in
    #: the default scene)
    detail_noise_scale_m: float = _setting(
        20.0,
        flag="--detail-noise-scale",
        help="metres between the detail noise's lattice points: the size of its features",
        label="Detail noise scale (m)",
        low=1.0,
        high=200.0,
        display="%.0f",
    )
    #: the ring is rebuilt when the eye has moved this fraction of ring_radius horizontally / vertically (Wang's
    #: rule), or sooner, once its panels' translation error passes the tolerance (docs/lod.md, "Wang's ring")
    ring_rebuild_horizontal: float = 0.15
    ring_rebuild_vertical: float = 0.02
    #: degrees above and below the horizon the ring covers; clouds reaching beyond stay out of it
    ring_elevation_deg: float = 30.0
    #: frames over which a rebuilt ring crossfades in
    ring_fade_frames: int = 8
    #: split clouds into layers around the objects inside them (Harris 3.1.1); off, objects are drawn
    #: with the world and clouds are depth-tested against them (the naive picture, for comparison)
    split_objects: bool = True
    #: draw batches of plain splats as point sprites (one vertex per particle) where the picture is the
    #: same (`cloudcore.particles.point_sprites`); off, always as quads (for comparison:
    #: docs/journal.md#point-sprites-third-session)
    point_sprites: bool = _setting(
        True,
        flag="--no-point-sprites",
        help="draw plain splats as point sprites (one vertex instead of four) where the picture is the same",
        label="Point sprites",
    )
    #: multisample the world (terrain, objects) 4x: smooth ridge lines against the sky, for twice the world
    #: pass on llvmpipe (docs/performance.md, "The world pass: where its time goes")
    world_antialiasing: bool = _setting(
        False,
        flag="--world-antialiasing",
        help="multisample the terrain and objects 4x: smooth edges against the sky, for twice the world pass's time",
        label="Antialiased world",
    )
    #: under the physical sky, the air between the eye and the terrain, objects' ground and clouds
    #: (`cloudcore.light.air_between`, docs/atmosphere.md); off, everything is drawn as if the air were empty in
    #: front of it, as before (for comparison and its cost: `cloudview bench --suite world --cases aerial`)
    aerial_perspective: bool = _setting(
        True,
        flag="--no-aerial-perspective",
        help="under the physical sky, draw the terrain and the clouds through the air between them and the eye",
        label="Aerial perspective",
    )
    #: the clouds' shadows in the sun's (the first light's) beam: on the terrain and the objects, and on each other
    #: (`cloudcore.light.cloud_shadows`, docs/atmosphere.md); off, the sun reaches everything whole, as before
    cloud_shadows: bool = _setting(
        True,
        flag="--no-cloud-shadows",
        help="let the clouds shadow the terrain, the objects and one another in the sun's light",
        label="Cloud shadows",
    )
    #: under the physical sky with cloud shadows and aerial perspective, the air in the clouds' shadow scatters
    #: no sunlight toward the eye (`cloudcore.light.light_shafts`, docs/atmosphere.md#light-shafts); off, the air
    #: is lit whole, as before
    light_shafts: bool = _setting(
        True,
        flag="--no-light-shafts",
        help="darken the air in the clouds' shadows: shafts of sunlight between them",
        label="Light shafts",
    )
    #: "plain": premultiplied billboards (ONE, ONE_MINUS_SRC_ALPHA); "volume": Yusov's volume-aware
    #: blending (HPG 2014, 5.5), intersecting particles composited as volumes by a tiled compute pass
    #: where the GL has compute shaders (plain otherwise).  Plain by default: the goldens are its
    #: pictures, and volume costs more on llvmpipe (docs/shading.md, "Volume-aware blending")
    blending: str = _setting(
        "plain",
        flag="--blending",
        help="plain: splats blended as billboards; volume: intersecting splats composited as volumes "
        "(Yusov), full 3D only",
        choices=BLENDINGS,
        label="Blending",
    )

    #: "cpu": a draw's particles are chosen and sorted far to near in numpy and their order uploaded; "gpu":
    #: chosen, sorted and counted by compute shaders, drawn as quads by an indirect draw, so that the CPU's
    #: work for a draw does not grow with its particles; "auto": the one measured faster on this GL
    #: (`cloudcore.gl.measured_way`: on llvmpipe the CPU's, whose sort is 5-9 times faster, the frame 1.32)
    splat_order: str = _setting(
        "auto",
        flag="--splat-order",
        help="cpu: splats (full 3D and impostor regenerations) chosen and sorted far to near on the CPU; "
        "gpu: by compute shaders, drawn indirectly; auto: the one measured faster here (the CPU on llvmpipe)",
        choices=SPLAT_ORDERS,
        label="Splat order",
    )

    #: "raster": full 3D's splats drawn as quads and blended by the raster; "compute": those chosen on the GPU
    #: (`splat_order` "gpu") and plain, composited the same way by a compute pass over screen tiles binned on the
    #: GPU, for chips whose raster is a small part of them (docs/performance.md, "Compositing by compute"); "auto":
    #: the one measured faster here, per mode (the raster on llvmpipe, untried)
    compositing: str = _setting(
        "auto",
        flag="--compositing",
        help="raster: full-3D splats blended by the raster; compute: those sorted on the GPU composited by a "
        "compute pass over screen tiles instead (the same picture; faster where the raster is small); auto: the "
        "one measured faster here (the raster on llvmpipe)",
        choices=COMPOSITINGS,
        label="Compositing",
    )

    def __post_init__(self):
        problems = []
        if self.mode not in MODES:
            problems.append(f"mode must be one of {', '.join(MODES)}, got {self.mode!r}")
        if self.blending not in BLENDINGS:
            problems.append(f"blending must be one of {', '.join(BLENDINGS)}, got {self.blending!r}")
        if self.splat_order not in SPLAT_ORDERS:
            problems.append(f"splat_order must be one of {', '.join(SPLAT_ORDERS)}, got {self.splat_order!r}")
        if self.compositing not in COMPOSITINGS:
            problems.append(f"compositing must be one of {', '.join(COMPOSITINGS)}, got {self.compositing!r}")
        if not 0.0 <= self.tolerance_deg <= 180.0:
            problems.append(f"tolerance_deg must be within [0, 180], got {self.tolerance_deg}")
        if self.translation_metric not in TRANSLATION_METRICS:
            problems.append(
                f"translation_metric must be one of {', '.join(TRANSLATION_METRICS)}, got {self.translation_metric!r}"
            )
        if not 0.0 <= self.tolerance_px < math.inf:
            problems.append(f"tolerance_px must be >= 0 and finite (0: use tolerance_deg), got {self.tolerance_px}")
        if not (self.ring_radius >= 0.0):
            problems.append(f"ring_radius must be >= 0 metres (inf for no ring), got {self.ring_radius}")
        for name in ("impostor_min_size", "impostor_max_size"):
            size = getattr(self, name)
            if not (isinstance(size, int) and 1 <= size <= 8192 and size & (size - 1) == 0):
                problems.append(f"{name} must be a power of two within [1, 8192], got {size!r}")
        if not 0.0 <= self.impostor_detail_texels < math.inf:
            problems.append(f"impostor_detail_texels must be >= 0 and finite, got {self.impostor_detail_texels}")
        if not (isinstance(self.regeneration_budget, int) and self.regeneration_budget >= 0):
            problems.append(
                f"regeneration_budget must be an integer >= 0 (0: no limit), got {self.regeneration_budget!r}"
            )
        if not 0.0 <= self.frame_budget_ms < math.inf:
            problems.append(f"frame_budget_ms must be >= 0 and finite (0: no budget), got {self.frame_budget_ms}")
        if self.impostor_min_size > self.impostor_max_size:
            problems.append("impostor_min_size must not exceed impostor_max_size")
        if not (isinstance(self.transition_frames, int) and self.transition_frames >= 1):
            problems.append(f"transition_frames must be an integer >= 1, got {self.transition_frames!r}")
        if not 0.0 < self.inside_resolution_scale <= 1.0:
            problems.append(f"inside_resolution_scale must be within (0, 1], got {self.inside_resolution_scale}")
        scale = self.cloud_resolution_scale
        if scale != AUTO_SCALE and not (
            isinstance(scale, (int, float)) and not isinstance(scale, bool) and LOWEST_SCALE <= scale <= 1.0
        ):
            problems.append(
                f"cloud_resolution_scale must be {AUTO_SCALE!r} or within [{LOWEST_SCALE}, 1], got {scale!r}"
            )
        if self.particle_shading not in PARTICLE_SHADINGS:
            problems.append(
                f"particle_shading must be one of {', '.join(PARTICLE_SHADINGS)}, got {self.particle_shading!r}"
            )
        if not _number_within(self.detail_noise, 0.0, MAX_DETAIL_NOISE):
            problems.append(f"detail_noise must be within [0, {MAX_DETAIL_NOISE:g}], got {self.detail_noise!r}")
        if not (_number_within(self.detail_noise_scale_m, 0.0, MAX_DETAIL_NOISE_SCALE_M) and self.detail_noise_scale_m):
            problems.append(
                f"detail_noise_scale_m must be within (0, {MAX_DETAIL_NOISE_SCALE_M:g}] metres, "
                f"got {self.detail_noise_scale_m!r}"
            )
        if self.blending == "volume" and (self.particle_shading != "per_particle" or self.detail_noise):
            problems.append(
                "blending 'volume' composites splats of one colour: it takes neither per-pixel shading nor detail noise"
            )
        if not (self.ring_rebuild_horizontal > 0.0 and self.ring_rebuild_vertical > 0.0):
            problems.append("ring rebuild fractions must be > 0")
        if not 0.0 < self.ring_elevation_deg < 90.0:
            problems.append(f"ring_elevation_deg must be within (0, 90), got {self.ring_elevation_deg}")
        if not (isinstance(self.ring_fade_frames, int) and self.ring_fade_frames >= 1):
            problems.append(f"ring_fade_frames must be an integer >= 1, got {self.ring_fade_frames!r}")
        for name in (
            "split_objects",
            "group_clouds",
            "groups_apart_in_motion",
            "point_sprites",
            "world_antialiasing",
            "aerial_perspective",
            "cloud_shadows",
            "light_shafts",
        ):
            if not isinstance(getattr(self, name), bool):
                problems.append(f"{name} must be true or false, got {getattr(self, name)!r}")
        if problems:
            raise ValueError("; ".join(problems))

    @property
    def uses_ring(self) -> bool:
        return self.mode != "full" and math.isfinite(self.ring_radius)


def _number_within(value, low: float, high: float) -> bool:
    """Whether `value` is a real number (not a bool) within [low, high] (NaN is not)."""
    return isinstance(value, (int, float)) and not isinstance(value, bool) and low <= value <= high


def setting_options() -> dict[str, Option]:
    """{field name: its Option} of the settings set from outside the engine, in the fields' order."""
    return {f.name: f.metadata["option"] for f in fields(RenderSettings) if "option" in f.metadata}


#: every particle every frame: the reference picture the approximations are measured against
FULL_3D = RenderSettings(mode="full")
