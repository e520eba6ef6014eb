"""A whole frame: prepare, plan, world pass, impostor updates, cloud pass, statistics; read back to 8-bit sRGB.

Everything is composed in linear light in a float target; the one transfer to
sRGB happens on read-back.  `FrameRenderer` keeps its context and GL passes
between frames, each made again only when what it came from changes
(`cloudcore.runtime.derived`); the clouds it draws, lit, carried by the wind
and with a cloud field's for the eye, are the pure
`cloudcore.particles.frame_clouds.FrameClouds` it holds; what the level of detail
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
import os
import platform
import time
from dataclasses import dataclass

import numpy as np
from OpenGL import GL

from cloudcore.field.state import FieldState
from cloudcore.field.weather import WeatherFieldState
from cloudcore.gl.context import HeadlessContext, WindowContext, check_frame_size
from cloudcore.gl.draw import CloudPass, CloudPassFrame, DrawCounts, PassTools
from cloudcore.gl.ground_shadows import GroundShadows
from cloudcore.gl.impostor_store import ImpostorStore
from cloudcore.gl.light_shafts import FrameShafts, LightShaftPass
from cloudcore.gl.measured_way import MeasuredWay
from cloudcore.gl.objects import ObjectPass
from cloudcore.gl.pass_clock import PassClock
from cloudcore.gl.programs import ProgramCache, build_program
from cloudcore.gl.quads import QuadPass
from cloudcore.gl.reduced_clouds import ReducedClouds
from cloudcore.gl.shadow_map import CloudShadowMap
from cloudcore.gl.splats import NEAREST_DEPTH_CORE, SplatPass
from cloudcore.gl.targets import TextureTarget
from cloudcore.gl.volume_blending import GpuFeatures, VolumeBlendingPass
from cloudcore.gl.world import WorldPass
from cloudcore.light.air_between import air_between
from cloudcore.light.cloud_shadows import FIELD_MAP_RESOLUTION, MAP_RESOLUTION, PREVIEW_MAP_RESOLUTION
from cloudcore.light.ground_shadows import steady_map
from cloudcore.light.illumination import IlluminationCache, shadowing_sun
from cloudcore.light.light_shafts import nearest_depth_particles
from cloudcore.light.lighting import scene_lights
from cloudcore.light.live_air import LiveAir
from cloudcore.light.relighting import PREVIEW_METHOD, dragged_look_settings
from cloudcore.light.sky_background import SkyBackground, scene_sky
from cloudcore.light.splat_look import SplatLook
from cloudcore.light.terrain_light import terrain_light
from cloudcore.lod.costs import CostEstimator, CostModel, remember_fit, remembered_prior
from cloudcore.lod.plan import FramePlan, LodState, plan_frame
from cloudcore.lod.splat_coverage import analytic_overdraw
from cloudcore.lod.units import LodUnits
from cloudcore.maths.colour import linear_to_srgb8
from cloudcore.model.scene import Camera, Lighting, Scene
from cloudcore.model.settings import COMPOSITING_WAYS, FULL_3D, RenderSettings
from cloudcore.particles.buffer import ParticleBuffer
from cloudcore.particles.frame_clouds import FrameClouds, PreparedClouds
from cloudcore.runtime.derived import Derived
from cloudcore.stats.frame_stats import FrameStats
from cloudcore.stats.overdraw import Overdraw, overdraw_statistics
from cloudcore.world.camera import NEAR_PLANE_M, frustum_planes, projection_matrix, view_matrix, view_rotation
from cloudcore.world.wind import reshapes


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
class _FrameScene:
    """A frame's scene made ready to plan: its lighting and eye, and its clouds prepared (`PreparedClouds`)."""

    lighting: Lighting
    camera: Camera
    clouds: PreparedClouds
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
        self._world_programs = ProgramCache()  # the world passes', kept across the lights that make them again
        self._objects: Derived[ObjectPass | None] = Derived(self._make_objects, ObjectPass.close)
        #: the clouds' transmittance map, and this frame's: None where the clouds shadow nothing
        self.shadow_map = CloudShadowMap()
        self._shadows: CloudShadowMap | None = None
        #: the clouds drawn: lit, carried by the wind, a field's for the eye, their units and keys
        self.clouds = FrameClouds(illumination if illumination is not None else IlluminationCache())
        self._air_for = air if air is not None else air_between
        self._sky_for = air.sky_seen_from if air is not None else SkyBackground.seen_from
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
        self._shadow_source = (None, MAP_RESOLUTION)  # the sun and the size of the clouds' transmittance map
        self._steady_shadows = False  # whether it is a map the world pass bakes on the ground (`steady_map`)
        self._overdraw_target = None
        self._display = None  # (RGBA8 target, program): the frame in sRGB for the editor
        self.last_plan: FramePlan | None = None

    @property
    def units(self) -> LodUnits:
        """The units (clouds, or groups of interpenetrating clouds) of the scene last rendered, where the wind
        had carried them; a frame may plan some groups apart (`FramePlan.units`)."""
        return self.clouds.units

    @property
    def field_state(self) -> FieldState:
        """The cloud field's cells for the last eye under the weather in force, or coming during a change."""
        return self.clouds.field_state

    @property
    def weather_state(self) -> WeatherFieldState:
        """The cloud field's cells made for the last eye under each weather over it (`cloudcore.field.weather`)."""
        return self.clouds.weather_state

    @property
    def particles(self) -> ParticleBuffer:
        """The particle buffer of the scene last rendered, where the wind had carried it."""
        return self.clouds.particles

    @property
    def light_shafts(self) -> LightShaftPass | None:
        """The world pass's light shafts, once a frame has drawn them (tests read their march)."""
        return None if self._world.value is None else self._world.value.light_shafts

    @property
    def ground_shadows(self) -> GroundShadows | None:
        """The world pass's clouds' shadow baked on the ground, where it has a terrain (tests read the texture)."""
        return None if self._world.value is None else self._world.value.ground_shadows

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
        if illumination_method == PREVIEW_METHOD:
            settings = dragged_look_settings(settings)
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
        """The authored clouds of `scene` as a frame lit at `lit_at` draws them (`FrameClouds.drawn_clouds`)."""
        return self.clouds.drawn_clouds(scene, lit_at)

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
                frame = self._draw_world(frame)
            # the world pass uploaded the air for this eye: the ring's segments and the cloud pass's splats take it
            self._splats.air = None if frame.air is None else frame.air[0]
            self._splats.look = SplatLook.of(settings)
            with clock.timed("impostor updates"):
                rendered = self._impostors.update(
                    frame.plan, frame.particles, settings, time_s, frame.splat_order, self.clouds.unit_weights
                )
            with clock.timed("clouds"):
                self.context.bind_target()
                # the cloud pass's splats less the light shafts' share of their air, where the world marched them
                # (not the ring's segments, made from the ring's eye for other eyes)
                self._splats.shafts = frame.shafts
                drawn = self._cloud_pass.draw(frame)
                self._splats.shafts = None
        drawn_by_gpu, rendered_by_gpu = self._splats.take_selected()
        self._observe(
            frame, drawn.compositable, drawn.particles + drawn_by_gpu + rendered + rendered_by_gpu, before_passes_ms
        )
        return self._statistics(
            frame, ready.illumination_ms, before_passes_ms, drawn, drawn_by_gpu, rendered + rendered_by_gpu
        )

    def _prepare(self, asked: _Asked) -> _FrameScene:
        """The frame's scene made ready (`_FrameScene`), and every resource made from it in step with it: the world
        pass, the objects' pass, the clouds (`FrameClouds.prepare`) and their shadows' map."""
        scene, time_of_day, settings = asked.scene, asked.time_of_day, asked.settings
        lighting = (
            scene.lighting if time_of_day is None else dataclasses.replace(scene.lighting, time_of_day=time_of_day)
        )
        camera = scene.camera if asked.camera is None else asked.camera
        lights, ambient = scene_lights(lighting)
        # a dragged slider's look (the editor's preview) draws the coarse sky, as its clouds are a coarse raster
        preview = asked.illumination_method == PREVIEW_METHOD
        self._world.follow((scene.terrain, lighting, preview), lights, ambient)
        self._objects.follow((scene.objects, lights, tuple(ambient), self.size), ambient)
        clouds = self.clouds.prepare(
            scene,
            camera,
            lighting,
            lights,
            ambient,
            asked.illumination_method,
            settings,
            asked.time_s,
            asked.lit_at,
        )
        # the clouds shadow the sun's (the first light's) beam where there are clouds and it shines
        sun = shadowing_sun(lights) if settings.cloud_shadows else None
        self._shadows = None if sun is None or not clouds.scene.clouds else self.shadow_map
        self._shadow_source = (
            sun,
            PREVIEW_MAP_RESOLUTION if preview else FIELD_MAP_RESOLUTION if scene.cloud_field else MAP_RESOLUTION,
        )
        illumination_ms = clouds.illumination_ms + self._update_shadows(
            clouds, asked.time_s, preview=preview, field=bool(scene.cloud_field)
        )
        return _FrameScene(lighting, camera, clouds, illumination_ms)

    def _plan(self, ready: _FrameScene, settings: RenderSettings, time_s: float, costs) -> CloudPassFrame:
        """Plan the frame (`plan_frame`), resolve its "auto" ways, and turn Wang's sprites to the eye; what the
        cloud pass's draws share."""
        objects = self._objects.value
        poses = objects.poses(time_s) if objects is not None else ()
        camera, clouds = ready.camera, ready.clouds
        particles = clouds.particles
        starts = particles.cloud_starts
        cloud_keys, ring_keys = self.clouds.cloud_keys(
            clouds.scene, clouds.fade_keys, time_s, SplatLook.of(settings).key
        )
        ring_keys = self.clouds.ring_keys_under_wind(ring_keys, clouds.motion, settings)
        plan = plan_frame(
            clouds.units,
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
            clouds.motion,
        )
        self.last_plan = plan
        view = view_matrix(camera)
        projection = projection_matrix(camera.fov_y_deg, self.context.width / self.context.height)
        # in the editor's context the GUI leaves its scissor rectangle on, which would clip our targets
        GL.glDisable(GL.GL_SCISSOR_TEST)
        for start, facing in self.clouds.lit.value.facings.update(camera.position, particles):
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
            self.clouds.unit_weights,
        )

    def _draw_world(self, frame: CloudPassFrame) -> CloudPassFrame:
        """The world pass: terrain and sky, and the objects outside the clouds the plan splits; `frame` with the
        light shafts it marched, cut at the clouds the plan draws (`FrameShafts`), where it marched them."""
        settings = frame.settings
        world = self._world.value
        marched = world.draw(
            self.context,
            frame.camera,
            frame.view,
            frame.projection,
            antialiased=settings.world_antialiasing,
            through_air=settings.aerial_perspective,
            shadows=self._shadows,
            steady_shadows=self._steady_shadows,
            light_shafts=settings.light_shafts,
            draw_cloud_depth=self._cloud_depth_drawer(frame),
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
        if marched is None:
            return frame
        return dataclasses.replace(frame, shafts=FrameShafts(marched, frame.projection @ view_rotation(frame.view)))

    def _cloud_depth_drawer(self, frame: CloudPassFrame):
        """What draws the nearest depth of the clouds the plan draws (not the ring's: its segments hold their air
        from the ring's eye) at the light shafts' march size, for the march to end its rays there (Yusov's cut)."""
        plan, particles = frame.plan, frame.particles

        def draw(size: tuple[int, int]) -> None:
            drawn = list(plan.draw_order)
            units = plan.units if plan.units is not None else self.clouds.units
            # a march pixel spans the view's height over its rows
            pixels_per_radian = size[1] / (2.0 * np.arctan(1.0 / frame.projection[1, 1]))
            chosen = nearest_depth_particles(
                [plan.clouds[unit].members for unit in drawn],
                particles.cloud_starts,
                units.centres[drawn],
                units.radii[drawn],
                units.radius_squares[drawn] / np.maximum(units.particle_counts[drawn], 1),
                NEAREST_DEPTH_CORE,
                frame.eye,
                pixels_per_radian,
            )
            self._splats.draw_nearest_depth(
                particles, frame.time_s, chosen, frame.eye, frame.view, frame.projection, size[1]
            )

        return draw

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

    def _make_world(self, source: tuple, lights, ambient) -> WorldPass:
        """The world pass of `source` (terrain, lighting, whether the sky is the preview's)."""
        terrain, lighting, preview = source
        return WorldPass(
            terrain,
            terrain_light(lighting, lights, ambient),
            scene_sky(lighting, preview),
            self._air_for,
            self._sky_for,
            programs=self._world_programs,
        )

    def _make_objects(self, source: tuple, ambient) -> ObjectPass | None:
        """The objects' pass of `source` (objects, lights, ambient, frame size); None without objects."""
        objects, lights, _, size = source
        return ObjectPass(objects, lights, ambient, size) if objects else None

    def _update_shadows(self, clouds: PreparedClouds, time_s: float, *, preview: bool, field: bool) -> float:
        """Make the clouds' transmittance map again for another particle buffer, sun or size, or when the clouds'
        opacities change (`CloudShadowMap.update`): every frame while a cloud forms or dissipates, when a field's
        clouds' blend weights leave their steps (`fade_keys`: they fade in and out, their shadows with them), never
        while none does; ms spent making it (0 when it was held).  A wind that moves every cloud alike moves the map
        made of their buffer at rest with them; one that changes them otherwise makes it again each frame, of the
        particles where they are (carried, weighed).  Whether the world pass bakes the map on the ground
        (`steady_map`) follows from it: not a dragged slider's look's (`preview`), nor a cloud `field`'s."""
        if self._shadows is None:
            return 0.0
        start, made = time.perf_counter(), self.shadow_map.made
        forming = self.clouds.forming(clouds.scene, time_s)
        opacity = (clouds.particles.opacity_factors(time_s), (forming, clouds.fade_keys))
        motion = clouds.motion
        self._steady_shadows = steady_map(preview, field, moving=motion is not None, forming=bool(forming))
        if motion is not None and not reshapes(motion.wind):
            at_rest = self.clouds.lit.value.particles
            self.shadow_map.update(at_rest, *self._shadow_source, *opacity, motion.drifts[0])
        else:
            self.shadow_map.update(clouds.particles, *self._shadow_source, *opacity)
        self.context.bind_target()
        return 1e3 * (time.perf_counter() - start) if self.shadow_map.made != made else 0.0

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
        self._world_programs.close()
        self._objects.close()
        self.context.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


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
