"""The world pass: terrain through pyrender (flat, its light baked per vertex) over the sky, seen through the air.

pyrender's PBR shader costs 70-90 ms a frame on llvmpipe; baking the lights into
vertex colours and drawing with RenderFlags.FLAT costs about a quarter of that
(measured: /work/shared/ENVIRONMENT.md).  pyrender writes the depth buffer the
cloud pass tests against; one full-screen pass then composites its colour over
the sky into the linear target (shaders/world.frag.glsl).  Under the physical sky that pass also
adds the air between the eye and the terrain (aerial perspective, `cloudcore.light.air_between`): it reads the
terrain's depth from a copy (the target's depth is a renderbuffer, shared with the cloud passes' targets).  Where
the clouds shadow the terrain (`sun_apart`) the vertex colours hold the light less the sun's, and the sun's part
(per heightfield vertex, a texture over the terrain) is added per pixel times the clouds' transmittance map at the
pixel's place (`cloudcore.gl.shadow_map`).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import trimesh
from OpenGL import GL

from cloudcore.atmosphere.geometry import horizon_cosine
from cloudcore.atmosphere.sky_view import eye_radius, horizon_angles
from cloudcore.camera import FAR_PLANE_M, NEAR_PLANE_M, camera_pose
from cloudcore.colour import srgb_encode
from cloudcore.gl.air_volume import AirVolume
from cloudcore.gl.context import HeadlessContext
from cloudcore.gl.programs import build_program, set_matrix, set_vec3
from cloudcore.gl.pyrender_compat import pyrender
from cloudcore.gl.shadow_map import CloudShadowMap
from cloudcore.light.air_between import air_between
from cloudcore.light.sky_background import SkyBackground
from cloudcore.light.terrain_light import TerrainLight
from cloudcore.limits import DRAWN_TERRAIN_KINDS
from cloudcore.scene import Camera, Terrain
from cloudcore.terrain import heightfield_mesh

#: the terrain's depth's and its sun's part's texture units, as world.frag.glsl declares them (the world's colour 0,
#: the sky-view table 1, the air's volume `AIR_UNITS`, the clouds' shadows `SHADOW_UNITS`)
_DEPTH_UNIT, _SUN_UNIT = 2, 7


@functools.lru_cache(maxsize=2)
def terrain_geometry(terrain: Terrain) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(vertices, faces, vertex normals) of a heightfield terrain: kept across lighting changes, which
    rebuild the world pass (the editor's time of day) and would rebuild these for 25 ms each time."""
    vertices, faces = heightfield_mesh(terrain)
    return vertices, faces, trimesh.Trimesh(vertices, faces, process=False).vertex_normals


def terrain_vertex_colours(normals, base_colour, light: TerrainLight, sun_apart: bool = False) -> np.ndarray:
    """Linear RGB per vertex: base * the irradiance `light` gives each vertex's normal (less the sun's part when
    `sun_apart`)."""
    return np.asarray(base_colour, dtype=np.float64) * light.irradiance(normals, 0.0 if sun_apart else 1.0)


class WorldPass:
    """Terrain and sky for one terrain and one lighting; rebuild it when either changes."""

    def __init__(self, terrain: Terrain | None, light: TerrainLight, sky: SkyBackground, sun_apart: bool = False):
        """`sun_apart`: the terrain's sun's part apart from the rest, for the clouds' shadows to scale (`draw`'s
        `shadows`)."""
        self._sky = sky
        self._composite_program = build_program("world")
        self._sky_view_texture = _sky_view_texture(sky) if sky.physical else None
        # core profile draws nothing without a vertex array, even one with no attributes
        self._fullscreen_vertex_array = GL.glGenVertexArrays(1)
        self._scene = None
        self._sun_texture = None  # the terrain's sun's part per heightfield vertex, where it is apart
        if terrain is not None:
            self._scene, self._camera_node = self._terrain_scene(terrain, light, sun_apart)
            self._sun_texture = _terrain_sun_texture(terrain, light) if sun_apart else None
        # the air's volume under the physical sky (the cloud pass reads it too: `air_volume`), and the terrain's
        # depth, which the terrain is seen through it by
        self._air_volume = AirVolume() if sky.physical else None
        self._depth_copy, self._depth_copy_size = None, None
        self._depth_copied = False  # this draw's depth is in the copy

    @staticmethod
    def _terrain_scene(terrain: Terrain, light: TerrainLight, sun_apart: bool):
        if terrain.kind not in DRAWN_TERRAIN_KINDS:  # the scene loader refuses these first (cloudcore.limits)
            raise ValueError(f"the GL prototype draws heightfield terrain only, not {terrain.kind!r}")
        vertices, faces, normals = terrain_geometry(terrain)
        colours = terrain_vertex_colours(normals, terrain.color, light, sun_apart)
        # encoded, because pyrender's 8-bit framebuffer would band linear colour in the shadows
        primitive = pyrender.Primitive(
            positions=vertices.astype(np.float32),
            indices=faces.astype(np.uint32),
            color_0=srgb_encode(colours).astype(np.float32),
        )
        scene = pyrender.Scene(bg_color=(0.0, 0.0, 0.0, 0.0))
        scene.add(pyrender.Mesh([primitive]))
        camera = pyrender.PerspectiveCamera(yfov=np.radians(60.0), znear=NEAR_PLANE_M, zfar=FAR_PLANE_M)
        return scene, scene.add(camera)

    def draw(
        self,
        context: HeadlessContext,
        camera: Camera,
        view_projection: np.ndarray,
        *,
        antialiased: bool = False,
        through_air: bool = True,
        shadows: CloudShadowMap | None = None,
    ) -> None:
        """Fill the render target: terrain colour and depth where there is terrain, sky elsewhere (the terrain
        multisampled 4x when `antialiased`, seen through the air under the physical sky when `through_air`, its
        sun's part, where apart, in the clouds' `shadows` where given)."""
        self._depth_copied = False
        if self._scene is None:
            context.clear_world()
        else:
            # the aspect ratio comes from the viewport, as in our projection_matrix
            self._camera_node.camera.yfov = np.radians(camera.fov_y_deg)
            self._scene.set_pose(self._camera_node, camera_pose(camera))
            context.render_pyrender_scene(self._scene, pyrender.RenderFlags.FLAT, antialiased=antialiased)
        program = self._composite_program
        GL.glUseProgram(program)
        GL.glActiveTexture(GL.GL_TEXTURE0)
        GL.glBindTexture(GL.GL_TEXTURE_2D, context.world_texture)
        set_matrix(program, "inverse_view_projection", np.linalg.inv(view_projection))
        self._set_sky_uniforms(program, camera)
        self._set_air_uniforms(program, context, camera, through_air)
        self._set_sun_uniforms(program, context, shadows)
        GL.glDisable(GL.GL_BLEND)
        GL.glDisable(GL.GL_CULL_FACE)
        GL.glDisable(GL.GL_DEPTH_TEST)  # colour everywhere; the depth pyrender wrote stays
        GL.glBindVertexArray(self._fullscreen_vertex_array)
        GL.glDrawArrays(GL.GL_TRIANGLES, 0, 3)
        GL.glBindVertexArray(0)

    def _set_sky_uniforms(self, program: int, camera: Camera) -> None:
        sky = self._sky
        GL.glUniform1i(GL.glGetUniformLocation(program, "physical_sky"), int(sky.physical))
        if not sky.physical:
            set_vec3(program, "zenith_colour", sky.zenith)
            set_vec3(program, "horizon_colour", sky.horizon)
            return
        params = sky.view.tables.params
        r = eye_radius(params, sky.view.altitude_m)
        _, zenith_horizon = horizon_angles(params, r)
        GL.glActiveTexture(GL.GL_TEXTURE1)
        GL.glBindTexture(GL.GL_TEXTURE_2D, self._sky_view_texture)
        height, width = sky.view.table.shape[:2]
        GL.glUniform2f(GL.glGetUniformLocation(program, "sky_view_size"), float(width), float(height))
        GL.glUniform1f(GL.glGetUniformLocation(program, "zenith_horizon_angle"), float(zenith_horizon))
        GL.glUniform1f(
            GL.glGetUniformLocation(program, "horizon_cosine"), float(horizon_cosine(r, params.bottom_radius_m))
        )
        set_vec3(program, "sun_direction", sky.view.sun_direction)
        set_vec3(program, "sun_disc_scale", sky.sun_disc_scale())
        viewport_height = int(GL.glGetIntegerv(GL.GL_VIEWPORT)[3])
        GL.glUniform1f(
            GL.glGetUniformLocation(program, "pixel_angle"),
            float(np.radians(camera.fov_y_deg) / max(viewport_height, 1)),
        )
        GL.glActiveTexture(GL.GL_TEXTURE0)

    def _set_air_uniforms(self, program: int, context: HeadlessContext, camera: Camera, through_air: bool) -> None:
        terrain_through_air = through_air and self._air_volume is not None and self._scene is not None
        GL.glUniform1i(GL.glGetUniformLocation(program, "through_air"), int(terrain_through_air))
        if self._air_volume is None or not through_air:
            return
        self._air_volume.upload(air_between(self._sky, camera.position))
        if not terrain_through_air:
            return
        self._air_volume.bind(program)
        GL.glActiveTexture(GL.GL_TEXTURE0 + _DEPTH_UNIT)
        GL.glBindTexture(GL.GL_TEXTURE_2D, self._copy_depth(context))
        GL.glActiveTexture(GL.GL_TEXTURE0)
        set_vec3(program, "eye_position", camera.position)

    def _set_sun_uniforms(self, program: int, context: HeadlessContext, shadows: CloudShadowMap | None) -> None:
        sun_apart = self._sun_texture is not None
        GL.glUniform1i(GL.glGetUniformLocation(program, "sun_apart"), int(sun_apart))
        if not sun_apart:
            return
        GL.glActiveTexture(GL.GL_TEXTURE0 + _SUN_UNIT)
        GL.glBindTexture(GL.GL_TEXTURE_2D, self._sun_texture.texture)
        GL.glActiveTexture(GL.GL_TEXTURE0 + _DEPTH_UNIT)
        GL.glBindTexture(GL.GL_TEXTURE_2D, self._copy_depth(context))
        GL.glActiveTexture(GL.GL_TEXTURE0)
        GL.glUniform2f(GL.glGetUniformLocation(program, "terrain_sun_origin"), *self._sun_texture.origin)
        GL.glUniform2f(GL.glGetUniformLocation(program, "terrain_sun_spacing"), *self._sun_texture.spacing)
        if shadows is None:
            GL.glUniform1i(GL.glGetUniformLocation(program, "cloud_shadows"), 0)
        else:
            shadows.bind(program)

    @property
    def air_volume(self) -> AirVolume | None:
        """The air's volume as the last `draw` uploaded it, for its eye; None under the gradient sky."""
        return self._air_volume

    def _copy_depth(self, context: HeadlessContext) -> int:
        """The depth pyrender wrote, copied into a texture of the target's size (made at the first draw and
        whenever that size changes; copied once a draw, however many read it); the target stays bound."""
        size = (context.width, context.height)
        if self._depth_copied:
            return self._depth_copy
        self._depth_copied = True
        if self._depth_copy_size != size:
            if self._depth_copy is not None:
                GL.glDeleteTextures([self._depth_copy])
            self._depth_copy = GL.glGenTextures(1)
            GL.glBindTexture(GL.GL_TEXTURE_2D, self._depth_copy)
            GL.glTexStorage2D(GL.GL_TEXTURE_2D, 1, GL.GL_DEPTH_COMPONENT24, *size)
            GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MIN_FILTER, GL.GL_NEAREST)
            GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MAG_FILTER, GL.GL_NEAREST)
            self._depth_copy_size = size
        GL.glBindTexture(GL.GL_TEXTURE_2D, self._depth_copy)
        GL.glCopyTexSubImage2D(GL.GL_TEXTURE_2D, 0, 0, 0, 0, 0, *size)
        return self._depth_copy

    def close(self) -> None:
        """Free the GL objects (the context must be current); pyrender frees the mesh with its context."""
        if self._sky_view_texture is not None:
            GL.glDeleteTextures([self._sky_view_texture])
        if self._air_volume is not None:
            self._air_volume.close()
        if self._depth_copy is not None:
            GL.glDeleteTextures([self._depth_copy])
        if self._sun_texture is not None:
            GL.glDeleteTextures([self._sun_texture.texture])
        GL.glDeleteProgram(self._composite_program)
        GL.glDeleteVertexArrays(1, [self._fullscreen_vertex_array])


def _sky_view_texture(sky: SkyBackground) -> int:
    """The sky-view table in the renderer's values as a float texture, sampled linearly and clamped to its edge
    texels as `cloudcore.atmosphere.table_sampling` reads it."""
    texture = GL.glGenTextures(1)
    GL.glBindTexture(GL.GL_TEXTURE_2D, texture)
    for parameter, value in (
        (GL.GL_TEXTURE_MIN_FILTER, GL.GL_LINEAR),
        (GL.GL_TEXTURE_MAG_FILTER, GL.GL_LINEAR),
        (GL.GL_TEXTURE_WRAP_S, GL.GL_CLAMP_TO_EDGE),
        (GL.GL_TEXTURE_WRAP_T, GL.GL_CLAMP_TO_EDGE),
    ):
        GL.glTexParameteri(GL.GL_TEXTURE_2D, parameter, value)
    # row 0 of the table is v's first texel: GL's first row, so the shader reads it with the numpy side's (u, v)
    pixels = np.ascontiguousarray(sky.table(), dtype=np.float32)
    height, width = pixels.shape[:2]
    GL.glTexImage2D(GL.GL_TEXTURE_2D, 0, GL.GL_RGB32F, width, height, 0, GL.GL_RGB, GL.GL_FLOAT, pixels)
    GL.glBindTexture(GL.GL_TEXTURE_2D, 0)
    return texture


@dataclass(frozen=True)
class _TerrainSun:
    """The terrain's sun's part, linear RGB per heightfield vertex, as a texture over the terrain: vertex (i, j) at
    `origin` + (i, j) `spacing` (x, z) is texel (i, j)'s centre."""

    texture: int
    origin: tuple[float, float]
    spacing: tuple[float, float]


def _terrain_sun_texture(terrain: Terrain, light: TerrainLight) -> _TerrainSun:
    """base * the sun's irradiance on each vertex of the heightfield (`heightfield_mesh`'s grid: rows along z),
    read linearly between vertices as the vertex colours are."""
    vertices, _, normals = terrain_geometry(terrain)
    n = terrain.resolution
    sun = np.asarray(terrain.color, dtype=np.float64) * light.sun_irradiance(normals)
    texture = GL.glGenTextures(1)
    GL.glBindTexture(GL.GL_TEXTURE_2D, texture)
    for parameter, value in (
        (GL.GL_TEXTURE_MIN_FILTER, GL.GL_LINEAR),
        (GL.GL_TEXTURE_MAG_FILTER, GL.GL_LINEAR),
        (GL.GL_TEXTURE_WRAP_S, GL.GL_CLAMP_TO_EDGE),
        (GL.GL_TEXTURE_WRAP_T, GL.GL_CLAMP_TO_EDGE),
    ):
        GL.glTexParameteri(GL.GL_TEXTURE_2D, parameter, value)
    pixels = np.ascontiguousarray(sun.reshape(n, n, 3), dtype=np.float32)
    GL.glTexImage2D(GL.GL_TEXTURE_2D, 0, GL.GL_RGB32F, n, n, 0, GL.GL_RGB, GL.GL_FLOAT, pixels)
    GL.glBindTexture(GL.GL_TEXTURE_2D, 0)
    corner = vertices[0]
    spacing = (vertices[1, 0] - corner[0], vertices[n, 2] - corner[2])
    return _TerrainSun(int(texture), (float(corner[0]), float(corner[2])), tuple(float(v) for v in spacing))
