"""The particles on the GPU: a `ParticleBuffer`'s per-particle terms uploaded once, and what the CPU keeps of them.

`ResidentParticles` uploads the buffer's centres, radii, scattering, ambient and incident light per light (the
shader's `Particle`), the part of that light a lit face sent back (where the light pass sends any), its clouds'
styles, the sprites' facing locks, the opacity factors of a scene time (a formation, a cloud field's blend
weights), Yusov's eye-pass profile rows and the bits of the particles a draw may leave out, each into a storage
buffer, when the particles change; the shading, the GPU's selection and the raster read them there.  On the CPU
it keeps per particle and per cloud what a draw is shaded and drawn by:
plain Gaussian splats (`cloudcore.particles.point_sprites.plain_splats`), atlas sprites, the shader features.
"""

from __future__ import annotations

import numpy as np
from OpenGL import GL

from cloudcore.artist.facing import FacingState
from cloudcore.artist.particle_styles import FACING_SPLAT, ParticleStyles
from cloudcore.artist.sprites import ATLAS_MAX_MIP_LEVEL, load_atlas
from cloudcore.gl.storage import store
from cloudcore.particles.batch import SplatBatch, SplatSelection
from cloudcore.particles.buffer import ParticleBuffer
from cloudcore.particles.point_sprites import plain_splats
from cloudcore.scenes.limits import MAX_LIGHTS

#: the shader's `Particle` in std430 layout: five vec4 then MAX_LIGHTS floats
PARTICLE_FLOATS = 20 + MAX_LIGHTS
#: the shader's `CloudStyle`: ten vec4
_CLOUD_FLOATS = 40
_UNLOCKED = (0.0, 0.0, 0.0, -1.0)


class ResidentParticles:
    """One `ParticleBuffer` on the GPU at a time (the last one a draw was of), in storage buffers."""

    def __init__(self):
        (
            self.particle_buffer,
            self.formation_buffer,
            self.cloud_buffer,
            self.facing_buffer,
            self.profile_buffer,
            self.drawn_bits_buffer,
            self.returned_buffer,
        ) = self._buffers = GL.glGenBuffers(7)
        self.particles: ParticleBuffer | None = None
        self.atlas: int | None = None  # the sprite atlas texture, made when a cloud first needs it
        self._plain: np.ndarray = np.zeros(0, dtype=bool)  # of the resident particles: `plain_splats`
        self._cloud_plain: np.ndarray = np.zeros(0, dtype=bool)  # of their clouds: all particles plain
        self._sprites: np.ndarray = np.zeros(0, dtype=bool)  # of the resident particles: drawn from the atlas
        #: of the resident particles: per particle, (facing, artist) as bits; whether there are Yusov's profiles
        self._feature_bits: np.ndarray = np.zeros(0, dtype=np.uint8)
        self.profiled = False
        #: whether the resident particles have light sent back by a lit face (`ParticleBuffer.returned`)
        self.returning = False
        #: of the resident particles' clouds: (facing, artist) as bits, whether any is an atlas sprite; what a
        #: `SplatSelection`'s shading and drawing go by, its particles unknown to the CPU
        self._cloud_feature_bits: np.ndarray = np.zeros(1, dtype=np.uint8)
        self._cloud_sprites: np.ndarray = np.zeros(1, dtype=bool)
        self._formation_time: tuple | None = None  # (time, weights serial) of the held opacity factors

    def hold(self, particles: ParticleBuffer) -> None:
        """Upload the particles' shading terms, styles and unlocked facings when the particles change."""
        if particles is self.particles:
            return
        store(self.particle_buffer, _particle_records(particles))
        store(self.cloud_buffer, _cloud_records(particles.styles))
        store(
            self.facing_buffer,
            np.tile(np.array(_UNLOCKED, dtype=np.float32), (max(len(particles.radii), 1), 1)),
            GL.GL_DYNAMIC_DRAW,
        )
        self._plain = plain_splats(particles.styles)
        # per cloud, whether all its particles are plain: asked each frame, of hundreds of clouds on a field
        self._cloud_plain = ~_any_of_each_cloud(~self._plain, particles.cloud_starts)
        self._sprites = particles.styles.sprite_index >= 0
        if self.atlas is None and np.any(particles.styles.sprite_index >= 0):
            self.atlas = _atlas_texture()
        store(self.formation_buffer, np.ones(max(len(particles.radii), 1), dtype=np.float32))
        # Yusov's eye pass's profile rows; one float where there are none (no empty buffer is bound)
        rows = np.zeros(0) if particles.profiles is None else particles.profiles.profiles.ravel()
        store(self.profile_buffer, (rows if rows.size else np.zeros(1)).astype(np.float32))
        per_cloud = [(s.facing != FACING_SPLAT) | (s.artist is not None) << 1 for s in particles.styles.clouds]
        self._cloud_feature_bits = np.array(per_cloud + [0], dtype=np.uint8)
        self._feature_bits = self._cloud_feature_bits[particles.styles.cloud_index]
        self.profiled = particles.profiles is not None
        # the light a lit face sent back, per particle and light; one float where there is none
        returned = np.zeros(1) if particles.returned is None or not particles.returned.size else particles.returned
        store(self.returned_buffer, np.ascontiguousarray(returned, dtype=np.float32).ravel())
        self.returning = particles.returned is not None
        self._cloud_sprites = np.append(_any_of_each_cloud(self._sprites, particles.cloud_starts), False)
        store(self.drawn_bits_buffer, np.append(particles.drawn_bits, np.uint32(0)))
        self.particles, self._formation_time = particles, None

    def hold_formation(self, particles: ParticleBuffer, time_s: float | None) -> None:
        """Upload the opacity factors (formation at `time_s`, blend weights) when they differ from those held."""
        factors = particles.opacity_factors(time_s)
        # what the buffer's factors are for: the time and the weights; None: all 1
        held = None if factors is None else (time_s, particles.weights_serial)
        if held != self._formation_time:
            store(
                self.formation_buffer,
                (np.ones(max(len(particles.radii), 1)) if factors is None else factors).astype(np.float32),
            )
            self._formation_time = held

    def update_facing(self, particles: ParticleBuffer, start: int, state: FacingState) -> None:
        """The facing lock of particles `start`, `start + 1`, ... (one cloud's) for the next draws."""
        self.hold(particles)
        records = np.empty((len(state.fade), 4), dtype=np.float32)
        records[:, :3] = state.normals
        records[:, 3] = np.where(state.locked, state.fade, _UNLOCKED[3])
        GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, self.facing_buffer)
        GL.glBufferSubData(GL.GL_SHADER_STORAGE_BUFFER, start * records.itemsize * 4, records.nbytes, records)
        GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, 0)

    def plain_splats(self, batch: SplatBatch) -> np.ndarray:
        """(n,) bool: which of the batch's particles are plain Gaussian splats of one colour
        (`cloudcore.particles.point_sprites.plain_splats`)."""
        self.hold(batch.particles)
        return self._plain[batch.order]

    def plain_selection(self, selection: SplatSelection) -> bool:
        """Whether every particle of a selection's clouds is a plain Gaussian splat of one colour."""
        self.hold(selection.particles)
        return bool(np.all(self._cloud_plain[list(selection.clouds)]))

    def with_sprites(self, batch: SplatBatch | SplatSelection) -> bool:
        """Whether any particle of the batch (of a selection's clouds) is drawn from the sprite atlas."""
        if isinstance(batch, SplatSelection):
            return bool(self._cloud_sprites[list(batch.clouds)].any())
        return bool(self._sprites[batch.order].any())

    def feature_bits(self, batch: SplatBatch | SplatSelection) -> int:
        """(facing, artist) as bits: the shader features the batch's particles need."""
        self.hold(batch.particles)
        if isinstance(batch, SplatSelection):
            return int(np.bitwise_or.reduce(self._cloud_feature_bits[list(batch.clouds)]))
        return int(np.bitwise_or.reduce(self._feature_bits[batch.order])) if len(batch) else 0

    def close(self) -> None:
        """Free the GL objects (the context must be current)."""
        if self.atlas is not None:
            GL.glDeleteTextures([self.atlas])
        GL.glDeleteBuffers(len(self._buffers), list(self._buffers))
        self.particles = None


def _particle_records(particles: ParticleBuffer) -> np.ndarray:
    """The shader's `Particle` array (n, PARTICLE_FLOATS) float32: the view-independent terms of `seen_from`."""
    lights = len(particles.light_directions)
    if lights > MAX_LIGHTS:  # the scene loader and the editor refuse these first (cloudcore.scenes.limits)
        raise ValueError(f"at most {MAX_LIGHTS} lights can shine on clouds at once, the scene has {lights}")
    records = np.zeros((max(len(particles.radii), 1), PARTICLE_FLOATS), dtype=np.float32)
    n = len(particles.radii)
    records[:n, 0:3] = particles.centres
    records[:n, 3] = particles.radii
    records[:n, 4:7] = particles.scattering[:, None] * particles.tint
    records[:n, 7] = particles.alpha
    records[:n, 8:11] = particles.ambient * particles.ambient_weight[:, None] * particles.tint
    records[:n, 11] = particles.inner_light_depth
    styles = particles.styles
    records[:n, 12:15] = styles.group_centres
    records[:n, 15] = styles.cloud_index
    records[:n, 16] = styles.sprite_index
    records[:n, 17] = styles.rotation
    records[:n, 18] = -1.0 if particles.profiles is None else particles.profiles.rows
    records[:n, 20 : 20 + lights] = particles.incident
    return records


def _cloud_records(styles: ParticleStyles) -> np.ndarray:
    """The shader's `CloudStyle` array (clouds, _CLOUD_FLOATS) float32."""
    records = np.zeros((max(len(styles.clouds), 1), _CLOUD_FLOATS), dtype=np.float32)
    for record, style in zip(records, styles.clouds):
        record[25:27] = style.bottom_y, style.top_y
        record[31] = style.facing
        if style.artist is not None:
            heights = style.artist["level_heights"]
            record[0:20] = style.artist["level_colours"].ravel()
            record[20:25] = heights
            record[27] = 1.0
            record[28:31] = style.artist["directional_colour"]
            record[32:35] = style.artist["directional_range"]
            record[36:39] = style.artist["sun_direction"]
    return records


def _atlas_texture() -> int:
    """The sprite atlas, mipmapped down to the level its cells' empty margins keep apart."""
    pixels = np.ascontiguousarray(load_atlas())
    texture = GL.glGenTextures(1)
    GL.glBindTexture(GL.GL_TEXTURE_2D, texture)
    GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MAX_LEVEL, ATLAS_MAX_MIP_LEVEL)
    GL.glTexStorage2D(GL.GL_TEXTURE_2D, ATLAS_MAX_MIP_LEVEL + 1, GL.GL_RGBA8, pixels.shape[1], pixels.shape[0])
    GL.glTexSubImage2D(GL.GL_TEXTURE_2D, 0, 0, 0, pixels.shape[1], pixels.shape[0], GL.GL_RGBA, GL.GL_FLOAT, pixels)
    GL.glGenerateMipmap(GL.GL_TEXTURE_2D)
    GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MIN_FILTER, GL.GL_LINEAR_MIPMAP_LINEAR)
    GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MAG_FILTER, GL.GL_LINEAR)
    GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_WRAP_S, GL.GL_CLAMP_TO_EDGE)
    GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_WRAP_T, GL.GL_CLAMP_TO_EDGE)
    GL.glBindTexture(GL.GL_TEXTURE_2D, 0)
    return texture


def _any_of_each_cloud(flags: np.ndarray, cloud_starts: np.ndarray) -> np.ndarray:
    """(clouds,) whether any particle of each cloud (its `cloud_starts` range) has its flag: by the flags' running
    count, no loop over the clouds."""
    counts = np.concatenate([[0], np.cumsum(flags)])
    return counts[cloud_starts[1:]] > counts[cloud_starts[:-1]]
