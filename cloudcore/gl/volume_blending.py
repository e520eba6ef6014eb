"""Volume-aware blending on the GPU: a tiled compute pass over per-tile particle lists (no interlock).

Yusov (HPG 2014, 5.5) composites intersecting particles as volumes with pixel-shader ordering
(GL_ARB_fragment_shader_interlock), which llvmpipe lacks.  Here the per-pixel ordering comes from the
work itself: `cloudcore.light.volume_blending.screen_tiles` bins the batch's splats into screen tiles
(keeping the far-to-near order), and `shaders/volume_blend.comp.glsl` runs one invocation per pixel
over its tile's list, reading and writing its own pixel of the target, as 3D Gaussian splatting
rasterisers do.  The splats' instances (corners and colours) are those the splat pass's compute shader
builds for its billboards, so both paths draw the same particles.  `GpuFeatures` says what the GL can
do; `cloudcore.light.volume_blending.blending_path` chooses from it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from OpenGL import GL

from cloudcore.gl.programs import build_compute_program, dispatch, gl_renderer, set_vec3
from cloudcore.gl.splats import INSTANCE_BYTES, SplatBatch
from cloudcore.gl.targets import blit_depth
from cloudcore.gl.tile_binning import DISCS_BINDING, GpuTileBinning
from cloudcore.light.kernel import SPLAT_SHARPNESS
from cloudcore.light.volume_blending import (
    FINISHED_TRANSMITTANCE,
    MAX_OPTICAL_DEPTH,
    TILE_PIXELS,
    ScreenTiles,
    Splats,
)

_TILE_STARTS_BINDING, _TILE_ENTRIES_BINDING, _OCCUPIED_BINDING = 6, 7, 8
#: the instances' binding, as `cloudcore.gl.splats` writes them
_INSTANCES_BINDING = 3
#: volume_blend.comp.glsl's constants, both variants'
_CONSTANTS = {"TILE_PIXELS": TILE_PIXELS, "SPLAT_SHARPNESS": SPLAT_SHARPNESS, "MAX_OPTICAL_DEPTH": MAX_OPTICAL_DEPTH}


@dataclass(frozen=True)
class GpuFeatures:
    """What the current GL offers volume-aware blending.

    `compute_shaders`: GL 4.3 compute with image load/store, the tiled pass this module runs.
    `fragment_shader_interlock`: GL_ARB_fragment_shader_interlock, where Yusov's own fragment-shader
    pass could run instead; reported, not used (no GL here has it to test such a pass on)."""

    compute_shaders: bool
    fragment_shader_interlock: bool
    renderer: str  # GL_RENDERER: which GL this is (llvmpipe, a GPU)

    @classmethod
    def query(cls) -> GpuFeatures:
        extensions = {
            GL.glGetStringi(GL.GL_EXTENSIONS, i).decode() for i in range(int(GL.glGetIntegerv(GL.GL_NUM_EXTENSIONS)))
        }
        version = (int(GL.glGetIntegerv(GL.GL_MAJOR_VERSION)), int(GL.glGetIntegerv(GL.GL_MINOR_VERSION)))
        compute = version >= (4, 3) or {"GL_ARB_compute_shader", "GL_ARB_shader_image_load_store"} <= extensions
        return cls(compute, "GL_ARB_fragment_shader_interlock" in extensions, gl_renderer())


class VolumeBlendingPass:
    """The compute pass and its buffers; `draw` composites one batch over a colour texture."""

    def __init__(self):
        self.features = GpuFeatures.query()
        self._program = self._plain_program = None
        if self.features.compute_shaders:
            self._program = build_compute_program("volume_blend", _CONSTANTS)
        self._buffers = self._starts, self._entries, self._occupied = GL.glGenBuffers(3)
        self._binning: GpuTileBinning | None = None  # made with the plain program, when first needed
        self._depth: tuple[int, int, tuple[int, int]] | None = None  # (texture, framebuffer, size)

    def draw(
        self,
        tiles: ScreenTiles,
        instances: tuple[int, int, int],
        view: np.ndarray,
        projection: np.ndarray,
        colour_texture: int,
        depth_framebuffer: int,
    ) -> None:
        """Composite the splats binned in `tiles` (their instances: (buffer, first slot, count)) over
        `colour_texture` (RGBA16F, the size of `tiles`), cut by the depth of `depth_framebuffer`.
        Leaves the framebuffer that was bound bound."""
        occupied = tiles.occupied
        if not len(occupied):
            return
        for binding, buffer, data in (
            (_TILE_STARTS_BINDING, self._starts, tiles.starts),
            (_TILE_ENTRIES_BINDING, self._entries, tiles.entries),
            (_OCCUPIED_BINDING, self._occupied, occupied),
        ):
            data = data if len(data) else np.zeros(1, dtype=np.uint32)
            GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, buffer)
            GL.glBufferData(GL.GL_SHADER_STORAGE_BUFFER, data.nbytes, np.ascontiguousarray(data), GL.GL_STREAM_DRAW)
            GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, binding, buffer)
        self._composite(
            self._program,
            tiles.size,
            tiles.across,
            len(occupied),
            instances,
            view,
            projection,
            colour_texture,
            depth_framebuffer,
        )

    def draw_plain(
        self,
        instances: tuple[int, int, int],
        count_at: tuple[int, int],
        view: np.ndarray,
        projection: np.ndarray,
        colour_texture: int,
        depth_framebuffer: int,
        size: tuple[int, int],
    ) -> bool:
        """Composite a GPU-chosen draw's plain splats (`instances`: buffer, first slot, slots; `count_at`: its
        indirect command's count) over `colour_texture` as the raster blends them, binned on the GPU
        (`cloudcore.gl.tile_binning`), cut by the depth of `depth_framebuffer`; False, nothing done, where the
        binning would hold too many pairs (`MAX_PAIRS`): the raster's to draw."""
        if self._binning is None:
            self._binning = GpuTileBinning()
            self._plain_program = build_compute_program(
                "volume_blend", _CONSTANTS | {"PLAIN": 1, "FINISHED_TRANSMITTANCE": FINISHED_TRANSMITTANCE}
            )
        binned = self._binning.bin(instances, count_at, view, projection, size)
        if binned is None or not binned.pairs:
            return binned is not None
        GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, _TILE_STARTS_BINDING, binned.starts)
        GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, _TILE_ENTRIES_BINDING, binned.entries)
        GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, DISCS_BINDING, binned.discs)
        self._composite(
            self._plain_program,
            binned.size,
            binned.across,
            binned.across * binned.up,
            instances,
            view,
            projection,
            colour_texture,
            depth_framebuffer,
        )
        return True

    def _composite(
        self, program, size, across, groups, instances, view, projection, colour_texture, depth_framebuffer
    ) -> None:
        """Run a compositing `program` over `groups` tiles (the occupied buffer's first; the plain program's: the
        screen's first), its tile buffers bound, the instances (buffer, first slot, count) bound here."""
        bound = GL.glGetIntegerv(GL.GL_DRAW_FRAMEBUFFER_BINDING)
        depth_texture = self._world_depth(depth_framebuffer, size)
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, int(bound))
        buffer, first, count = instances
        GL.glBindBufferRange(
            GL.GL_SHADER_STORAGE_BUFFER, _INSTANCES_BINDING, buffer, first * INSTANCE_BYTES, count * INSTANCE_BYTES
        )
        GL.glUseProgram(program)
        GL.glUniform2i(GL.glGetUniformLocation(program, "size"), *size)
        GL.glUniform1i(GL.glGetUniformLocation(program, "tiles_across"), across)
        set_vec3(program, "view_right", view[0, :3])
        set_vec3(program, "view_up", view[1, :3])
        set_vec3(program, "view_forward", -view[2, :3])
        GL.glUniform2f(GL.glGetUniformLocation(program, "focal"), projection[0, 0], projection[1, 1])
        GL.glUniform2f(GL.glGetUniformLocation(program, "depth_terms"), projection[2, 2], projection[2, 3])
        GL.glActiveTexture(GL.GL_TEXTURE0)
        GL.glBindTexture(GL.GL_TEXTURE_2D, depth_texture)
        GL.glUniform1i(GL.glGetUniformLocation(program, "world_depth"), 0)
        # what was drawn into the target before must be there to read
        GL.glMemoryBarrier(GL.GL_FRAMEBUFFER_BARRIER_BIT | GL.GL_SHADER_IMAGE_ACCESS_BARRIER_BIT)
        GL.glBindImageTexture(0, colour_texture, 0, GL.GL_FALSE, 0, GL.GL_READ_WRITE, GL.GL_RGBA16F)
        GL.glUniform1ui(GL.glGetUniformLocation(program, "group_count"), groups)
        dispatch(groups)
        # and what it wrote there, for the draws, blits and reads after it
        GL.glMemoryBarrier(
            GL.GL_FRAMEBUFFER_BARRIER_BIT | GL.GL_TEXTURE_FETCH_BARRIER_BIT | GL.GL_SHADER_IMAGE_ACCESS_BARRIER_BIT
        )
        GL.glBindImageTexture(0, 0, 0, GL.GL_FALSE, 0, GL.GL_READ_WRITE, GL.GL_RGBA16F)

    def _world_depth(self, framebuffer: int, size: tuple[int, int]) -> int:
        """A texture holding the depth of `framebuffer` (a renderbuffer, which a shader cannot read)."""
        if self._depth is None or self._depth[2] != size:
            self._close_depth()
            texture = GL.glGenTextures(1)
            GL.glBindTexture(GL.GL_TEXTURE_2D, texture)
            GL.glTexStorage2D(GL.GL_TEXTURE_2D, 1, GL.GL_DEPTH_COMPONENT24, *size)
            GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MIN_FILTER, GL.GL_NEAREST)
            GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MAG_FILTER, GL.GL_NEAREST)
            target = GL.glGenFramebuffers(1)
            GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, target)
            GL.glFramebufferTexture2D(GL.GL_FRAMEBUFFER, GL.GL_DEPTH_ATTACHMENT, GL.GL_TEXTURE_2D, texture, 0)
            self._depth = (texture, target, size)
        texture, target, _ = self._depth
        blit_depth(framebuffer, size, target, size)
        return texture

    def _close_depth(self) -> None:
        if self._depth is not None:
            GL.glDeleteTextures([self._depth[0]])
            GL.glDeleteFramebuffers(1, [self._depth[1]])
            self._depth = None

    def close(self) -> None:
        """Free the GL objects (the context must be current)."""
        self._close_depth()
        for program in (self._program, self._plain_program):
            if program is not None:
                GL.glDeleteProgram(program)
        if self._binning is not None:
            self._binning.close()
        GL.glDeleteBuffers(len(self._buffers), list(self._buffers))


def batch_splats(batch: SplatBatch, view: np.ndarray) -> Splats:
    """What a batch's splats draw, seen from its eye, for the numpy reference of either path."""
    colours, opacities = batch.particles.seen_from(batch.eye, batch.order, time_s=batch.time_s)
    return Splats(batch.centres - batch.eye, batch.radii, colours, opacities, view[0, :3], view[1, :3])
