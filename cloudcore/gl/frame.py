"""A whole frame: world pass, cloud pass, read-back to 8-bit sRGB, with timings.

Everything is composed in linear light in a float target; the one transfer to
sRGB happens on read-back.  `FrameRenderer` keeps its context, GL objects,
terrain and precomputed cloud illumination between frames and rebuilds the
latter two only when the scene or lighting they came from changes.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np
from OpenGL import GL

from cloudcore.camera import NEAR_PLANE_M, projection_matrix, view_matrix
from cloudcore.gl.context import HeadlessContext
from cloudcore.eye_scattering import ParticleShading
from cloudcore.gl.splats import SplatPass
from cloudcore.colour import linear_to_srgb8
from cloudcore.gl.targets import TextureTarget
from cloudcore.gl.world import WorldPass
from cloudcore.lighting import scene_lights, sky_colors
from cloudcore.overdraw import analytic_overdraw, overdraw_statistics
from cloudcore.scene import Camera, Lighting, Scene

#: the sky needs an hour even when explicit lights replace the sun.
_DEFAULT_SKY_HOURS = Lighting().time_of_day


class FrameRenderer:
    """Renders scenes headlessly at a fixed size; use as a context manager or call close()."""

    def __init__(self, width: int, height: int):
        self.context = HeadlessContext(width, height)
        self.context.make_current()
        self._splats = SplatPass()
        self._world, self._world_source = None, None
        self._particles, self._particles_source = None, None
        self._overdraw_target = None
        self._last_view_projection = None

    def render(self, scene: Scene, *, time_of_day: float | None = None, camera: Camera | None = None,
               illumination_method: str = "exact") -> tuple[np.ndarray, dict]:
        """(sRGB uint8 (height, width, 3), stats); `time_of_day` and `camera` override the scene's."""
        lighting = scene.lighting if time_of_day is None else dataclasses.replace(
            scene.lighting, time_of_day=time_of_day)
        camera = scene.camera if camera is None else camera
        lights, ambient = scene_lights(lighting)
        stats = {"illumination_ms": 0.0}

        world_source = (scene.terrain, lighting)
        if world_source != self._world_source:
            self.context.make_current()
            if self._world is not None:
                self._world.close()
            hours = _DEFAULT_SKY_HOURS if lighting.time_of_day is None else lighting.time_of_day
            self._world = WorldPass(scene.terrain, lights, ambient, *sky_colors(hours))
            self._world_source = world_source
        particles_source = (scene.clouds, scene.shading, lighting, illumination_method)
        if particles_source != self._particles_source:
            start = time.perf_counter()
            self._particles = ParticleShading(scene.clouds, scene.shading, lights, ambient, illumination_method)
            self._particles_source = particles_source
            stats["illumination_ms"] = 1e3 * (time.perf_counter() - start)

        view = view_matrix(camera)
        projection = projection_matrix(camera.fov_y_deg, self.context.width / self.context.height)
        self._last_view_projection = view, projection
        start = time.perf_counter()
        self._world.draw(self.context, camera, projection @ view)
        GL.glFinish()
        world_done = time.perf_counter()
        stats |= self._splats.draw(self._particles, camera.position, view, projection)
        GL.glFinish()
        done = time.perf_counter()
        stats |= {"frame_ms": 1e3 * (done - start), "world_ms": 1e3 * (world_done - start),
                  "cloud_ms": 1e3 * (done - world_done)}
        return linear_to_srgb8(self.context.read_linear_rgb()), stats

    def measure_overdraw(self) -> tuple[np.ndarray, dict]:
        """(fragments per pixel (height, width) float32, statistics) of the last rendered frame's clouds.

        Replays the cloud pass into a float counter that shares the frame's
        depth, so fragments hidden by terrain are not counted; the analytic
        estimate of the same frame is reported beside the measurement.
        """
        if self._last_view_projection is None:
            raise RuntimeError("render a frame before measuring its overdraw")
        view, projection = self._last_view_projection
        self.context.make_current()
        if self._overdraw_target is None:
            self._overdraw_target = TextureTarget(self.context.width, self.context.height, GL.GL_R32F,
                                                  depth_renderbuffer=self.context.depth_renderbuffer)
        self._overdraw_target.bind_cleared()
        self._splats.count_fragments(view, projection)
        counts = self._overdraw_target.read()
        self.context.bind_target()
        stats = overdraw_statistics(counts)
        stats["overdraw_analytic"] = analytic_overdraw(self._splats.drawn_centres, self._splats.drawn_radii,
                                                       view, projection, NEAR_PLANE_M)
        return counts, stats

    def close(self) -> None:
        if self.context.renderer is None:
            return
        self.context.make_current()
        if self._overdraw_target is not None:
            self._overdraw_target.close()
        self._splats.close()
        if self._world is not None:
            self._world.close()
        self.context.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def render_full(scene: Scene, width: int, height: int, *, time_of_day: float | None = None,
                camera: Camera | None = None, illumination_method: str = "exact") -> tuple[np.ndarray, dict]:
    """Render one frame of `scene` in a context of its own; see `FrameRenderer.render`."""
    with FrameRenderer(width, height) as renderer:
        return renderer.render(scene, time_of_day=time_of_day, camera=camera,
                               illumination_method=illumination_method)
