"""The clouds a frame draws, kept between frames: the scene's own and its cloud field's for the eye, lit, carried
where the wind has them now and weighed by the field's blend weights; their LOD units, what the wind did to each,
and the keys their impostors and Wang's ring go stale by (pure numpy).

The renderer (`cloudcore.gl.frame.FrameRenderer`) holds one and asks it each frame (`prepare`); everything here is
made again only when what it came from changes (`cloudcore.runtime.derived.Derived`, or a source held beside what
was made from it), so a still scene costs a few comparisons a frame.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import time
from dataclasses import dataclass

import numpy as np

from cloudcore.artist.facing import CloudFacings
from cloudcore.artist.formation import formation_state
from cloudcore.artist.particle_styles import particle_styles
from cloudcore.field.shadow_cells import CellShadowing, casting_weights, cell_shadowing
from cloudcore.field.state import FieldFrame, FieldState
from cloudcore.field.weather import WeatherFieldState, update_weather_field, weather_drift
from cloudcore.light.ground_bounce import cloud_lights, ground_albedo_rgb
from cloudcore.light.illumination import IlluminationCache
from cloudcore.lod.units import LodUnits, lod_units
from cloudcore.model.scene import Camera, Lighting, Scene
from cloudcore.model.settings import RenderSettings
from cloudcore.particles.buffer import ParticleBuffer
from cloudcore.runtime.derived import Derived
from cloudcore.world.wind import (
    AirMotion,
    CloudMotion,
    field_speed,
    light_time,
    shape_change_bound_m,
    turbulent_offsets,
)


@dataclass(frozen=True)
class LitClouds:
    """The clouds' particle buffer (their light) and what is made with it."""

    particles: ParticleBuffer
    facings: CloudFacings  # the facing locks of Wang's sprites, following the eye
    #: per cloud, changes whenever that cloud's particle colours may have: its impostor is stale
    lighting_keys: tuple
    forming_clouds: tuple  # the clouds that form or dissipate, whose colours follow the clock


@dataclass(frozen=True)
class PreparedClouds:
    """A frame's clouds made ready to plan: the scene with its field's clouds for this eye after its own, their
    particles lit, carried where the wind has them now, and weighed."""

    scene: Scene
    particles: ParticleBuffer
    units: LodUnits
    motion: CloudMotion | None  # what the wind did to each cloud; None in still air
    fade_keys: tuple  # per cloud, the key of its blend weights (`FrameClouds._with_field`)
    illumination_ms: float  # spent lighting the clouds


class FrameClouds:
    """The clouds of the frames drawn, between frames; `prepare` makes a frame's."""

    def __init__(self, illumination: IlluminationCache):
        """`illumination` holds the clouds' precomputed light between frames (the editor's is filled by a worker
        in the background: `cloudcore.light.relighting`)."""
        self._illumination = illumination
        self.lit: Derived[LitClouds] = Derived(self._light_clouds)
        self._units: Derived[LodUnits] = Derived(
            lambda source, particles, authored: lod_units(particles, source[1], authored)
        )
        self._keys: Derived[tuple[tuple, tuple]] = Derived(self._keys_of)
        self._key_serial = 0
        #: the cloud field's cells made for the last eye, its particles' blend weights and every cloud's mean weight
        #: (None: no field)
        self.weather_state = WeatherFieldState()
        self._field_weights: np.ndarray | None = None
        self._cloud_weights: np.ndarray | None = None
        #: (what it was made from, how the field's clouds shadow one another): (None, None) without a field
        self._cell_shadowing: tuple[tuple | None, CellShadowing | None] = (None, None)
        self._air: AirMotion | None = None  # the wind applied to the authored clouds (None: still air)
        #: this frame's carried particles and units and the clouds' motion, and what they were made from
        self._carry_source, self._carry_made = None, None
        self._ring_drift = None  # (ring keys, clouds' drift steps, the keys with them) under wind

    @property
    def units(self) -> LodUnits:
        """The units of the clouds last prepared, where the wind had carried them."""
        return self._units.value if self._carry_made is None else self._carry_made[1]

    @property
    def particles(self) -> ParticleBuffer:
        """The particle buffer of the clouds last prepared, where the wind had carried it."""
        return self.lit.value.particles if self._carry_made is None else self._carry_made[0]

    @property
    def field_state(self) -> FieldState:
        """The cloud field's cells for the last eye under the weather in force, or coming during a change."""
        return self.weather_state.in_force

    def drawn_clouds(self, scene: Scene, lit_at: float) -> tuple:
        """The authored clouds of `scene` as a frame lit at `lit_at` draws them under its wind: their shapes then
        (`AirMotion.lit_clouds`), whose light the frame needs; the scene's own in still air."""
        air = self._air_motion(scene)
        return scene.clouds if air is None else air.lit_clouds(lit_at)

    def prepare(
        self,
        scene: Scene,
        camera: Camera,
        lighting: Lighting,
        lights,
        ambient,
        illumination_method: str,
        settings: RenderSettings,
        time_s: float,
        lit_at: float | None,
    ) -> PreparedClouds:
        """The frame's clouds at the scene clock `time_s` for the eye `camera`, lit by `lights` and `ambient` of
        `lighting` (with `settings.cloud_shadows`, the sun's light through the other clouds too), their light made
        for their shapes at `lit_at` (by default `wind.light_time`'s) and carried on to `time_s`."""
        authored_clouds = len(scene.clouds)
        air = self._air_motion(scene)
        if air is not None:  # the clouds as their light is made now: at rest, while the wind only carries them
            lit_at = light_time(air.wind, time_s) if lit_at is None else lit_at
            scene = dataclasses.replace(scene, clouds=air.lit_clouds(lit_at))
        field_carried = weather_drift(scene.wind, scene.cloud_field, scene.weather, time_s)
        scene, fade_keys = self._with_field(scene, camera, field_carried, time_s)
        # the clouds shadow one another: a field's cells pair by pair, made again for the clouds a new set of cells
        # reaches (`cloudcore.light.cell_shadows`)
        between_clouds = settings.cloud_shadows and (self._cell_shadowing[1] if scene.cloud_field is not None else True)
        # the ground's bounce follows the ground's colour and heights (`cloudcore.light.ground_bounce`)
        ground = scene.terrain if scene.shading.ground_bounce else None
        lights, ambient = cloud_lights(lights, ambient, scene.shading, ground_albedo_rgb(ground, lighting.air))
        start = time.perf_counter()
        relit = self.lit.follow(
            (scene.clouds, scene.shading, lighting, illumination_method, between_clouds, ground), lights, ambient
        )
        illumination_ms = 1e3 * (time.perf_counter() - start) if relit else 0.0
        # the units follow the particles' places and sizes, not their light: a relit scene keeps them
        self._units.follow((scene.clouds, settings.group_clouds), self.lit.value.particles, authored_clouds)
        particles, units, motion = self._carried(air, field_carried, time_s, lit_at)
        particles.weigh(self._field_weights)
        return PreparedClouds(scene, particles, units, motion, fade_keys, illumination_ms)

    def forming(self, scene: Scene, time_s: float) -> tuple:
        """The states at `time_s` of the prepared clouds that form or dissipate."""
        return tuple(formation_state(scene.clouds[index].formation, time_s) for index in self.lit.value.forming_clouds)

    def cloud_keys(self, scene: Scene, fade_keys: tuple, time_s: float, look: tuple = ()) -> tuple[tuple, tuple]:
        """(per cloud, what its colours are made from this frame: its lighting key, the splats' look other than
        plain (`cloudcore.light.splat_look.SplatLook.key`: its impostor and ring panels are made again when it
        changes), and as a forming or
        dissipating cloud's colours change with the clock and a field's cloud's with its blend weights, those
        (its impostor is stale meanwhile); the same less the blend weights, what Wang's ring goes stale by:
        they follow the eye's place, which its rebuild distance bounds (`plan_frame`'s `ring_keys`)).  The same
        tuples as the frame before while none changed: the plan then finds its ring's clouds unchanged at once
        (`cloudcore.lod.ring`), with no cloud looked at."""
        forming = tuple(zip(self.lit.value.forming_clouds, self.forming(scene, time_s)))
        self._keys.follow((self.lit.value.lighting_keys, fade_keys, forming, look))
        return self._keys.value

    def ring_keys_under_wind(self, ring_keys: tuple, motion: CloudMotion | None, settings: RenderSettings) -> tuple:
        """Wang's ring's panels follow their clouds' mean drift (`FramePlan.ring_shifts`), but the eye's place relative
        to the clouds moves the other way: a cloud's ring key changes each time the wind has carried it another
        rebuild distance (`ring_rebuild_horizontal` of `ring_radius`; the first at half of one), the bound Wang's
        ring keeps on the eye's own steps, and the ring is built again.  The same tuple while no cloud crossed one."""
        if motion is None or not math.isfinite(settings.ring_radius):
            return ring_keys
        # rounded, not floored: a drift across the wind of -1e-14 m is no step
        steps = np.rint(motion.drifts / (settings.ring_rebuild_horizontal * settings.ring_radius)).astype(np.int64)
        held = self._ring_drift
        if held is None or held[0] is not ring_keys or not np.array_equal(held[1], steps):
            keys = tuple((*key, tuple(step)) for key, step in zip(ring_keys, steps.tolist()))
            self._ring_drift = (ring_keys, steps, keys)
        return self._ring_drift[2]

    def unit_weights(self, units: list) -> np.ndarray:
        """The mean blend weight of the particles of each unit's members (tuples of cloud indices) of `units`."""
        if self._cloud_weights is None or not units:
            return np.ones(len(units))
        clouds = np.fromiter(itertools.chain.from_iterable(units), dtype=np.int64)
        firsts = np.cumsum([0] + [len(members) for members in units[:-1]])
        counts = np.diff(self.lit.value.particles.cloud_starts)[clouds]
        particles = np.add.reduceat(counts, firsts)
        weighted = np.add.reduceat(self._cloud_weights[clouds] * counts, firsts)
        return np.divide(weighted, particles, out=np.ones(len(units)), where=particles > 0)

    def _with_field(self, scene: Scene, camera: Camera, carried: np.ndarray, time_s: float) -> tuple[Scene, tuple]:
        """The scene with its cloud field's clouds for this eye after its own (`cloudcore.field.state`), and
        per cloud the key of its blend weights; the field's weights are held for the particle buffer.  The field's
        grid has drifted `carried` (3,) metres with the wind: its cells are made and weighed for the eye's place
        relative to the air, where the particle buffer's carry (`_carried`) then moves them."""
        if scene.cloud_field is None:
            self.weather_state, self._field_weights, self._cloud_weights = WeatherFieldState(), None, None
            self._cell_shadowing = (None, None)
            return scene, (1.0,) * len(scene.clouds)
        eye_in_air = np.asarray(camera.position, dtype=np.float64) - carried
        frame, self.weather_state = update_weather_field(
            scene.cloud_field, scene.weather, time_s, eye_in_air, self.weather_state
        )
        authored = scene.particle_count
        self._field_weights = np.concatenate([np.ones(authored), frame.weights])
        self._cloud_weights = np.concatenate([np.ones(len(scene.clouds)), frame.mean_weights])
        self._follow_cells(len(scene.clouds), authored, frame)
        return (
            dataclasses.replace(scene, clouds=scene.clouds + frame.clouds),
            (1.0,) * len(scene.clouds) + frame.fade_keys,
        )

    def _follow_cells(self, authored_clouds: int, authored_particles: int, frame: FieldFrame) -> None:
        """Make how the field's clouds shadow one another (`cell_shadowing`) again when its cells changed: the
        weather's parts' cells and places, by identity (an unchanged part is the same object); its particles casting
        as in that `frame` (the field's clouds' blend weights' steps, `casting_weights`: a cell entering at weight 0
        casts nothing, and the shadows fade in and out with the cells at the frames where cells change), the
        authored clouds' wholly."""
        state = self.weather_state
        source = (authored_clouds, state.places, state.leading, [p.cells for p in state.parts])
        held = self._cell_shadowing[0]
        if held is None or held[:3] != source[:3] or any(a is not b for a, b in zip(held[3], source[3], strict=True)):
            casting = np.concatenate(
                [np.ones(authored_particles), casting_weights(frame.mean_weights, frame.cloud_starts)]
            )
            shadowing = cell_shadowing(authored_clouds, state.parts, state.places, state.leading, casting)
            self._cell_shadowing = (source, shadowing)

    def _air_motion(self, scene: Scene) -> AirMotion | None:
        """The wind applied to the scene's authored clouds (`cloudcore.world.wind.AirMotion`), made again for other
        clouds or another wind; None in still air."""
        if scene.wind is None:
            self._air = None
        elif self._air is None or self._air.wind != scene.wind or self._air.clouds is not scene.clouds:
            self._air = AirMotion(scene.wind, scene.clouds)
        return self._air

    def _carried(
        self, air: AirMotion | None, field_carried: np.ndarray, time_s: float, lit_at: float | None
    ) -> tuple[ParticleBuffer, LodUnits, CloudMotion | None]:
        """(the particle buffer, the units, what the wind did to each cloud) at `time_s`: the buffer whose light was
        made for the clouds' shapes at `lit_at` (`AirMotion.lit_clouds`) with every particle carried on to its place
        now, and the units with it (the same arrays moved: no loop over clouds), the authored clouds by `air`, a
        field's by its grid's drift `field_carried` and the turbulence (`air` is None only in still air: the buffer and
        units themselves)."""
        lit, units = self.lit.value.particles, self._units.value
        if air is None:
            self._carry_source = self._carry_made = None
            return lit, units, None
        source = (lit, units, air, time_s, lit_at, tuple(field_carried))
        held = self._carry_source
        if held is not None and all(a is b for a, b in zip(held[:3], source[:3])) and held[3:] == source[3:]:
            return self._carry_made
        authored = len(air.clouds)
        field_clouds = len(lit.cloud_starts) - 1 - authored
        field_drifts = np.tile(field_carried, (field_clouds, 1))
        field_speeds = np.tile(field_speed(air.wind, self.field_state.field, time_s), (field_clouds, 1))
        # a field's particles swirl by the same turbulence as the authored clouds' about their places in the drifting
        # grid; their light stays the cells' at rest (docs/lod.md, "Clouds that move with the wind")
        field_rest = lit.centres[int(lit.cloud_starts[authored]) :]
        offsets = np.concatenate(
            [air.carry(time_s, lit_at), field_carried + turbulent_offsets(air.wind, field_rest, time_s)]
        )
        drifts = np.concatenate([air.drifts(time_s), field_drifts])
        # the authored clouds' light was made where they were at `lit_at`: their buffer carries them on from there
        shifts = np.concatenate([air.drifts(time_s) - air.drifts(lit_at), field_drifts])
        grown = shape_change_bound_m(air.wind, math.inf)
        self._carry_source = source
        self._carry_made = (
            lit.carried(offsets, shifts, grown),
            units.moved(shifts, grown),
            CloudMotion(drifts, time_s, air.wind, np.concatenate([air.speeds(time_s), field_speeds])),
        )
        return self._carry_made

    def _light_clouds(self, source: tuple, lights, ambient) -> LitClouds:
        """The clouds' particle buffer (their light) for `source` (the clouds, shading, lighting, light pass method,
        whether the clouds shadow one another), each cloud's lighting key kept from the last where its light is
        the same."""
        clouds, shading, lighting, illumination_method, between_clouds, ground = source
        particles = ParticleBuffer(
            clouds,
            shading,
            lights,
            ambient,
            illumination_method,
            self._illumination,
            particle_styles(clouds, lighting),
            between_clouds=between_clouds,
            ground=ground,
        )
        old = self.lit.value
        # a field's new cells shadow anew (another `CellShadowing`): the keys stay where the light stays
        same_lighting = old is not None and self.lit.source[1:4] == source[1:4]
        same_lighting = same_lighting and (self.lit.source[4] is False) == (between_clouds is False)
        same_lighting = same_lighting and self.lit.source[5] == source[5]
        # by identity, not place: a cloud field's clouds that stay keep their keys when others come and go, unless
        # the light reaching them changed (the clouds shadow one another: one moved, another's shadow moves)
        held = (
            {
                id(cloud): (key, old.particles.incident[start:stop])
                for cloud, key, start, stop in zip(
                    self.lit.source[0],
                    old.lighting_keys,
                    old.particles.cloud_starts[:-1],
                    old.particles.cloud_starts[1:],
                )
            }
            if same_lighting
            else {}
        )
        starts = particles.cloud_starts
        lighting_keys = tuple(
            key
            if (key := _held_key(held.get(id(cloud)), particles.incident[start:stop])) is not None
            else self._next_key()
            for cloud, start, stop in zip(clouds, starts[:-1], starts[1:])
        )
        forming = tuple(index for index, cloud in enumerate(clouds) if cloud.formation is not None)
        return LitClouds(particles, CloudFacings(particles), lighting_keys, forming)

    def _keys_of(self, source: tuple) -> tuple[tuple, tuple]:
        """`cloud_keys`' pair made from its source (the lighting keys, the fade keys, the forming clouds' states)."""
        lighting_keys, fade_keys, forming, look = source
        states = dict(forming)
        colours = tuple((key, states.get(index), *look) for index, key in enumerate(lighting_keys))
        held = () if self._keys.value is None else self._keys.value[1]
        return (
            tuple((*colour, fade) for colour, fade in zip(colours, fade_keys)),  # unformed: state None
            held if colours == held else colours,  # only blend weights changed: the ring's keys are as they were
        )

    def _next_key(self) -> int:
        self._key_serial += 1
        return self._key_serial


def _held_key(held, incident: np.ndarray):
    """A cloud's lighting key from before (`held`: (key, the light that reached its particles then)) while the
    light reaching it is the same, else None."""
    return held[0] if held is not None and np.array_equal(held[1], incident) else None
