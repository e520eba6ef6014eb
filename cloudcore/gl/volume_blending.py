"""Volume-aware blending on the GPU: a tiled compute pass over per-tile particle lists (no interlock).

Yusov (HPG 2014, 5.5) composites intersecting particles as volumes with pixel-shader ordering
(GL_ARB_fragment_shader_interlock), which llvmpipe lacks.  Here the per-pixel ordering comes from the
work itself: `cloudcore.gl.tile_binning` bins the batch's splats into screen tiles on the GPU, keeping
the far-to-near order, as `cloudcore.light.volume_blending.screen_tiles` does in numpy (the reference: it
took 72 ms of CPU a frame on the default view at 640x480, and 79 on the H200's host, where the pass was on
the CPU's side of the frame); and `shaders/volume_blend.comp.glsl` runs one invocation per pixel
over its tile's list, reading and writing its own pixel of the target, as 3D Gaussian splatting
rasterisers do.  The splats' instances (corners and colours) are those the splat pass's compute shader
builds for its billboards, so both paths draw the same particles.  `GpuFeatures` says what the GL can
do; `cloudcore.light.volume_blending.blending_path` chooses from it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from OpenGL import GL

from cloudcore.gl.programs import build_compute_program, gl_renderer, set_vec3
from cloudcore.gl.targets import DepthTexture
from cloudcore.gl.tile_binning import DISCS_BINDING, OCCUPIED_BINDING, BinnedTiles, GpuTileBinning
from cloudcore.light.volume_blending import (
    FINISHED_TRANSMITTANCE,
    MAX_OPTICAL_DEPTH,
    TILE_PIXELS,
    Splats,
)
from cloudcore.maths.splat_kernel import SPLAT_SHARPNESS
from cloudcore.particles.batch import SplatBatch

_TILE_STARTS_BINDING, _TILE_ENTRIES_BINDING = 6, 7
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
    """The compute pass, its programs and the binning; `draw` composites one batch over a colour texture."""

    def __init__(self):
        self.features = GpuFeatures.query()
        self._programs: dict[bool, int] = {}  # per variant (plain?), built when first needed
        self._binning: GpuTileBinning | None = None
        self._depth = DepthTexture()  # the world's depth, which the compositing reads

    def draw(
        self,
        instances: tuple[int, int, int],
        view: np.ndarray,
        projection: np.ndarray,
        colour_texture: int,
        depth_framebuffer: int,
        size: tuple[int, int],
        *,
        plain: bool = False,
        count_at: tuple[int, int] | None = None,
    ) -> bool:
        """Composite a draw's splats (`instances`: buffer, first slot, slots, far to near) over `colour_texture`
        (RGBA16F, `size` pixels), cut by the depth of `depth_framebuffer`: as volumes, or where `plain` as the
        raster blends them.  `count_at`: a GPU-chosen draw's indirect command's count (buffer, uint index),
        which says how many of the slots it kept; without it, all.  The splats are binned into tiles on the GPU
        (`cloudcore.gl.tile_binning`); False, nothing done, where the bins would hold too many pairs
        (`MAX_PAIRS`): then the raster draws them.  Leaves the framebuffer that was bound bound."""
        if self._binning is None:
            self._binning = GpuTileBinning()
        if plain not in self._programs:
            defines = {"PLAIN": 1, "FINISHED_TRANSMITTANCE": FINISHED_TRANSMITTANCE} if plain else {}
            self._programs[plain] = build_compute_program("volume_blend", _CONSTANTS | defines)
        binned = self._binning.bin(instances, count_at, view, projection, size)
        if binned is None:
            return False
        if binned.pairs == 0:  # counted: no splat on the screen (counted on the GPU, None: the dispatch finds out)
            return True
        self._composite(self._programs[plain], binned, view, projection, colour_texture, depth_framebuffer)
        return True

    def settle(self) -> bool:
        """After the frame's wait: whether it must be drawn again, a draw's tile pairs past the room it had
        (`GpuTileBinning.settle`)."""
        return self._binning is not None and self._binning.settle()

    def _composite(self, program, binned: BinnedTiles, view, projection, colour_texture, depth_framebuffer) -> None:
        """Run a compositing `program` over `binned`'s occupied tiles, by the indirect dispatch the binning made."""
        bound = GL.glGetIntegerv(GL.GL_DRAW_FRAMEBUFFER_BINDING)
        depth_texture = self._depth.copy(depth_framebuffer, binned.size)
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, int(bound))
        for binding, buffer in (
            (_TILE_STARTS_BINDING, binned.starts),
            (_TILE_ENTRIES_BINDING, binned.entries),
            (DISCS_BINDING, binned.discs),
            (OCCUPIED_BINDING, binned.occupied),
        ):
            GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, binding, buffer)
        GL.glBindBuffer(GL.GL_DISPATCH_INDIRECT_BUFFER, binned.occupied)
        GL.glUseProgram(program)
        GL.glUniform2i(GL.glGetUniformLocation(program, "size"), *binned.size)
        GL.glUniform1i(GL.glGetUniformLocation(program, "tiles_across"), binned.across)
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
        GL.glDispatchComputeIndirect(0)
        GL.glBindBuffer(GL.GL_DISPATCH_INDIRECT_BUFFER, 0)
        # and what it wrote there, for the draws, blits and reads after it
        GL.glMemoryBarrier(
            GL.GL_FRAMEBUFFER_BARRIER_BIT | GL.GL_TEXTURE_FETCH_BARRIER_BIT | GL.GL_SHADER_IMAGE_ACCESS_BARRIER_BIT
        )
        GL.glBindImageTexture(0, 0, 0, GL.GL_FALSE, 0, GL.GL_READ_WRITE, GL.GL_RGBA16F)

    def close(self) -> None:
        """Free the GL objects (the context must be current)."""
        self._depth.close()
        for program in self._programs.values():
            GL.glDeleteProgram(program)
        if self._binning is not None:
            self._binning.close()


def batch_splats(batch: SplatBatch, view: np.ndarray) -> Splats:
    """What a batch's splats draw, seen from its eye, for the numpy reference of either path."""
    colours, opacities = batch.particles.seen_from(batch.eye, batch.order, time_s=batch.time_s)
    return Splats(batch.centres - batch.eye, batch.radii, colours, opacities, view[0, :3], view[1, :3])
