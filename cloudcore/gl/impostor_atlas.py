"""The impostors' array texture: cells of `cloudcore.lod.atlas` rendered into and drawn from one texture.

One GL_TEXTURE_2D_ARRAY (RGBA16F, premultiplied linear colour) follows its
layout's layer count, copying the layers it keeps when it is resized.  An
impostor of side s lives in the lower left s x s texels of its cell; a quad
drawn from it samples within those texels only, clamped half a texel inside
them: exactly what CLAMP_TO_EDGE gave an impostor texture of its own, so the
picture does not change and no neighbour bleeds in.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from OpenGL import GL

from cloudcore.lod.atlas import AtlasLayout, Cell

_TEXEL_BYTES = 8  # RGBA16F

#: floats of one quad's instance in `QuadPass.draw_instanced`: four corners, uv and clamp rectangles, weight, layer
INSTANCE_FLOATS = 22


class ImpostorAtlas:
    def __init__(self, layer_side: int):
        self.layout = AtlasLayout(layer_side)
        self.texture, self._layers = None, 0
        self._framebuffer, self._copy_framebuffer, self._layered_framebuffer = GL.glGenFramebuffers(3)
        self._bound_layer = None
        self._layered_texture = None  # the texture the layered framebuffer has attached

    @property
    def layer_side(self) -> int:
        return self.layout.layer_side

    @property
    def nbytes(self) -> int:
        return self._layers * self.layer_side**2 * _TEXEL_BYTES

    @property
    def in_use(self) -> bool:
        return self.layout.texels_in_use > 0

    def allocate(self, side: int) -> AtlasImage:
        image = AtlasImage(self, self.layout.allocate(side), side)
        self._fit()
        return image

    def release(self, image: AtlasImage) -> None:
        self.layout.release(image.cell)
        self._fit()

    def bind_cleared(self, cell: Cell, side: int) -> None:
        """Draw into the side x side texels of `cell` from now on (viewport and scissor), cleared to transparent.

        The scissor stays on: a point sprite whose centre is in the viewport may reach beyond it."""
        self.bind(cell, side)
        GL.glClearColor(0.0, 0.0, 0.0, 0.0)
        GL.glClear(GL.GL_COLOR_BUFFER_BIT)

    def bind(self, cell: Cell, side: int) -> None:
        """`bind_cleared` without the clearing."""
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, self._framebuffer)
        if self._bound_layer != cell.layer:  # consecutive cells of one layer keep the attachment
            GL.glFramebufferTextureLayer(GL.GL_FRAMEBUFFER, GL.GL_COLOR_ATTACHMENT0, self.texture, 0, cell.layer)
            self._bound_layer = cell.layer
        GL.glViewport(cell.x, cell.y, side, side)
        GL.glEnable(GL.GL_SCISSOR_TEST)
        GL.glScissor(cell.x, cell.y, side, side)

    def bind_layers(self) -> None:
        """Draw into every layer at once from now on (a draw's vertices pick theirs: gl_Layer), with the scissor
        test on; the viewports and scissors are the caller's to set per index."""
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, self._layered_framebuffer)
        if self._layered_texture != self.texture:
            GL.glFramebufferTexture(GL.GL_FRAMEBUFFER, GL.GL_COLOR_ATTACHMENT0, self.texture, 0)
            self._layered_texture = self.texture
        GL.glEnable(GL.GL_SCISSOR_TEST)

    def read(self, cell: Cell, side: int) -> np.ndarray:
        """The side x side texels of `cell` as float32 (side, side, 4), top row first."""
        GL.glBindFramebuffer(GL.GL_READ_FRAMEBUFFER, self._copy_framebuffer)
        GL.glFramebufferTextureLayer(GL.GL_READ_FRAMEBUFFER, GL.GL_COLOR_ATTACHMENT0, self.texture, 0, cell.layer)
        GL.glPixelStorei(GL.GL_PACK_ALIGNMENT, 1)
        data = GL.glReadPixels(cell.x, cell.y, side, side, GL.GL_RGBA, GL.GL_FLOAT)
        return np.frombuffer(data, dtype=np.float32).reshape(side, side, 4)[::-1].copy()

    def _fit(self) -> None:
        """Resize the texture to the layout's layers, copying the layers both hold."""
        if self.layout.layers == self._layers:
            return
        texture = GL.glGenTextures(1)
        GL.glBindTexture(GL.GL_TEXTURE_2D_ARRAY, texture)
        side = self.layer_side
        GL.glTexStorage3D(GL.GL_TEXTURE_2D_ARRAY, 1, GL.GL_RGBA16F, side, side, self.layout.layers)
        for name in (GL.GL_TEXTURE_MIN_FILTER, GL.GL_TEXTURE_MAG_FILTER):
            GL.glTexParameteri(GL.GL_TEXTURE_2D_ARRAY, name, GL.GL_LINEAR)
        for name in (GL.GL_TEXTURE_WRAP_S, GL.GL_TEXTURE_WRAP_T):
            GL.glTexParameteri(GL.GL_TEXTURE_2D_ARRAY, name, GL.GL_CLAMP_TO_EDGE)
        GL.glDisable(GL.GL_SCISSOR_TEST)
        for layer in range(min(self._layers, self.layout.layers)):
            GL.glBindFramebuffer(GL.GL_READ_FRAMEBUFFER, self._copy_framebuffer)
            GL.glFramebufferTextureLayer(GL.GL_READ_FRAMEBUFFER, GL.GL_COLOR_ATTACHMENT0, self.texture, 0, layer)
            GL.glBindFramebuffer(GL.GL_DRAW_FRAMEBUFFER, self._framebuffer)
            GL.glFramebufferTextureLayer(GL.GL_DRAW_FRAMEBUFFER, GL.GL_COLOR_ATTACHMENT0, texture, 0, layer)
            GL.glBlitFramebuffer(0, 0, side, side, 0, 0, side, side, GL.GL_COLOR_BUFFER_BIT, GL.GL_NEAREST)
        if self.texture is not None:
            GL.glDeleteTextures([self.texture])
        # the framebuffers are attached again when next bound: a new texture may take a deleted one's name
        self.texture, self._layers, self._bound_layer, self._layered_texture = texture, self.layout.layers, None, None

    def close(self) -> None:
        GL.glDeleteFramebuffers(3, [self._framebuffer, self._copy_framebuffer, self._layered_framebuffer])
        if self.texture is not None:
            GL.glDeleteTextures([self.texture])
        self.texture, self._layers = None, 0


@dataclass(frozen=True)
class AtlasImage:
    """One impostor texture of side `side` in `cell` of `atlas`."""

    atlas: ImpostorAtlas
    cell: Cell
    side: int

    def bind_cleared(self) -> None:
        self.atlas.bind_cleared(self.cell, self.side)

    def bind(self) -> None:
        self.atlas.bind(self.cell, self.side)

    @property
    def viewport(self) -> tuple[int, int, int, int]:
        """(x, y, width, height) of its texels in its layer."""
        return self.cell.x, self.cell.y, self.side, self.side

    def read(self) -> np.ndarray:
        return self.atlas.read(self.cell, self.side)


def atlas_instances(images, corners: np.ndarray, weights, extents: np.ndarray) -> np.ndarray:
    """Instances of `QuadPass.draw_instanced` (n, `INSTANCE_FLOATS`), one per image of `images` (of one atlas):
    the quad of world `corners` (n, 4, 3) showing the part `extents` (n, 4: u0, v0, u1, v1) of its image at
    its weight of `weights`, its texels clamped half a texel inside its own.  A frame's impostors at once: one
    at a time cost 29 us each on the CPU, 18 a frame along the default flythrough."""
    layer_side = float(images[0].atlas.layer_side)
    cells = np.array([(image.cell.x, image.cell.y, image.side, image.cell.layer) for image in images], dtype=np.float64)
    origin, scale = cells[:, [0, 1, 0, 1]] / layer_side, cells[:, 2:3] / layer_side
    half = 0.5 / layer_side
    inside = np.concatenate([np.full((len(cells), 2), half), np.repeat(scale - half, 2, axis=1)], axis=1)
    return np.concatenate(
        [
            np.asarray(corners, dtype=np.float64).reshape(len(cells), 12),
            origin + scale * np.asarray(extents, dtype=np.float64),  # the part of the image shown
            origin + inside,  # where its texels are sampled: its own, half a texel in
            np.asarray(weights, dtype=np.float64)[:, None],
            cells[:, 3:4],
        ],
        axis=1,
    ).astype(np.float32)
