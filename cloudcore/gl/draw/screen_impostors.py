"""Harris's screen impostors of the units the eye is inside: a run of them at the plan's reduced resolution,
made before anything else of the cloud pass and laid over the screen where the run starts."""

from __future__ import annotations

import numpy as np
from OpenGL import GL

from cloudcore.gl.draw.executor import CloudPassFrame, DrawCounts, DrawExecutor, DrawStep, draw_kind
from cloudcore.gl.quads import SCREEN_CORNERS
from cloudcore.gl.targets import TextureTarget, blit_depth, depth_renderbuffer
from cloudcore.lod.impostors import cropped_corners, particle_extent
from cloudcore.particles.batch import SplatBatch


@draw_kind("inside")
class ScreenImpostors(DrawExecutor):
    """A run of units the eye is inside (consecutive in the pass, drawn at one weight: `inside_runs`), their
    particles sorted together into one screen impostor, laid over everything.

    Their only input from the frame is the world's depth, which no cloud or object of the cloud pass writes, so
    made first they are the same.  Made where they are laid, each stalled the frame twice on llvmpipe: the depth
    blit waits for the frame's draws so far, the composite for the impostor's."""

    made_ahead = True

    def __init__(self, tools):
        super().__init__(tools)
        self._targets: list[tuple[TextureTarget, int]] = []  # (target, its depth renderbuffer), all of one size
        #: this frame's screen impostors by step: (target, particles drawn, the part of the screen they can cover:
        #: the composite draws only that, 18% fewer fragments along the untuned cumulus field)
        self._made: dict[DrawStep, tuple[TextureTarget, int, tuple]] = {}

    def batch(self, frame: CloudPassFrame, step: DrawStep) -> SplatBatch:
        return frame.batch_of(step.items)

    def make_ahead(self, frame: CloudPassFrame, steps: list[DrawStep]) -> None:
        size, self._made = frame.plan.inside_size, {}
        for step, target in zip(steps, self._inside_targets(size, len(steps))):
            blit_depth(frame.context.framebuffer, frame.size, target.framebuffer, size)
            target.bind_cleared()
            batch = step.batch
            self.tools.splats.draw(batch, frame.view, frame.projection, point_sprites=frame.settings.point_sprites)
            extent = particle_extent(frame.view, frame.projection, batch.centres, batch.radii, size)
            self._made[step] = (target, len(batch), extent)

    def draw(self, frame: CloudPassFrame, step: DrawStep) -> DrawCounts:
        target, particles_drawn, extent = self._made[step]
        weight = frame.plan.clouds[step.items[0].index].full_weight
        corners = cropped_corners(SCREEN_CORNERS, extent)
        self.tools.quads.draw(corners, np.eye(4), target.texture, weight, depth_test=False, uv_rect=extent)
        return DrawCounts(particles=particles_drawn)

    def count_fragments(self, frame: CloudPassFrame, step: DrawStep) -> tuple:
        extent = self._made[step][2]
        corners = cropped_corners(SCREEN_CORNERS, extent)
        self.tools.quads.draw(corners, np.eye(4), 0, 1.0, depth_test=False, counting=True, uv_rect=extent)
        return ()

    def _inside_targets(self, size, count: int) -> list[TextureTarget]:
        """`count` screen impostor targets of `size`, each with its own depth buffer for the frame's."""
        if self._targets and (self._targets[0][0].width, self._targets[0][0].height) != tuple(size):
            self.close_screen_targets()
        while len(self._targets) < count:
            depth = depth_renderbuffer(*size)
            self._targets.append((TextureTarget(*size, depth_renderbuffer=depth), depth))
        return [target for target, _ in self._targets[:count]]

    def close_screen_targets(self) -> None:
        for target, depth in self._targets:
            target.close()
            GL.glDeleteRenderbuffers(1, [depth])
        self._targets = []

    @property
    def texture_bytes(self) -> int:
        return sum(target.nbytes for target, _ in self._targets)
