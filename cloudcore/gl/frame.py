"""A whole frame: plan, world pass, impostor updates, cloud pass, read-back to 8-bit sRGB, with timings.

Everything is composed in linear light in a float target; the one transfer to
sRGB happens on read-back.  `FrameRenderer` keeps its context, GL objects,
terrain and precomputed cloud illumination between frames and rebuilds each
only when what it came from changes (a scene's cloud field adds its clouds
for the eye after the scene's own first: `cloudcore.field.state`, whose
state it holds too); what the level of detail carries from
frame to frame (impostor cache, ring, representations, the fitted costs) is
the pure `cloudcore.lod.plan.LodState` it holds.  Each frame it asks
`cloudcore.lod.plan.plan_frame` what to do, executes exactly that, and
folds the two timed passes into the state's cost fit:

1. the world (terrain depth and colour over the sky), and the objects
   that are not inside a drawn cloud;
2. the impostors and ring segment the plan regenerates;
3. the ring panels, then the plan's draw items far to near: runs of full-3D
   units (clouds, or groups of interpenetrating clouds, or their layers) as
   one sorted splat batch, impostors as quads, crossfading units as their
   full-3D image (in a screen layer) mixed with their impostor, the unit the
   eye is inside as a reduced-resolution screen impostor, and the objects
   inside clouds between the layers they split.
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
from cloudcore.gl.air_volume import AirVolume
from cloudcore.gl.context import HeadlessContext, WindowContext, check_frame_size
from cloudcore.gl.impostor_atlas import atlas_instances
from cloudcore.gl.impostor_store import ImpostorStore
from cloudcore.gl.light_shafts import LightShaftPass
from cloudcore.gl.objects import ObjectPass
from cloudcore.gl.pass_clock import PassClock
from cloudcore.gl.programs import build_program
from cloudcore.gl.quads import SCREEN_CORNERS, QuadPass
from cloudcore.gl.reduced_clouds import ReducedClouds
from cloudcore.gl.shadow_map import CloudShadowMap
from cloudcore.gl.splats import SplatBatch, SplatPass, SplatSelection, splat_batch
from cloudcore.gl.targets import TextureTarget, blit_depth, depth_renderbuffer
from cloudcore.gl.volume_blending import GpuFeatures, VolumeBlendingPass
from cloudcore.gl.world import WorldPass
from cloudcore.light.air_between import air_between
from cloudcore.light.cloud_shadows import FIELD_MAP_RESOLUTION, MAP_RESOLUTION, PREVIEW_MAP_RESOLUTION
from cloudcore.light.eye_scattering import ParticleBuffer
from cloudcore.light.illumination import IlluminationCache, shadowing_sun
from cloudcore.light.lighting import scene_lights
from cloudcore.light.live_air import LiveAir
from cloudcore.light.relighting import PREVIEW_METHOD
from cloudcore.light.sky_background import SkyBackground, scene_sky
from cloudcore.light.terrain_light import terrain_light
from cloudcore.light.volume_blending import blending_path
from cloudcore.lod.costs import CostEstimator, CostModel, remember_fit, remembered_prior
from cloudcore.lod.impostors import cropped_corners, particle_extent
from cloudcore.lod.plan import FramePlan, LodState, plan_frame
from cloudcore.lod.plan.draw_items import inside_runs
from cloudcore.lod.units import LodUnits, lod_units
from cloudcore.measure.frame_stats import FrameStats
from cloudcore.measure.overdraw import Overdraw, overdraw_statistics
from cloudcore.measured_way import COMPOSITING_WAYS, MeasuredWay
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
)


@dataclass(frozen=True)
class _CloudPassFrame:
    """What every draw of one frame's cloud pass shares."""

    plan: FramePlan
    particles: ParticleBuffer
    camera: Camera
    view: np.ndarray
    projection: np.ndarray
    view_projection: np.ndarray
    frustum: np.ndarray  # the view's planes (`cloudcore.camera.frustum_planes`)
    poses: tuple
    time_s: float
    point_sprites: bool  # the setting: draw plain splats as points where the picture is the same
    blending: str  # the setting: full-3D splats as billboards ("plain") or as volumes ("volume")
    splat_order: str  # splats chosen and sorted on the "cpu" or the "gpu" (the setting, "auto" resolved)
    compositing: str  # the GPU's plain full-3D splats blended by the "raster" or by "compute" ("auto" resolved)
    #: the air's volume uploaded for this eye, and the eye, that world-space quads are seen through; None: no air
    air: tuple[AirVolume, np.ndarray] | None
    #: where the cloud draws go: None, the frame's target; else the reduced pass (`plan.cloud_size`)
    reduced: ReducedClouds | None

    @property
    def eye(self) -> np.ndarray:
        return np.asarray(self.camera.position, dtype=np.float64)


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
        self._world, self._world_source = None, None
        #: the clouds' transmittance map, and this frame's: None where the clouds shadow nothing
        self.shadow_map = CloudShadowMap()
        self._shadows: CloudShadowMap | None = None
        self._objects, self._objects_source = None, None
        self._particles, self._particles_source = None, None
        self._facings: CloudFacings | None = None
        self._illumination = illumination if illumination is not None else IlluminationCache()
        self._air_for = air if air is not None else air_between
        self._sky_for = air.sky_seen_from if air is not None else SkyBackground.seen_from
        #: per cloud, changes whenever that cloud's particle colours may have: its impostor is stale
        self._lighting_keys: tuple = ()
        self._forming_clouds: tuple = ()  # the clouds that form or dissipate, whose colours follow the clock
        self._cloud_keys_source, self._cloud_keys_made = None, ((), ())
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
        self._compositable = 0  # this frame's particles in draws either way could composite
        #: the cloud field's cells made for the last eye, its particles' blend weights and every cloud's mean weight
        #: (None: no field)
        self.weather_state = WeatherFieldState()
        self._field_weights: np.ndarray | None = None
        self._cloud_weights: np.ndarray | None = None
        self._units: LodUnits | None = None
        self._units_source = None
        self._air: AirMotion | None = None  # the wind applied to the authored clouds (None: still air)
        #: this frame's carried particles and units and the clouds' motion, and what they were made from
        self._carry_source, self._carry_made = None, None
        self._ring_drift = None  # (ring keys, clouds' drift steps, the keys with them) under wind
        self._shadow_source = (None, MAP_RESOLUTION)  # the sun and the size of the clouds' transmittance map
        self._layer = None  # screen-sized, sharing the frame's depth: crossfading clouds' full-3D image
        self._reduced: ReducedClouds | None = None  # the cloud pass at a fraction of the screen's resolution
        self._inside = []  # (target, its depth renderbuffer) per screen impostor of a frame, all of one size
        self._overdraw_target = None
        self._display = None  # (RGBA8 target, program): the frame in sRGB for the editor
        # the last frame's draws into the screen, replayable as fragment counts, and its splat batches
        self._replay, self._screen_batches, self._last_matrices = [], [], None
        self._particles_as_volumes = 0  # this frame's, for its statistics
        self.last_plan: FramePlan | None = None

    @property
    def units(self) -> LodUnits:
        """The units (clouds, or groups of interpenetrating clouds) of the scene last rendered, where the wind
        had carried them; a frame may plan some groups apart (`FramePlan.units`)."""
        return self._units if self._carry_made is None else self._carry_made[1]

    @property
    def field_state(self) -> FieldState:
        """The cloud field's cells for the last eye under the weather in force, or coming during a change."""
        return self.weather_state.in_force

    @property
    def particles(self) -> ParticleBuffer:
        """The particle buffer of the scene last rendered, where the wind had carried it."""
        return self._particles if self._carry_made is None else self._carry_made[0]

    @property
    def light_shafts(self) -> LightShaftPass | None:
        """The world pass's light shafts, once a frame has drawn them (tests read their march)."""
        return None if self._world is None else self._world.light_shafts

    @property
    def reduced_clouds(self) -> ReducedClouds | None:
        """The reduced cloud pass, once a frame has drawn one (tests read what it laid over the screen)."""
        return self._reduced

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
        drawing = (scene, time_of_day, camera, illumination_method, settings, time_s, costs, lit_at)
        stats = self._draw_frame(*drawing)
        if self._volume.settle():
            # a draw composited by compute had more tile pairs than the room the GPU had for them, and lost its
            # nearest splats: drawn again, each draw's pairs counted first (`cloudcore.gl.tile_binning`)
            first = stats
            stats = self._draw_frame(*drawing)
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

    def _draw_frame(
        self,
        scene: Scene,
        time_of_day,
        camera,
        illumination_method: str,
        settings: RenderSettings,
        time_s,
        costs,
        lit_at: float | None,
    ) -> FrameStats:
        """`render`'s frame, left in the render target."""
        self.context.make_current()  # several renderers may share a thread (the benchmarks take turns)
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
        illumination_ms = self._prepare(scene, lighting, illumination_method, settings.cloud_shadows)
        # the units follow the particles' places and sizes, not their light: a relit scene keeps them
        if (scene.clouds, settings.group_clouds) != self._units_source:
            self._units = lod_units(self._particles, settings.group_clouds, authored_clouds)
            self._units_source = (scene.clouds, settings.group_clouds)
        particles, units, motion = self._carried(air, field_carried, time_s, lit_at)
        particles.weigh(self._field_weights)
        illumination_ms += self._update_shadows(scene, particles, motion, time_s, fade_keys)
        planning_started = time.perf_counter()
        poses = self._objects.poses(time_s) if self._objects is not None else ()
        starts = particles.cloud_starts
        cloud_keys, ring_keys = self._cloud_keys(scene, fade_keys, time_s)
        ring_keys = self._ring_keys_under_wind(ring_keys, motion, settings)
        plan = plan_frame(
            units,
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
            motion,
        )
        self.last_plan = plan

        view = view_matrix(camera)
        projection = projection_matrix(camera.fov_y_deg, self.context.width / self.context.height)
        self._last_matrices = view, projection
        # in the editor's context the GUI leaves its scissor rectangle on, which would clip our targets
        GL.glDisable(GL.GL_SCISSOR_TEST)
        for start, facing in self._facings.update(camera.position, particles):
            self._splats.update_facing(particles, start, facing)
        before_passes_ms = 1e3 * (time.perf_counter() - planning_started)
        self._splats.particles_as_points = 0
        self._particles_as_volumes = 0
        gl_renderer = self._volume.features.renderer
        way = self.splat_order.way(settings.splat_order, gl_renderer)
        compositing = self.compositing.get(settings.mode, MeasuredWay(COMPOSITING_WAYS))
        composited_by = compositing.way(settings.compositing, gl_renderer)
        self._compositable = 0
        clock = self._clock
        with clock.frame():
            with clock.timed("world"):
                antialiased = settings.world_antialiasing
                self._world.draw(
                    self.context,
                    camera,
                    view,
                    projection,
                    antialiased=antialiased,
                    through_air=settings.aerial_perspective,
                    shadows=self._shadows,
                    light_shafts=settings.light_shafts,
                )
                if plan.objects_with_world:
                    self._objects.draw(
                        self.context,
                        camera,
                        poses,
                        plan.objects_with_world,
                        write_depth=True,
                        antialiased=antialiased,
                        air=self._world.air_volume if settings.aerial_perspective else None,
                        shadows=self._shadows,
                    )
            # the world pass uploaded the air for this eye: the ring's segments are drawn through it
            self._splats.air = self._world.air_volume if settings.aerial_perspective else None
            with clock.timed("impostor updates"):
                rendered = self._impostors.update(plan, particles, settings, time_s, way, self._unit_weights)
            with clock.timed("clouds"):
                self.context.bind_target()
                drawn = self._draw_clouds(
                    plan, particles, camera, view, projection, settings, poses, time_s, way, composited_by
                )
        drawn_by_gpu, rendered_by_gpu = self._splats.take_selected()
        drawn, rendered = drawn + drawn_by_gpu, rendered + rendered_by_gpu
        world, updates, clouds = (clock.times[name] for name in ("world", "impostor updates", "clouds"))
        self.lod_state = plan.state.measured(
            [(plan.update_work, updates.wall_ms), (plan.cloud_work, clouds.wall_ms)], fit=plan.priced
        )
        self.splat_order = self.splat_order.observe(way, updates.wall_ms + clouds.wall_ms, drawn + rendered)
        self.compositing[settings.mode] = compositing.observe(composited_by, clouds.wall_ms, self._compositable)
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
            particles_drawn=drawn,
            particles_as_points=self._splats.particles_as_points,
            particles_as_volumes=self._particles_as_volumes,
            splat_order=way,
            compositing=composited_by if self._compositable else "",
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
        held = self._impostors.texture_bytes
        for target in (self._layer, *(target for target, _ in self._inside)):
            held += target.nbytes if target is not None else 0
        return held + (self._reduced.nbytes if self._reduced is not None else 0)

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

    def _prepare(self, scene: Scene, lighting: Lighting, illumination_method: str, cloud_shadows: bool) -> float:
        """Rebuild the world pass and the particle illumination where their inputs changed, and say which map of
        the clouds' shadows the frame takes (`_update_shadows` makes it); ms spent shading."""
        lights, ambient = scene_lights(lighting)
        # a dragged slider's look (the editor's preview) draws the coarse sky, as its clouds are a coarse raster
        preview = illumination_method == PREVIEW_METHOD
        # the clouds shadow the sun's (the first light's) beam where there are clouds and it shines
        sun = shadowing_sun(lights) if cloud_shadows else None
        # on one another too, but not a cloud field's: the light pass's part is made again for every new set of
        # clouds, and a flight through a field brings one every few frames (`sun_through_others`, 100 ms)
        cloud_shadows = cloud_shadows and scene.cloud_field is None
        world_source = (scene.terrain, lighting, preview)
        if world_source != self._world_source:
            self.context.make_current()
            if self._world is not None:
                self._world.close()
                # closed: a new one that fails to build leaves none to close again, and none to draw
                self._world, self._world_source = None, None
            self._world = WorldPass(
                scene.terrain,
                terrain_light(lighting, lights, ambient),
                scene_sky(lighting, preview),
                self._air_for,
                self._sky_for,
            )
            self._world_source = world_source
        objects_source = (scene.objects, lights, tuple(ambient), self.size)
        if objects_source != self._objects_source:
            self.context.make_current()
            if self._objects is not None:
                self._objects.close()
                self._objects, self._objects_source = None, None
            self._objects = ObjectPass(scene.objects, lights, ambient, self.size) if scene.objects else None
            self._objects_source = objects_source
        particles_source = (scene.clouds, scene.shading, lighting, illumination_method, cloud_shadows)
        illumination_ms = 0.0
        if particles_source != self._particles_source:
            illumination_ms = self._prepare_particles(scene, lights, ambient, particles_source)
        self._shadows = None if sun is None or not scene.clouds else self.shadow_map
        self._shadow_source = (
            sun,
            PREVIEW_MAP_RESOLUTION if preview else FIELD_MAP_RESOLUTION if scene.cloud_field else MAP_RESOLUTION,
        )
        return illumination_ms

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
        forming = tuple(formation_state(scene.clouds[index].formation, time_s) for index in self._forming_clouds)
        opacity = (particles.opacity_factors(time_s), (forming, fade_keys))
        if motion is not None and not reshapes(motion.wind):
            self.shadow_map.update(self._particles, *self._shadow_source, *opacity, motion.drifts[0])
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
        field's by its grid's drift `field_carried` (`air` is None only in still air: the buffer and units
        themselves)."""
        lit, units = self._particles, self._units
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
        field_particles = len(lit.radii) - int(lit.cloud_starts[authored])
        offsets = np.concatenate([air.carry(time_s, lit_at), np.tile(field_carried, (field_particles, 1))])
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

    def _prepare_particles(self, scene: Scene, lights, ambient, particles_source: tuple) -> float:
        """Make the particle buffer (the clouds' light) again for `particles_source` (the clouds, shading,
        lighting, light pass method, whether the clouds shadow one another); ms spent."""
        _, _, lighting, illumination_method, cloud_shadows = particles_source
        start = time.perf_counter()
        old_particles = self._particles
        self._particles = ParticleBuffer(
            scene.clouds,
            scene.shading,
            lights,
            ambient,
            illumination_method,
            self._illumination,
            particle_styles(scene.clouds, lighting),
            between_clouds=cloud_shadows,
        )
        self._facings = CloudFacings(self._particles)
        old_clouds, old_lighting = (
            ((), None) if self._particles_source is None else (self._particles_source[0], self._particles_source[1:])
        )
        same_lighting = old_lighting == particles_source[1:]
        # by identity, not place: a cloud field's clouds that stay keep their keys when others come and go, unless
        # the light reaching them changed (the clouds shadow one another: one moved, another's shadow moves)
        held = (
            {
                id(cloud): (key, old_particles.incident[start:stop])
                for cloud, key, start, stop in zip(
                    old_clouds, self._lighting_keys, old_particles.cloud_starts[:-1], old_particles.cloud_starts[1:]
                )
            }
            if same_lighting
            else {}
        )
        starts = self._particles.cloud_starts
        self._lighting_keys = tuple(
            key
            if (key := _held_key(held.get(id(cloud)), self._particles.incident[start:stop])) is not None
            else self._next_key()
            for cloud, start, stop in zip(scene.clouds, starts[:-1], starts[1:])
        )
        self._forming_clouds = tuple(index for index, cloud in enumerate(scene.clouds) if cloud.formation is not None)
        self._particles_source = particles_source
        return 1e3 * (time.perf_counter() - start)

    def _cloud_keys(self, scene: Scene, fade_keys: tuple, time_s: float) -> tuple[tuple, tuple]:
        """(per cloud, what its colours are made from this frame: its lighting key, and as a forming or
        dissipating cloud's colours change with the clock and a field's cloud's with its blend weights, those
        (its impostor is stale meanwhile); the same less the blend weights, what Wang's ring goes stale by:
        they follow the eye's place, which its rebuild distance bounds (`plan_frame`'s `ring_keys`)).  The same
        tuples as the frame before while none changed: the plan then finds its ring's clouds unchanged at once
        (`cloudcore.lod.ring`), with no cloud looked at."""
        forming = tuple(
            (index, formation_state(scene.clouds[index].formation, time_s)) for index in self._forming_clouds
        )
        source = (self._lighting_keys, fade_keys, forming)
        if source != self._cloud_keys_source:
            states = dict(forming)
            colours = tuple((key, states.get(index)) for index, key in enumerate(self._lighting_keys))
            self._cloud_keys_source = source
            held = self._cloud_keys_made[1]
            self._cloud_keys_made = (
                tuple((*colour, fade) for colour, fade in zip(colours, fade_keys)),  # unformed: state None
                held if colours == held else colours,  # only blend weights changed: the ring's keys are as they were
            )
        return self._cloud_keys_made

    def _unit_weights(self, units: list) -> np.ndarray:
        """The mean blend weight of the particles of each unit's members (tuples of cloud indices) of `units`."""
        if self._cloud_weights is None or not units:
            return np.ones(len(units))
        clouds = np.fromiter(itertools.chain.from_iterable(units), dtype=np.int64)
        firsts = np.cumsum([0] + [len(members) for members in units[:-1]])
        counts = np.diff(self._particles.cloud_starts)[clouds]
        particles = np.add.reduceat(counts, firsts)
        weighted = np.add.reduceat(self._cloud_weights[clouds] * counts, firsts)
        return np.divide(weighted, particles, out=np.ones(len(units)), where=particles > 0)

    def _faded(self, units: list, made_at: np.ndarray) -> np.ndarray:
        """What scales each impostor of `units` made at mean blend weights `made_at`: a cloud field's fade moves
        its units' weights between the steps of their keys (`cloudcore.field.state.FADE_KEY_STEPS`), and the
        impostor follows by its opacity, in proportion.  One made at weight 0 is empty, and its key holds only
        while the weight stays 0."""
        now = self._unit_weights(units)
        return np.divide(now, made_at, out=np.zeros(len(units)), where=made_at > 0.0)

    def _next_key(self) -> int:
        self._key_serial += 1
        return self._key_serial

    def _draw_clouds(
        self,
        plan: FramePlan,
        particles: ParticleBuffer,
        camera: Camera,
        view,
        projection,
        settings: RenderSettings,
        poses,
        time_s: float,
        splat_order: str,
        compositing: str,
    ) -> int:
        """Execute the plan's cloud pass into the frame target at scene time `time_s`, one method per draw kind,
        full-3D draws sorted the way `splat_order` ("cpu" or "gpu"), the GPU's plain ones composited the way
        `compositing` ("raster" or "compute"); returns the particles drawn."""
        view_projection = projection @ view
        air = self._world.air_volume if settings.aerial_perspective else None
        frame = _CloudPassFrame(
            plan,
            particles,
            camera,
            view,
            projection,
            view_projection,
            frustum_planes(view_projection),
            poses,
            time_s,
            settings.point_sprites,
            settings.blending,
            splat_order,
            compositing,
            None if air is None else (air, np.asarray(camera.position, float)),
            None,  # begun below, once the CPU's part of the pass is done
        )
        # the world pass uploaded the air for this eye: the cloud pass's splats take it per particle
        self._splats.air = air
        self._replay, self._screen_batches = [], []
        steps = self._cloud_pass_steps(frame)
        runs = inside_runs(plan.draw_items, plan.clouds)
        inside_batches = [self._batch_of(frame, run) for run in runs]
        self._splats.shade_ahead(
            [(batch, view) for batch in inside_batches]
            + [(step[-1], view) for step in steps if step[0] in ("splats", "crossfade")]
        )
        # the reduced pass reads the world's depth, and on llvmpipe the CPU then waits for the world to be drawn:
        # begun after the batches are sorted and shaded, which the world's drawing overlapped
        frame = dataclasses.replace(frame, reduced=self._reduced_pass(plan.cloud_size))
        # units the eye is in, one after the other: one screen impostor each run, laid where the run starts
        screen_impostors = self._screen_impostors(frame, runs, inside_batches)
        if plan.ring is not None:
            self._draw_ring(frame, settings.ring_elevation_deg)
        drawn = 0
        for kind, item, batch in steps:
            if kind == "splats":
                drawn += self._draw_splats(frame, batch)
            elif kind == "object":
                antialiased = settings.world_antialiasing
                if frame.reduced is not None:  # the clouds behind it laid over the screen first, at its resolution
                    frame.reduced.composite(self.context)
                self._objects.draw(
                    self.context,
                    camera,
                    poses,
                    [item.index],
                    write_depth=False,
                    antialiased=antialiased,
                    air=None if frame.air is None else frame.air[0],
                    shadows=self._shadows,
                )
                if frame.reduced is not None:
                    frame.reduced.resume()
            elif kind == "inside":
                if item in screen_impostors:  # the rest of its run is in the same screen impostor
                    target, particles_drawn, extent = screen_impostors[item]
                    self._draw_screen_quad(target.texture, plan.clouds[item.index].full_weight, extent)
                    drawn += particles_drawn
            elif kind == "impostors":
                self._draw_impostors(frame, item)
            else:
                drawn += self._draw_crossfade(frame, item, plan.clouds[item.index], batch)
        if frame.reduced is not None:
            frame.reduced.composite(self.context)
        return drawn

    def _reduced_pass(self, size: tuple) -> ReducedClouds | None:
        """The reduced cloud pass begun for this frame at `size`, bound; None at the screen's size (the frame's
        target, as before)."""
        if tuple(size) == self.size:
            return None
        if self._reduced is None:
            self._reduced = ReducedClouds()
        self._reduced.begin(self.context, size)
        return self._reduced

    def _cloud_pass_steps(self, frame: _CloudPassFrame) -> list[tuple]:
        """The cloud pass's draws in order, (kind, draw item, splat batch or None), kind one of "splats" (a run
        of consecutive full-3D layers: they interpenetrate, sorted together), "object", "inside",
        "impostors" (the draw items of a run of consecutive impostor quads: drawn with their state set once,
        2.6% of the untuned cumulus field's clouds side by side), "crossfade": sorted first, so that their
        splats are shaded before anything is drawn."""
        steps, full_run = [], []  # full_run: draw items of consecutive full-3D layers
        for item in frame.plan.draw_items:
            cloud = frame.plan.clouds[item.index] if item.kind == "cloud" else None
            if cloud is not None and cloud.kind == "full":
                full_run.append(item)
                continue
            if full_run:
                steps.append(("splats", None, self._full_3d_batch(frame, full_run)))
                full_run = []
            kind = "object" if cloud is None else cloud.kind
            if kind == "impostor" and steps and steps[-1][0] == "impostors":
                steps[-1][1].append(item)
            elif kind == "impostor":
                steps.append(("impostors", [item], None))
            else:
                steps.append((kind, item, self._batch_of(frame, [item]) if kind == "crossfade" else None))
        if full_run:
            steps.append(("splats", None, self._full_3d_batch(frame, full_run)))
        return steps

    def _full_3d_batch(self, frame: _CloudPassFrame, items) -> SplatBatch | SplatSelection:
        """`_batch_of` for a run of full-3D layers; chosen and sorted on the GPU when that is the frame's way
        and they are blended as billboards (volume blending reads its batch on the CPU)."""
        if frame.splat_order == "gpu" and frame.blending == "plain":
            clouds, depth_ranges = self._members_and_ranges(frame, items)
            return SplatSelection(
                frame.particles, clouds, frame.eye, depth_ranges, frame.time_s, frame.frustum, through_air=True
            )
        return self._batch_of(frame, items)

    def _batch_of(self, frame: _CloudPassFrame, items) -> SplatBatch:
        """The splats of the units of draw `items`, each within its item's depth range, sorted together, seen
        through the air from the eye (their screen layers and screen impostors are made for this eye alone)."""
        clouds, depth_ranges = self._members_and_ranges(frame, items)
        return splat_batch(frame.particles, clouds, frame.eye, depth_ranges, frame.time_s, frame.frustum, True)

    @staticmethod
    def _members_and_ranges(frame: _CloudPassFrame, items) -> tuple[tuple, tuple]:
        """(the clouds of draw `items`, the depth range of each: its item's)."""
        pairs = [(member, (item.near, item.far)) for item in items for member in frame.plan.clouds[item.index].members]
        return tuple(zip(*pairs))

    def _draw_splats(
        self, frame: _CloudPassFrame, batch: SplatBatch | SplatSelection, colour_texture: int | None = None
    ) -> int:
        """Full 3D: a batch of splats on the screen (or the screen layer whose `colour_texture` is bound), as
        billboards or as volumes; returns the particles drawn, but 0 for a selection: the GPU counts those
        (`SplatPass.take_selected`)."""
        view, projection, points = frame.view, frame.projection, frame.point_sprites
        if isinstance(batch, SplatSelection):
            composited = False
            compositable = self._volume.features.compute_shaders and self._splats.plain_selection(batch)
            self._compositable += batch.slots if compositable else 0
            if frame.compositing == "compute" and compositable:
                instances, count_at = self._splats.selected_instances(batch, view)
                target, framebuffer, size = self._drawn_into(frame, colour_texture)
                composited = self._volume.draw(
                    instances, view, projection, target, framebuffer, size, plain=True, count_at=count_at
                )
            if composited:
                self._splats.count_drawn(batch)
            else:  # not asked for, not plain splats, or too many pairs to bin
                self._splats.draw(batch, view, projection)
            self._replay.append(lambda: self._splats.draw(batch, view, projection, counting=True))
            self._screen_batches.append(batch)
            return 0
        path = blending_path(
            frame.blending,
            compute_shaders=self._volume.features.compute_shaders,
            plain_splats_only=bool(np.all(self._splats.plain_splats(batch))),
        )
        composited = False
        if path == "volume" and len(batch):
            buffer, first = self._splats.shade(batch, view)
            target, framebuffer, size = self._drawn_into(frame, colour_texture)
            composited = self._volume.draw((buffer, first, len(batch)), view, projection, target, framebuffer, size)
            self._particles_as_volumes += len(batch) if composited else 0
        if not composited:  # plain billboards, asked for or past the binning's pairs
            self._splats.draw(batch, view, projection, point_sprites=points)
        self._replay.append(lambda: self._splats.draw(batch, view, projection, counting=True, point_sprites=points))
        self._screen_batches.append(batch)
        return len(batch)

    def _drawn_into(self, frame: _CloudPassFrame, colour_texture: int | None) -> tuple[int, int, tuple[int, int]]:
        """(the colour texture, the framebuffer whose depth cuts it, their size) a compositing pass draws into: the
        frame's target or the reduced pass's, or `colour_texture` (a screen layer of the same size and depth)."""
        if frame.reduced is None:
            framebuffer, size, texture = self.context.framebuffer, self.size, self.context.colour_texture
        else:
            target = frame.reduced.target
            framebuffer, size, texture = target.framebuffer, frame.reduced.size, target.texture
        return (texture if colour_texture is None else colour_texture), framebuffer, size

    def _bind_cloud_target(self, frame: _CloudPassFrame) -> None:
        """Draw into the frame's target, or the reduced pass's, from now on."""
        if frame.reduced is None:
            self.context.bind_target()
        else:
            frame.reduced.bind()

    def _draw_screen_quad(self, texture, weight, extent) -> None:
        """A screen impostor: the part `extent` (u0, v0, u1, v1) of `texture` that its particles can cover,
        over the same part of the screen, over everything."""
        corners = cropped_corners(SCREEN_CORNERS, extent)
        self._quads.draw(corners, np.eye(4), texture, weight, depth_test=False, uv_rect=extent)
        self._replay.append(
            lambda: self._quads.draw(corners, np.eye(4), 0, 1.0, depth_test=False, counting=True, uv_rect=extent)
        )

    def _draw_ring(self, frame: _CloudPassFrame, elevation_deg: float) -> None:
        """Wang's ring: the panels of the generations drawn (two while a rebuilt one fades in)."""
        quads = []
        shifts = frame.plan.ring_shifts or [np.zeros(3)] * len(frame.plan.ring.draws)
        for (generation, weight), shift in zip(frame.plan.ring.draws, shifts):
            for segment in generation.occupied_segments:
                target, corners, extent = self._impostors.ring_panel(generation, segment, elevation_deg)
                quads.append((np.asarray(corners + shift, dtype=np.float32), target.texture, float(weight), extent))
        self._draw_quad_run(frame, quads, through_air=False)  # their segments hold their clouds through the air

    def _draw_impostors(self, frame: _CloudPassFrame, items) -> None:
        """Units' impostors (a layer each, when split around objects), consecutive in the pass: one instanced
        draw from the atlas (two, where larger impostors than its layers' side need one of their own)."""
        clouds = [frame.plan.clouds[item.index] for item in items]
        images, corners, extents, made_at = self._impostors.cloud_impostors(
            [(cloud.members, item.layer) for cloud, item in zip(clouds, items)]
        )
        corners = corners + frame.plan.impostor_shifts([item.index for item in items])[:, None, :]
        faded = self._faded([cloud.members for cloud in clouds], made_at)
        weights = np.array([cloud.impostor_weight for cloud in clouds]) * faded
        for _, run in itertools.groupby(range(len(images)), key=lambda i: id(images[i].atlas)):  # one atlas a run
            run = list(run)
            instances = atlas_instances([images[i] for i in run], corners[run], weights[run], extents[run])
            self._draw_instanced(frame, images[run[0]].atlas.texture, instances)

    def _draw_instanced(self, frame: _CloudPassFrame, atlas_texture: int, instances: np.ndarray, **crossfade) -> None:
        """Quads from the atlas (`QuadPass.draw_instanced`), depth-tested, in one draw."""
        self._quads.draw_instanced(instances, frame.view_projection, atlas_texture, air=frame.air, **crossfade)
        self._replay.append(
            lambda: self._quads.draw_instanced(instances, frame.view_projection, atlas_texture, counting=True)
        )

    def _draw_quad_run(self, frame: _CloudPassFrame, quads, through_air: bool = True) -> None:
        """World-space quads (corners, texture, weight, uv_rect), depth-tested, one after the other."""
        self._quads.draw_run(quads, frame.view_projection, air=frame.air if through_air else None)
        self._replay.append(lambda: self._quads.draw_run(quads, frame.view_projection, counting=True))

    def _draw_crossfade(self, frame: _CloudPassFrame, item, cloud, batch: SplatBatch) -> int:
        """A unit between its impostor and full 3D: its splats (`batch`) into a screen layer, mixed with the
        impostor."""
        image, corners, extent, made_at = self._impostors.cloud_impostor(cloud.members, item.layer)
        corners = corners + frame.plan.impostor_shifts([item.index])[0]
        faded = self._faded([cloud.members], np.array([made_at]))
        layer = self._screen_layer() if frame.reduced is None else frame.reduced.layer()
        layer.bind_cleared()
        drawn = self._draw_splats(frame, batch, layer.texture)
        self._bind_cloud_target(frame)
        instance = atlas_instances([image], corners[None], cloud.impostor_weight * faded, extent[None])
        self._draw_instanced(
            frame, image.atlas.texture, instance, layer_texture=layer.texture, layer_weight=cloud.full_weight
        )
        return drawn

    def _screen_impostors(self, frame: _CloudPassFrame, runs, batches) -> dict:
        """Harris's screen impostors of the units the eye is in, before anything else of the cloud pass:
        per run of consecutive draw items (keyed by its first), (target, particles drawn, the part of
        the screen they can cover: the composite draws only that, 18% fewer fragments along the untuned
        cumulus field), their particles sorted together (`batches`, one a run) at the plan's reduced
        resolution.

        Their only input from the frame is the world's depth, which no cloud or object of the cloud pass
        writes, so made first they are the same.  Made where they are laid, each stalled the frame twice
        on llvmpipe: the depth blit waits for the frame's draws so far, the composite for the impostor's.
        """
        made = {}
        for run, batch, target in zip(runs, batches, self._inside_targets(frame.plan.inside_size, len(runs))):
            blit_depth(self.context.framebuffer, self.size, target.framebuffer, frame.plan.inside_size)
            target.bind_cleared()
            self._splats.draw(batch, frame.view, frame.projection, point_sprites=frame.point_sprites)
            extent = particle_extent(frame.view, frame.projection, batch.centres, batch.radii, frame.plan.inside_size)
            made[run[0]] = (target, len(batch), extent)
        self._bind_cloud_target(frame)
        return made

    def _screen_layer(self) -> TextureTarget:
        if self._layer is None:
            self._layer = TextureTarget(*self.size, depth_renderbuffer=self.context.depth_renderbuffer)
        return self._layer

    def _inside_targets(self, size, count: int) -> list[TextureTarget]:
        """`count` screen impostor targets of `size`, each with its own depth buffer for the frame's."""
        if self._inside and (self._inside[0][0].width, self._inside[0][0].height) != tuple(size):
            self._close_inside()
        while len(self._inside) < count:
            depth = depth_renderbuffer(*size)
            self._inside.append((TextureTarget(*size, depth_renderbuffer=depth), depth))
        return [target for target, _ in self._inside[:count]]

    def _close_inside(self) -> None:
        for target, depth in self._inside:
            target.close()
            GL.glDeleteRenderbuffers(1, [depth])
        self._inside = []

    def measure_overdraw(self) -> tuple[np.ndarray, Overdraw]:
        """(fragments per pixel (height, width) float32, statistics) of the last rendered frame's clouds.

        Replays the last frame's screen-resolution cloud draws (splats, and one
        fragment per pixel for each impostor quad) into a float counter that
        shares the frame's depth, so fragments hidden by terrain are not
        counted.  The analytic estimate beside it sums the splats' disc areas.
        """
        if self.last_plan is None:
            raise RuntimeError("render a frame before measuring its overdraw")
        self.context.make_current()
        if self._overdraw_target is None:
            self._overdraw_target = TextureTarget(
                *self.size, GL.GL_R32F, depth_renderbuffer=self.context.depth_renderbuffer
            )
        self._overdraw_target.bind_cleared()
        for count_fragments in self._replay:
            count_fragments()
        view, projection = self._last_matrices
        analytic = sum(
            analytic_overdraw(batch.centres, batch.radii, view, projection, NEAR_PLANE_M)
            for batch in (batch.on_cpu() for batch in self._screen_batches)
        )
        counts = self._overdraw_target.read()
        self.context.bind_target()
        return counts, overdraw_statistics(counts, analytic)

    def _close_screen_targets(self) -> None:
        """Free the targets whose size is the frame's."""
        for target in (self._overdraw_target, self._layer, self._display[0] if self._display else None):
            if target is not None:
                target.close()
        if self._display is not None:
            GL.glDeleteProgram(self._display[1])
        self._overdraw_target = self._layer = self._display = None
        self._close_inside()
        if self._reduced is not None:
            self._reduced.close()
            self._reduced = None

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
        if self._world is not None:
            self._world.close()
        if self._objects is not None:
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
