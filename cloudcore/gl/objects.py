"""The scene's opaque objects: drawn by pyrender, lit by the scene's lights, composited into the frame.

pyrender draws the objects asked for into a target of our own (RGBA8 colour
and a depth texture); one full-screen pass then blends them into the linear
frame at their own depth, tested against the frame's depth so terrain stays
in front.  Objects outside clouds are composited once after the world with
their depth written, so the clouds behind them are hidden; an object inside
a split cloud is composited between its layers without writing depth, so
the layers in front of it cover it whole and no billboard cuts through it
(`cloudcore.lod.splitting`).

Where the clouds shadow them, pyrender draws them twice: lit by the sun (the first light) alone into a second
colour target, then by the rest; the composite adds the sun's picture times the clouds' transmittance map at each
pixel's place (`cloudcore.gl.shadow_map`).
"""

from __future__ import annotations

import math

import numpy as np
from OpenGL import GL

from cloudcore.gl.air_volume import AirVolume
from cloudcore.gl.programs import build_program, set_matrix, set_vec3
from cloudcore.gl.pyrender_compat import pyrender
from cloudcore.gl.shadow_map import CloudShadowMap
from cloudcore.light.lighting import active_lights
from cloudcore.model.scene import Camera
from cloudcore.world.camera import (
    FAR_PLANE_M,
    NEAR_PLANE_M,
    camera_pose,
    points_in_eye_space,
    projection_matrix,
    view_matrix,
)
from cloudcore.world.objects import mesh_sphere, object_mesh, object_poses

_UP = np.array([0.0, 1.0, 0.0])


class ObjectPass:
    """Objects of one scene under one lighting; rebuild it when either changes."""

    def __init__(self, objects, lights, ambient, size: tuple[int, int]):
        """`size`: the frame's, which the objects' colour and depth targets match."""
        self.objects = tuple(objects)
        meshes = [object_mesh(obj) for obj in self.objects]
        self._spheres = [mesh_sphere(mesh) for mesh in meshes]
        self._ambient = np.asarray(ambient)
        self._scene = pyrender.Scene(bg_color=(0.0, 0.0, 0.0, 0.0), ambient_light=self._ambient)
        #: (pyrender light, its intensity) of each light that gives some; the first the sun where it does
        self._lights = []
        for light in active_lights(lights):
            # pyrender's diffuse term is albedo / pi: pi * intensity gives the terrain's Lambert shading
            node = pyrender.DirectionalLight(color=np.asarray(light.color), intensity=math.pi * light.intensity)
            self._scene.add(node, pose=_light_pose(np.asarray(light.direction, dtype=np.float64)))
            self._lights.append((node, node.intensity))
        self._sun_shines = bool(lights) and bool(active_lights(tuple(lights)[:1]))
        self._nodes = []
        for obj, mesh in zip(self.objects, meshes):
            material = pyrender.MetallicRoughnessMaterial(
                baseColorFactor=(*obj.color, 1.0), metallicFactor=0.0, roughnessFactor=1.0
            )
            self._nodes.append(self._scene.add(pyrender.Mesh.from_trimesh(mesh, material=material, smooth=False)))
        self._camera_node = self._scene.add(pyrender.PerspectiveCamera(yfov=1.0, znear=NEAR_PLANE_M, zfar=FAR_PLANE_M))
        self._program = build_program("objects", vertex="world")
        self._vertex_array = GL.glGenVertexArrays(1)
        self._colour, self._depth, self._framebuffer = _colour_and_depth_target(*size)
        self._size = size
        self._sun_target: tuple[int, int] | None = None  # (colour, framebuffer) of the sun's picture, once drawn

    def poses(self, time_s: float):
        return object_poses(self.objects, time_s, self._spheres)

    def draw(
        self,
        context,
        camera: Camera,
        poses,
        which,
        *,
        write_depth: bool,
        antialiased: bool = False,
        air: AirVolume | None = None,
        shadows: CloudShadowMap | None = None,
    ) -> None:
        """Composite the objects `which` (indices) at `poses` into the bound frame target (multisampled 4x
        when `antialiased`), seen through `air` (uploaded for `camera`'s eye) where there is one, in the clouds'
        `shadows` where given."""
        which = set(which)
        drawn = [poses[index] for index in sorted(which)]
        box = scissor_box(drawn, camera, (context.width, context.height))
        if box is None:  # none of them on the screen
            return
        for index, (node, pose) in enumerate(zip(self._nodes, poses)):
            node.mesh.is_visible = index in which
            self._scene.set_pose(node, pose.model)
        self._camera_node.camera.yfov = math.radians(camera.fov_y_deg)
        self._scene.set_pose(self._camera_node, camera_pose(camera))
        sun_apart = shadows is not None and self._sun_shines
        if sun_apart:
            self._render_sun_alone(context, antialiased)
        context.render_pyrender_scene(
            self._scene, pyrender.RenderFlags.NONE, self._framebuffer, antialiased=antialiased
        )
        self._set_lights(sun=True, rest=True)
        GL.glUseProgram(self._program)
        # the units objects.frag.glsl declares
        sun_colour = self._sun_target[0] if sun_apart else 0
        for unit, texture in enumerate((self._colour, self._depth, sun_colour)):
            GL.glActiveTexture(GL.GL_TEXTURE0 + unit)
            GL.glBindTexture(GL.GL_TEXTURE_2D, texture)
        GL.glActiveTexture(GL.GL_TEXTURE0)
        GL.glUniform1i(GL.glGetUniformLocation(self._program, "through_air"), int(air is not None))
        GL.glUniform1i(GL.glGetUniformLocation(self._program, "sun_apart"), int(sun_apart))
        if sun_apart:
            shadows.bind(self._program)
        if air is not None or sun_apart:
            view_projection = projection_matrix(camera.fov_y_deg, context.width / context.height) @ view_matrix(camera)
            set_matrix(self._program, "inverse_view_projection", np.linalg.inv(view_projection))
        if air is not None:
            air.bind(self._program)
            set_vec3(self._program, "eye_position", camera.position)
        GL.glEnable(GL.GL_DEPTH_TEST)
        GL.glDepthFunc(GL.GL_LESS)
        GL.glDepthMask(GL.GL_TRUE if write_depth else GL.GL_FALSE)
        GL.glEnable(GL.GL_BLEND)
        GL.glBlendFunc(GL.GL_ONE, GL.GL_ONE_MINUS_SRC_ALPHA)
        # the full-screen composite within the objects' box alone: llvmpipe pays a pixel's lookups (the air, the
        # shadows) whether or not an object covers it, and an aircraft covers a few percent of the screen
        GL.glEnable(GL.GL_SCISSOR_TEST)
        GL.glScissor(*box)
        GL.glBindVertexArray(self._vertex_array)
        GL.glDrawArrays(GL.GL_TRIANGLES, 0, 3)
        GL.glBindVertexArray(0)
        GL.glDisable(GL.GL_SCISSOR_TEST)
        GL.glDepthMask(GL.GL_TRUE)
        GL.glDisable(GL.GL_BLEND)

    def _render_sun_alone(self, context, antialiased: bool) -> None:
        """The objects lit by the sun alone into the sun's target (its depth the main target's, which the second
        picture writes again alike); then the lights are left for the rest."""
        if self._sun_target is None:
            self._sun_target = _sun_target(self._depth, *self._size)
        self._set_lights(sun=True, rest=False)
        context.render_pyrender_scene(
            self._scene, pyrender.RenderFlags.NONE, self._sun_target[1], antialiased=antialiased
        )
        self._set_lights(sun=False, rest=True)

    def _set_lights(self, *, sun: bool, rest: bool) -> None:
        """Light the scene by the sun (the first light, where it shines), the rest (the other lights and the
        ambient), or both."""
        for index, (node, intensity) in enumerate(self._lights):
            node.intensity = intensity if (sun if index == 0 and self._sun_shines else rest) else 0.0
        self._scene.ambient_light = self._ambient if rest else np.zeros(3)

    def close(self) -> None:
        """Free our GL objects (the context must be current); pyrender frees the meshes with its context."""
        GL.glDeleteProgram(self._program)
        GL.glDeleteVertexArrays(1, [self._vertex_array])
        GL.glDeleteFramebuffers(1, [self._framebuffer])
        GL.glDeleteTextures([self._colour, self._depth])
        if self._sun_target is not None:
            GL.glDeleteFramebuffers(1, [self._sun_target[1]])
            GL.glDeleteTextures([self._sun_target[0]])


def _light_pose(direction: np.ndarray) -> np.ndarray:
    """A pose whose -z axis points along the light's travel (from the light, -direction)."""
    back = direction / np.linalg.norm(direction)
    side = np.cross(_UP, back)
    side = side / np.linalg.norm(side) if np.linalg.norm(side) > 1e-9 else np.array([1.0, 0.0, 0.0])
    pose = np.eye(4)
    pose[:3, 0], pose[:3, 1], pose[:3, 2] = side, np.cross(back, side), back
    return pose


def _colour_and_depth_target(width: int, height: int) -> tuple[int, int, int]:
    """(RGBA8 colour texture, DEPTH_COMPONENT24 texture, framebuffer): pyrender's formats, sampleable."""
    textures = GL.glGenTextures(2)
    for texture, internal_format in zip(textures, (GL.GL_RGBA8, GL.GL_DEPTH_COMPONENT24)):
        GL.glBindTexture(GL.GL_TEXTURE_2D, texture)
        GL.glTexStorage2D(GL.GL_TEXTURE_2D, 1, internal_format, width, height)
        GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MIN_FILTER, GL.GL_NEAREST)
        GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MAG_FILTER, GL.GL_NEAREST)
    framebuffer = GL.glGenFramebuffers(1)
    GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, framebuffer)
    GL.glFramebufferTexture2D(GL.GL_FRAMEBUFFER, GL.GL_COLOR_ATTACHMENT0, GL.GL_TEXTURE_2D, textures[0], 0)
    GL.glFramebufferTexture2D(GL.GL_FRAMEBUFFER, GL.GL_DEPTH_ATTACHMENT, GL.GL_TEXTURE_2D, textures[1], 0)
    status = GL.glCheckFramebufferStatus(GL.GL_FRAMEBUFFER)
    if status != GL.GL_FRAMEBUFFER_COMPLETE:
        raise RuntimeError(f"objects framebuffer incomplete (status 0x{int(status):x})")
    return int(textures[0]), int(textures[1]), framebuffer


def _sun_target(depth: int, width: int, height: int) -> tuple[int, int]:
    """(RGBA8 colour texture, framebuffer) for the objects lit by the sun alone, sharing the objects' `depth`."""
    colour = int(GL.glGenTextures(1))
    GL.glBindTexture(GL.GL_TEXTURE_2D, colour)
    GL.glTexStorage2D(GL.GL_TEXTURE_2D, 1, GL.GL_RGBA8, width, height)
    GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MIN_FILTER, GL.GL_NEAREST)
    GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MAG_FILTER, GL.GL_NEAREST)
    framebuffer = GL.glGenFramebuffers(1)
    GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, framebuffer)
    GL.glFramebufferTexture2D(GL.GL_FRAMEBUFFER, GL.GL_COLOR_ATTACHMENT0, GL.GL_TEXTURE_2D, colour, 0)
    GL.glFramebufferTexture2D(GL.GL_FRAMEBUFFER, GL.GL_DEPTH_ATTACHMENT, GL.GL_TEXTURE_2D, depth, 0)
    status = GL.glCheckFramebufferStatus(GL.GL_FRAMEBUFFER)
    if status != GL.GL_FRAMEBUFFER_COMPLETE:
        raise RuntimeError(f"objects' sun framebuffer incomplete (status 0x{int(status):x})")
    return colour, framebuffer


#: the corners of a cube of half side 1 about the origin
_CUBE_CORNERS = np.array([[x, y, z] for x in (-1.0, 1.0) for y in (-1.0, 1.0) for z in (-1.0, 1.0)])


def scissor_box(poses, camera: Camera, size: tuple[int, int]) -> tuple[int, int, int, int] | None:
    """(x, y, width, height), GL's from the bottom left: pixels that hold every pixel the bounding spheres of
    `poses` can cover, the image of the cubes around them (a sphere's image lies within its cube's, the cube wholly
    in front of the eye); the whole target where a cube reaches the near plane; None where none is on the screen."""
    width, height = size
    centres = np.array([pose.centre for pose in poses], dtype=np.float64).reshape(-1, 3)
    radii = np.array([pose.radius for pose in poses], dtype=np.float64)
    eye = points_in_eye_space(centres, view_matrix(camera))
    ahead = -eye[:, 2] + radii > NEAR_PLANE_M  # the rest wholly behind the near plane
    eye, radii = eye[ahead], radii[ahead]
    if not len(radii):
        return None
    # a cube's nearest corner is sqrt(3) radii nearer than its centre at most
    if np.any(-eye[:, 2] - np.sqrt(3.0) * radii <= NEAR_PLANE_M):
        return (0, 0, width, height)
    corners = (eye[:, None, :] + radii[:, None, None] * _CUBE_CORNERS).reshape(-1, 3)
    projection = projection_matrix(camera.fov_y_deg, width / height)
    ndc = (corners[:, :2] * np.diag(projection)[:2]) / -corners[:, 2:3]
    low = np.floor((np.clip(ndc.min(axis=0), -1.0, 1.0) + 1.0) * 0.5 * np.array([width, height])).astype(int)
    high = np.ceil((np.clip(ndc.max(axis=0), -1.0, 1.0) + 1.0) * 0.5 * np.array([width, height])).astype(int)
    if np.any(high <= low):
        return None
    return (int(low[0]), int(low[1]), int(high[0] - low[0]), int(high[1] - low[1]))
