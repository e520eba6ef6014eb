"""A whole frame: prepare, plan, world pass, impostor updates, cloud pass, statistics; read back to 8-bit sRGB.

Everything is composed in linear light in a float target; the one transfer to
sRGB happens on read-back.  `FrameRenderer` keeps its context, GL passes,
terrain and precomputed cloud illumination between frames, each made again
only when what it came from changes (`cloudcore.gl.derived`; a scene's cloud
field adds its clouds for the eye after the scene's own first:
`cloudcore.field.state`, whose state it holds too); what the level of detail
carries from frame to frame (impostor cache, ring, representations, the
fitted costs) is the pure `cloudcore.lod.plan.LodState` it holds.  A frame's
recipe (`FrameRenderer._draw_frame`):

1. prepare: the scene as the weather, the wind and the field have it now, its
   resources in step with it, its particles lit and carried;
2. plan: `cloudcore.lod.plan.plan_frame` decides, and "auto" ways resolve;
3. the passes, timed: the world (terrain depth and colour over the sky, and
   the objects that are not inside a drawn cloud), the impostors and ring
   segment the plan regenerates, and the cloud pass
   (`cloudcore.gl.draw.CloudPass`: each draw item by its kind's executor);
4. observe: the passes' times fold into the state's cost fit and the ways'
   measurements;
5. the frame's statistics.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import os
import platform
import time
from dataclasses import dataclass

import numpy as np
from OpenGL import GL

from cloudcore.artist.facing import CloudFacings
from cloudcore.artist.formation import formation_state
from cloudcore.artist.particle_styles import particle_styles
from cloudcore.camera import NEAR_PLANE_M, frustum_planes, projection_matrix, view_matrix
from cloudcore.colour import linear_to_srgb8
from cloudcore.field.state import FieldState
from cloudcore.gl.context import HeadlessContext, WindowContext, check_frame_size
from cloudcore.gl.derived import Derived
from cloudcore.gl.draw import CloudPass, CloudPassFrame, DrawCounts, PassTools
from cloudcore.gl.impostor_store import ImpostorStore
from cloudcore.gl.light_shafts import LightShaftPass
from cloudcore.gl.objects import ObjectPass
from cloudcore.gl.pass_clock import PassClock
from cloudcore.gl.programs import build_program
from cloudcore.gl.quads import QuadPass
from cloudcore.gl.reduced_clouds import ReducedClouds
from cloudcore.gl.shadow_map import CloudShadowMap
from cloudcore.gl.splats import SplatPass
from cloudcore.gl.targets import TextureTarget
from cloudcore.gl.volume_blending import GpuFeatures, VolumeBlendingPass
from cloudcore.gl.world import WorldPass
from cloudcore.light.air_between import air_between
from cloudcore.light.cloud_shadows import FIELD_MAP_RESOLUTION, MAP_RESOLUTION, PREVIEW_MAP_RESOLUTION
from cloudcore.light.illumination import IlluminationCache, shadowing_sun
from cloudcore.light.lighting import scene_lights
from cloudcore.light.live_air import LiveAir
from cloudcore.light.relighting import PREVIEW_METHOD
from cloudcore.light.sky_background import SkyBackground, scene_sky
from cloudcore.light.terrain_light import terrain_light
from cloudcore.lod.costs import CostEstimator, CostModel, remember_fit, remembered_prior
from cloudcore.lod.plan import FramePlan, LodState, plan_frame
from cloudcore.lod.units import LodUnits, lod_units
from cloudcore.measure.frame_stats import FrameStats
from cloudcore.measure.overdraw import Overdraw, overdraw_statistics
from cloudcore.measured_way import COMPOSITING_WAYS, MeasuredWay
from cloudcore.particles.buffer import ParticleBuffer
from cloudcore.scene import Camera, Lighting, Scene
from cloudcore.settings import FULL_3D, RenderSettings
from cloudcore.splat_coverage import analytic_overdraw
from cloudcore.weather import WeatherFieldState, update_weather_field, weather_drift
from cloudcore.wind import (
    AirMotion,
    CloudMotion,
    field_speed,
    light_time,
    reshapes,
    shape_change_bound_m,
    turbulent_offsets,
)


@dataclass(frozen=True)
class _Asked:
    """What `FrameRenderer.render` was asked to draw (its arguments but the read-back)."""

    scene: Scene
    time_of_day: float | None
    camera: Camera | None
    illumination_method: str
    settings: RenderSettings
    time_s: float
    costs: CostModel | None
    lit_at: float | None


@dataclass(frozen=True)
class _LitClouds:
    """The clouds' particle buffer (their light) and what is made with it."""

    particles: ParticleBuffer
    facings: CloudFacings  # the facing locks of Wang's sprites, following the eye
    #: per cloud, changes whenever that cloud's particle colours may have: its impostor is stale
    lighting_keys: tuple
    forming_clouds: tuple  # the clouds that form or dissipate, whose colours follow the clock


@dataclass(frozen=True)
class _FrameScene:
    """A frame's scene made ready to plan: its clouds (a cloud field's for this eye after its own) lit, carried
    where the wind has them now, and weighed."""

    scene: Scene
    lighting: Lighting
    camera: Camera
    particles: ParticleBuffer
    units: LodUnits
    motion: CloudMotion | None  # what the wind did to each cloud; None in still air
    fade_keys: tuple  # per cloud, the key of its blend weights (`_with_field`)
    illumination_ms: float  # spent lighting the clouds and making their shadows' map


class FrameRenderer:
    """Renders scenes headlessly at a fixed size; use as a context manager or call close()."""

    def __init__(
        self,
        width: int,
        height: int,
        context=None,
        illumination: IlluminationCache | None = None,
        remember_costs: bool = False,
        air: LiveAir | None = None,
    ):
        """A headless renderer, or with `context` (a `WindowContext`) one inside the current window.

        `illumination` holds the clouds' precomputed light between frames; the editor passes one
        that a worker fills in the background (`cloudcore.light.relighting`).  With `remember_costs`, auto
        mode's cost model starts from the one the last such renderer on this machine and GL fitted, and the
        one fitted here is kept for the next when it closes (`cloudcore.lod.costs.remembered_prior`): the
        editor and the command line; the tests and benchmarks start from the same prior every time.

        `air`: the editor's, which gives a coarse aerial-perspective volume and the nearest altitude's sky while
        the exact ones for a new altitude are built in the background (`cloudcore.light.live_air`); without it a
        frame waits for the exact ones."""
        self.context = context if context is not None else HeadlessContext(width, height)
        self.context.make_current()
        self._splats = SplatPass()
        self._clock = PassClock()
        self._volume = VolumeBlendingPass()
        self._quads = QuadPass()
        self._impostors = ImpostorStore(self._splats)
        self._cloud_pass = CloudPass(PassTools(self._splats, self._quads, self._volume, self._impostors))
        #: what is made from the scene, each in step with its source: the world pass (terrain, lighting), the
        #: objects' pass, the clouds' light, the LOD units
        self._world: Derived[WorldPass] = Derived(self._make_world, WorldPass.close)
        self._objects: Derived[ObjectPass | None] = Derived(self._make_objects, ObjectPass.close)
        self._lit: Derived[_LitClouds] = Derived(self._light_clouds)
        self._units: Derived[LodUnits] = Derived(
            lambda source, particles, authored: lod_units(particles, source[1], authored)
        )
        #: the clouds' transmittance map, and this frame's: None where the clouds shadow nothing
        self.shadow_map = CloudShadowMap()
        self._shadows: CloudShadowMap | None = None
        self._illumination = illumination if illumination is not None else IlluminationCache()
        self._air_for = air if air is not None else air_between
        self._sky_for = air.sky_seen_from if air is not None else SkyBackground.seen_from
        self._keys: Derived[tuple[tuple, tuple]] = Derived(self._keys_of)
        self._key_serial = 0
        #: the level of detail's state between frames (impostor cache, ring, representations, costs)
        self.lod_state = LodState()
        self._remember_costs = remember_costs
        if remember_costs:
            prior = remembered_prior(self._machine)
            if prior is not None:
                self.lod_state = LodState(costs=CostEstimator(prior))
        self.splat_order = MeasuredWay()  # where draws and regenerations sort, measured (settings' "auto")
        #: per mode, what composites the GPU's plain full-3D splats, measured (settings' "auto"): on the H200 the
        #: compute pass won in full 3D and lost in auto mode, whose full-3D draws are a few near clouds
        self.compositing: dict[str, MeasuredWay] = {}
        #: the cloud field's cells made for the last eye, its particles' blend weights and every cloud's mean weight
        #: (None: no field)
        self.weather_state = WeatherFieldState()
        self._field_weights: np.ndarray | None = None
        self._cloud_weights: np.ndarray | None = None
        self._air: AirMotion | None = None  # the wind applied to the authored clouds (None: still air)
        #: this frame's carried particles and units and the clouds' motion, and what they were made from
        self._carry_source, self._carry_made = None, None
        self._ring_drift = None  # (ring keys, clouds' drift steps, the keys with them) under wind
        self._shadow_source = (None, MAP_RESOLUTION)  # the sun and the size of the clouds' transmittance map
        self._overdraw_target = None
        self._display = None  # (RGBA8 target, program): the frame in sRGB for the editor
        self.last_plan: FramePlan | None = None

    @property
    def units(self) -> LodUnits:
        """The units (clouds, or groups of interpenetrating clouds) of the scene last rendered, where the wind
        had carried them; a frame may plan some groups apart (`FramePlan.units`)."""
        return self._units.value if self._carry_made is None else self._carry_made[1]

    @property
    def field_state(self) -> FieldState:
        """The cloud field's cells for the last eye under the weather in force, or coming during a change."""
        return self.weather_state.in_force

    @property
    def particles(self) -> ParticleBuffer:
        """The particle buffer of the scene last rendered, where the wind had carried it."""
        return self._lit.value.particles if self._carry_made is None else self._carry_made[0]

    @property
    def light_shafts(self) -> LightShaftPass | None:
        """The world pass's light shafts, once a frame has drawn them (tests read their march)."""
        return None if self._world.value is None else self._world.value.light_shafts

    @property
    def reduced_clouds(self) -> ReducedClouds | None:
        """The reduced cloud pass, once a frame has drawn one (tests read what it laid over the screen)."""
        return self._cloud_pass.reduced

    @property
    def volume_features(self) -> GpuFeatures:
        """What this GL offers volume-aware blending."""
        return self._volume.features

    @property
    def size(self) -> tuple[int, int]:
        return self.context.width, self.context.height

    def render(
        self,
        scene: Scene,
        *,
        time_of_day: float | None = None,
        camera: Camera | None = None,
        illumination_method: str = "exact",
        settings: RenderSettings = RenderSettings(),
        time_s: float = 0.0,
        read_back: bool = True,
        costs: CostModel | None = None,
        lit_at: float | None = None,
    ) -> tuple[np.ndarray | None, FrameStats]:
        """(sRGB uint8 (height, width, 3), stats); `time_of_day` and `camera` override the scene's.

        Auto mode prices its choices with the cost model fitted to the frames rendered so far, or
        with `costs` when given (a pinned model: tests, comparisons across machines).

        `time_s` is the scene clock, in the time of the objects' path keys and of the clouds' formations.

        With `read_back=False` the image stays on the GPU (None is returned in its place): the
        editor shows it through `display_texture`.

        A frame one of whose draws composited by compute had more tile pairs than the GPU had room for is
        drawn twice (`FrameStats.drawn_again`; `cloudcore.gl.tile_binning`).

        `lit_at`: the scene time whose shapes of the clouds a wind reshapes their light is made for, carried on
        to `time_s` (`drawn_clouds`); by default `wind.light_time`'s, the frame waiting for it.  The editor
        passes the last period's while its relighting worker lights the new one.
        """
        asked = _Asked(scene, time_of_day, camera, illumination_method, settings, time_s, costs, lit_at)
        stats = self._draw_frame(asked)
        if self._volume.settle():
            # a draw composited by compute had more tile pairs than the room the GPU had for them, and lost its
            # nearest splats: drawn again, each draw's pairs counted first (`cloudcore.gl.tile_binning`)
            first = stats
            stats = self._draw_frame(asked)
            self._volume.settle()
            stats = dataclasses.replace(
                stats, frame_ms=first.frame_ms + stats.frame_ms, cpu_ms=first.cpu_ms + stats.cpu_ms, drawn_again=True
            )
        return (linear_to_srgb8(self.context.read_linear_rgb()) if read_back else None), stats

    def drawn_clouds(self, scene: Scene, lit_at: float) -> tuple:
        """The authored clouds of `scene` as a frame lit at `lit_at` draws them under its wind: their shapes then
        (`AirMotion.lit_clouds`), whose light the frame needs; the scene's own in still air."""
        air = self._air_motion(scene)
        return scene.clouds if air is None else air.lit_clouds(lit_at)

    def _draw_frame(self, asked: _Asked) -> FrameStats:
        """`render`'s frame, left in the render target: prepare, plan, the passes, observe, statistics."""
        self.context.make_current()  # several renderers may share a thread (the benchmarks take turns)
        settings, time_s = asked.settings, asked.time_s
        ready = self._prepare(asked)
        planning_started = time.perf_counter()
        frame = self._plan(ready, settings, time_s, asked.costs)
        before_passes_ms = 1e3 * (time.perf_counter() - planning_started)
        self._splats.particles_as_points = 0  # the passes' draws count theirs
        clock = self._clock
        with clock.frame():
            with clock.timed("world"):
                self._draw_world(frame)
            # the world pass uploaded the air for this eye: the ring's segments and the cloud pass's splats take it
            self._splats.air = None if frame.air is None else frame.air[0]
            with clock.timed("impostor updates"):
                rendered = self._impostors.update(
                    frame.plan, frame.particles, settings, time_s, frame.splat_order, self._unit_weights
                )
            with clock.timed("clouds"):
                self.context.bind_target()
                drawn = self._cloud_pass.draw(frame)
        drawn_by_gpu, rendered_by_gpu = self._splats.take_selected()
        self._observe(
            frame, drawn.compositable, drawn.particles + drawn_by_gpu + rendered + rendered_by_gpu, before_passes_ms
        )
        return self._statistics(
            frame, ready.illumination_ms, before_passes_ms, drawn, drawn_by_gpu, rendered + rendered_by_gpu
        )

    def _prepare(self, asked: _Asked) -> _FrameScene:
        """The frame's scene made ready (`_FrameScene`), and every resource made from it in step with it."""
        scene, time_of_day, camera, lit_at = asked.scene, asked.time_of_day, asked.camera, asked.lit_at
        settings, time_s = asked.settings, asked.time_s
        lighting = (
            scene.lighting if time_of_day is None else dataclasses.replace(scene.lighting, time_of_day=time_of_day)
        )
        camera = scene.camera if camera is None else camera
        authored_clouds = len(scene.clouds)
        air = self._air_motion(scene)
        if air is not None:  # the clouds as their light is made now: at rest, while the wind only carries them
            lit_at = light_time(air.wind, time_s) if lit_at is None else lit_at
            scene = dataclasses.replace(scene, clouds=air.lit_clouds(lit_at))
        field_carried = weather_drift(scene.wind, scene.cloud_field, scene.weather, time_s)
        scene, fade_keys = self._with_field(scene, camera, field_carried, time_s)
        illumination_ms = self._follow_scene(scene, lighting, asked.illumination_method, settings.cloud_shadows)
        # the units follow the particles' places and sizes, not their light: a relit scene keeps them
        self._units.follow((scene.clouds, settings.group_clouds), self._lit.value.particles, authored_clouds)
        particles, units, motion = self._carried(air, field_carried, time_s, lit_at)
        particles.weigh(self._field_weights)
        illumination_ms += self._update_shadows(scene, particles, motion, time_s, fade_keys)
        return _FrameScene(scene, lighting, camera, particles, units, motion, fade_keys, illumination_ms)

    def _plan(self, ready: _FrameScene, settings: RenderSettings, time_s: float, costs) -> CloudPassFrame:
        """Plan the frame (`plan_frame`), resolve its "auto" ways, and turn Wang's sprites to the eye; what the
        cloud pass's draws share."""
        objects = self._objects.value
        poses = objects.poses(time_s) if objects is not None else ()
        camera, particles = ready.camera, ready.particles
        starts = particles.cloud_starts
        cloud_keys, ring_keys = self._cloud_keys(ready.scene, ready.fade_keys, time_s)
        ring_keys = self._ring_keys_under_wind(ring_keys, ready.motion, settings)
        plan = plan_frame(
            ready.units,
            camera,
            self.size,
            settings,
            self.lod_state,
            cloud_keys,
            poses,
            lambda cloud: particles.centres[starts[cloud] : starts[cloud + 1]],
            costs,
            lambda cloud: (
                particles.centres[starts[cloud] : starts[cloud + 1]],
                particles.radii[starts[cloud] : starts[cloud + 1]],
            ),
            ring_keys,
            ready.motion,
        )
        self.last_plan = plan
        view = view_matrix(camera)
        projection = projection_matrix(camera.fov_y_deg, self.context.width / self.context.height)
        # in the editor's context the GUI leaves its scissor rectangle on, which would clip our targets
        GL.glDisable(GL.GL_SCISSOR_TEST)
        for start, facing in self._lit.value.facings.update(camera.position, particles):
            self._splats.update_facing(particles, start, facing)
        gl_renderer = self._volume.features.renderer
        compositing = self.compositing.get(settings.mode, MeasuredWay(COMPOSITING_WAYS))
        air = self._world.value.air_volume if settings.aerial_perspective else None
        view_projection = projection @ view
        return CloudPassFrame(
            plan,
            settings,
            particles,
            camera,
            view,
            projection,
            view_projection,
            frustum_planes(view_projection),
            poses,
            time_s,
            self.splat_order.way(settings.splat_order, gl_renderer),
            compositing.way(settings.compositing, gl_renderer),
            None if air is None else (air, np.asarray(camera.position, float)),
            self.context,
            objects,
            self._shadows,
            self._unit_weights,
        )

    def _draw_world(self, frame: CloudPassFrame) -> None:
        """The world pass: terrain and sky, and the objects outside the clouds the plan splits."""
        settings = frame.settings
        world = self._world.value
        world.draw(
            self.context,
            frame.camera,
            frame.view,
            frame.projection,
            antialiased=settings.world_antialiasing,
            through_air=settings.aerial_perspective,
            shadows=self._shadows,
            light_shafts=settings.light_shafts,
        )
        if frame.plan.objects_with_world:
            frame.objects.draw(
                self.context,
                frame.camera,
                frame.poses,
                frame.plan.objects_with_world,
                write_depth=True,
                antialiased=settings.world_antialiasing,
                air=world.air_volume if settings.aerial_perspective else None,
                shadows=self._shadows,
            )

    def _observe(self, frame: CloudPassFrame, compositable: int, particles: int, plan_ms: float) -> None:
        """Fold the timed passes into the plan's cost fit, and into the measured ways' choices: the particles
        drawn and rendered into impostors, and those of draws either compositing way could composite; auto mode's
        choice of a frame's way counts the plan's `plan_ms` too."""
        updates, clouds = (self._clock.times[name] for name in ("impostor updates", "clouds"))
        plan, mode = frame.plan, frame.settings.mode
        self.lod_state = plan.state.measured(
            [(plan.update_work, updates.wall_ms), (plan.cloud_work, clouds.wall_ms)], fit=plan.priced, plan_ms=plan_ms
        )
        self.splat_order = self.splat_order.observe(frame.splat_order, updates.wall_ms + clouds.wall_ms, particles)
        compositing = self.compositing.get(mode, MeasuredWay(COMPOSITING_WAYS))
        self.compositing[mode] = compositing.observe(frame.compositing, clouds.wall_ms, compositable)

    def _statistics(
        self,
        frame: CloudPassFrame,
        illumination_ms: float,
        before_passes_ms: float,
        drawn: DrawCounts,
        drawn_by_gpu: int,
        rendered: int,
    ) -> FrameStats:
        """The frame's statistics: the plan's, the passes' times, what they drew."""
        plan = frame.plan
        world, updates, clouds = (self._clock.times[name] for name in ("world", "impostor updates", "clouds"))
        return FrameStats(
            plan=plan.stats(),
            illumination_ms=illumination_ms,
            frame_ms=before_passes_ms + world.wall_ms + updates.wall_ms + clouds.wall_ms,
            plan_ms=before_passes_ms,
            world_ms=world.wall_ms,
            impostor_update_ms=updates.wall_ms,
            cloud_ms=clouds.wall_ms,
            cpu_ms=before_passes_ms + world.cpu_ms + updates.cpu_ms + clouds.cpu_ms,
            world_gpu_ms=world.gpu_ms,
            impostor_update_gpu_ms=updates.gpu_ms,
            cloud_gpu_ms=clouds.gpu_ms,
            particles_drawn=drawn.particles + drawn_by_gpu,
            particles_as_points=self._splats.particles_as_points,
            particles_as_volumes=drawn.as_volumes,
            splat_order=frame.splat_order,
            compositing=frame.compositing if drawn.compositable else "",
            particles_to_impostors=rendered,
            clouds_drawn=sum(len(plan.clouds[i].members) for i in plan.draw_order),
            texture_bytes=self.texture_bytes,
        )

    def display_texture(self) -> int:
        """An RGBA8 texture holding the last frame in sRGB (rows bottom first, as GL stores them).

        Leaves the window's framebuffer bound.
        """
        if self._display is None:
            self._display = (TextureTarget(*self.size, GL.GL_RGBA8), build_program("present", vertex="world"))
        target, program = self._display
        target.bind_cleared()
        GL.glUseProgram(program)
        GL.glActiveTexture(GL.GL_TEXTURE0)
        GL.glBindTexture(GL.GL_TEXTURE_2D, self.context.colour_texture)
        GL.glDisable(GL.GL_BLEND)
        GL.glDisable(GL.GL_DEPTH_TEST)
        GL.glBindVertexArray(self._quads.vertex_array)
        GL.glDrawArrays(GL.GL_TRIANGLES, 0, 3)
        GL.glBindVertexArray(0)
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, 0)  # the window's own framebuffer, for the GUI to draw on
        return target.texture

    def read_display(self) -> np.ndarray:
        """The last `display_texture` as 8-bit RGB, top row first (what the editor showed)."""
        pixels = self._display[0].read()
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, 0)
        return np.rint(pixels[..., :3] * 255.0).astype(np.uint8)

    def resize(self, width: int, height: int) -> None:
        """New frame size for a window renderer; cached shading and impostors are kept."""
        if (width, height) == self.size:
            return
        if not isinstance(self.context, WindowContext):
            raise TypeError("a headless renderer has a fixed size; make a new one")
        check_frame_size(width, height)  # before anything is closed: a refused size leaves the renderer as it was
        self._close_screen_targets()
        self.context.close()
        self.context = WindowContext(width, height)

    @property
    def texture_bytes(self) -> int:
        """GPU memory of every impostor, ring, layer and screen-impostor texture held."""
        return self._impostors.texture_bytes + self._cloud_pass.texture_bytes

    def _with_field(self, scene: Scene, camera: Camera, carried: np.ndarray, time_s: float) -> tuple[Scene, tuple]:
        """The scene with its cloud field's clouds for this eye after its own (`cloudcore.field.state`), and
        per cloud the key of its blend weights; the field's weights are held for the particle buffer.  The field's
        grid has drifted `carried` (3,) metres with the wind: its cells are made and weighed for the eye's place
        relative to the air, where the particle buffer's carry (`_carried`) then moves them."""
        if scene.cloud_field is None:
            self.weather_state, self._field_weights, self._cloud_weights = WeatherFieldState(), None, None
            return scene, (1.0,) * len(scene.clouds)
        eye_in_air = np.asarray(camera.position, dtype=np.float64) - carried
        frame, self.weather_state = update_weather_field(
            scene.cloud_field, scene.weather, time_s, eye_in_air, self.weather_state
        )
        authored = scene.particle_count
        self._field_weights = np.concatenate([np.ones(authored), frame.weights])
        self._cloud_weights = np.concatenate([np.ones(len(scene.clouds)), frame.mean_weights])
        return (
            dataclasses.replace(scene, clouds=scene.clouds + frame.clouds),
            (1.0,) * len(scene.clouds) + frame.fade_keys,
        )

    def _follow_scene(self, scene: Scene, lighting: Lighting, illumination_method: str, cloud_shadows: bool) -> float:
        """Make the world pass, the objects' pass and the clouds' light again where what they are made from
        changed, and say which map of the clouds' shadows the frame takes (`_update_shadows` makes it); ms spent
        lighting the clouds."""
        lights, ambient = scene_lights(lighting)
        # a dragged slider's look (the editor's preview) draws the coarse sky, as its clouds are a coarse raster
        preview = illumination_method == PREVIEW_METHOD
        # the clouds shadow the sun's (the first light's) beam where there are clouds and it shines
        sun = shadowing_sun(lights) if cloud_shadows else None
        # on one another too, but not a cloud field's: the light pass's part is made again for every new set of
        # clouds, and a flight through a field brings one every few frames (`sun_through_others`, 100 ms)
        cloud_shadows = cloud_shadows and scene.cloud_field is None
        self._world.follow((scene.terrain, lighting, preview), lights, ambient)
        self._objects.follow((scene.objects, lights, tuple(ambient), self.size), ambient)
        start = time.perf_counter()
        relit = self._lit.follow(
            (scene.clouds, scene.shading, lighting, illumination_method, cloud_shadows), lights, ambient
        )
        illumination_ms = 1e3 * (time.perf_counter() - start) if relit else 0.0
        self._shadows = None if sun is None or not scene.clouds else self.shadow_map
        self._shadow_source = (
            sun,
            PREVIEW_MAP_RESOLUTION if preview else FIELD_MAP_RESOLUTION if scene.cloud_field else MAP_RESOLUTION,
        )
        return illumination_ms

    def _make_world(self, source: tuple, lights, ambient) -> WorldPass:
        """The world pass of `source` (terrain, lighting, whether the sky is the preview's)."""
        terrain, lighting, preview = source
        return WorldPass(
            terrain,
            terrain_light(lighting, lights, ambient),
            scene_sky(lighting, preview),
            self._air_for,
            self._sky_for,
        )

    def _make_objects(self, source: tuple, ambient) -> ObjectPass | None:
        """The objects' pass of `source` (objects, lights, ambient, frame size); None without objects."""
        objects, lights, _, size = source
        return ObjectPass(objects, lights, ambient, size) if objects else None

    def _update_shadows(
        self, scene: Scene, particles: ParticleBuffer, motion: CloudMotion | None, time_s: float, fade_keys: tuple
    ) -> float:
        """Make the clouds' transmittance map again for another particle buffer, sun or size, or when the clouds'
        opacities change (`CloudShadowMap.update`): every frame while a cloud forms or dissipates, when a field's
        clouds' blend weights leave their steps (`fade_keys`: they fade in and out, their shadows with them), never
        while none does; ms spent making it (0 when it was held).  A wind that moves every cloud alike moves the map
        made of their buffer at rest with them; one that changes them otherwise makes it again each frame, of the
        particles where they are (`particles`, weighed)."""
        if self._shadows is None:
            return 0.0
        start, made = time.perf_counter(), self.shadow_map.made
        forming = tuple(
            formation_state(scene.clouds[index].formation, time_s) for index in self._lit.value.forming_clouds
        )
        opacity = (particles.opacity_factors(time_s), (forming, fade_keys))
        if motion is not None and not reshapes(motion.wind):
            self.shadow_map.update(self._lit.value.particles, *self._shadow_source, *opacity, motion.drifts[0])
        else:
            self.shadow_map.update(particles, *self._shadow_source, *opacity)
        self.context.bind_target()
        return 1e3 * (time.perf_counter() - start) if self.shadow_map.made != made else 0.0

    def _air_motion(self, scene: Scene) -> AirMotion | None:
        """The wind applied to the scene's authored clouds (`cloudcore.wind.AirMotion`), made again for other
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
        lit, units = self._lit.value.particles, self._units.value
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

    def _ring_keys_under_wind(self, ring_keys: tuple, motion: CloudMotion | None, settings: RenderSettings) -> tuple:
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

    def _light_clouds(self, source: tuple, lights, ambient) -> _LitClouds:
        """The clouds' particle buffer (their light) for `source` (the clouds, shading, lighting, light pass method,
        whether the clouds shadow one another), each cloud's lighting key kept from the last where its light is
        the same."""
        clouds, shading, lighting, illumination_method, cloud_shadows = source
        particles = ParticleBuffer(
            clouds,
            shading,
            lights,
            ambient,
            illumination_method,
            self._illumination,
            particle_styles(clouds, lighting),
            between_clouds=cloud_shadows,
        )
        old = self._lit.value
        same_lighting = old is not None and self._lit.source[1:] == source[1:]
        # by identity, not place: a cloud field's clouds that stay keep their keys when others come and go, unless
        # the light reaching them changed (the clouds shadow one another: one moved, another's shadow moves)
        held = (
            {
                id(cloud): (key, old.particles.incident[start:stop])
                for cloud, key, start, stop in zip(
                    self._lit.source[0],
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
        return _LitClouds(particles, CloudFacings(particles), lighting_keys, forming)

    def _cloud_keys(self, scene: Scene, fade_keys: tuple, time_s: float) -> tuple[tuple, tuple]:
        """(per cloud, what its colours are made from this frame: its lighting key, and as a forming or
        dissipating cloud's colours change with the clock and a field's cloud's with its blend weights, those
        (its impostor is stale meanwhile); the same less the blend weights, what Wang's ring goes stale by:
        they follow the eye's place, which its rebuild distance bounds (`plan_frame`'s `ring_keys`)).  The same
        tuples as the frame before while none changed: the plan then finds its ring's clouds unchanged at once
        (`cloudcore.lod.ring`), with no cloud looked at."""
        lit = self._lit.value
        forming = tuple((index, formation_state(scene.clouds[index].formation, time_s)) for index in lit.forming_clouds)
        self._keys.follow((lit.lighting_keys, fade_keys, forming))
        return self._keys.value

    def _keys_of(self, source: tuple) -> tuple[tuple, tuple]:
        """`_cloud_keys`' pair made from its source (the lighting keys, the fade keys, the forming clouds' states)."""
        lighting_keys, fade_keys, forming = source
        states = dict(forming)
        colours = tuple((key, states.get(index)) for index, key in enumerate(lighting_keys))
        held = () if self._keys.value is None else self._keys.value[1]
        return (
            tuple((*colour, fade) for colour, fade in zip(colours, fade_keys)),  # unformed: state None
            held if colours == held else colours,  # only blend weights changed: the ring's keys are as they were
        )

    def _unit_weights(self, units: list) -> np.ndarray:
        """The mean blend weight of the particles of each unit's members (tuples of cloud indices) of `units`."""
        if self._cloud_weights is None or not units:
            return np.ones(len(units))
        clouds = np.fromiter(itertools.chain.from_iterable(units), dtype=np.int64)
        firsts = np.cumsum([0] + [len(members) for members in units[:-1]])
        counts = np.diff(self._lit.value.particles.cloud_starts)[clouds]
        particles = np.add.reduceat(counts, firsts)
        weighted = np.add.reduceat(self._cloud_weights[clouds] * counts, firsts)
        return np.divide(weighted, particles, out=np.ones(len(units)), where=particles > 0)

    def _next_key(self) -> int:
        self._key_serial += 1
        return self._key_serial

    def measure_overdraw(self) -> tuple[np.ndarray, Overdraw]:
        """(fragments per pixel (height, width) float32, statistics) of the last rendered frame's clouds.

        Draws the last frame's cloud pass again (`CloudPass.count_fragments`: splats, and one fragment per
        pixel for each impostor quad) into a float counter that shares the frame's depth, so fragments hidden
        by terrain are not counted.  The analytic estimate beside it sums the splats' disc areas.
        """
        if self.last_plan is None:
            raise RuntimeError("render a frame before measuring its overdraw")
        self.context.make_current()
        if self._overdraw_target is None:
            self._overdraw_target = TextureTarget(
                *self.size, GL.GL_R32F, depth_renderbuffer=self.context.depth_renderbuffer
            )
        self._overdraw_target.bind_cleared()
        batches = self._cloud_pass.count_fragments()
        view, projection = self._cloud_pass.last_matrices
        analytic = sum(
            analytic_overdraw(batch.centres, batch.radii, view, projection, NEAR_PLANE_M)
            for batch in (batch.on_cpu() for batch in batches)
        )
        counts = self._overdraw_target.read()
        self.context.bind_target()
        return counts, overdraw_statistics(counts, analytic)

    def _close_screen_targets(self) -> None:
        """Free the targets whose size is the frame's."""
        for target in (self._overdraw_target, self._display[0] if self._display else None):
            if target is not None:
                target.close()
        if self._display is not None:
            GL.glDeleteProgram(self._display[1])
        self._overdraw_target = self._display = None
        self._cloud_pass.close_screen_targets()

    @property
    def _machine(self) -> dict:
        """What a cost model fitted here holds for: this GL on this processor (`remembered_prior`)."""
        return {
            "gl": self._volume.features.renderer,
            "processor": platform.machine(),
            "cores": os.cpu_count() or 0,
            "format": 1,
        }

    def close(self) -> None:
        if self.context.closed:
            return
        if self._remember_costs:
            remember_fit(self._machine, self.lod_state.costs)
        self.context.make_current()
        self._close_screen_targets()
        self._impostors.close()
        self._quads.close()
        self._splats.close()
        self._clock.close()
        self._volume.close()
        self.shadow_map.close()
        self._world.close()
        self._objects.close()
        self.context.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def _held_key(held, incident: np.ndarray):
    """A cloud's lighting key from before (`held`: (key, the light that reached its particles then)) while the
    light reaching it is the same, else None."""
    return held[0] if held is not None and np.array_equal(held[1], incident) else None


def render_full(
    scene: Scene,
    width: int,
    height: int,
    *,
    time_of_day: float | None = None,
    camera: Camera | None = None,
    illumination_method: str = "exact",
) -> tuple[np.ndarray, FrameStats]:
    """Render one full-3D frame of `scene` in a context of its own; see `FrameRenderer.render`."""
    with FrameRenderer(width, height) as renderer:
        return renderer.render(
            scene, time_of_day=time_of_day, camera=camera, illumination_method=illumination_method, settings=FULL_3D
        )
