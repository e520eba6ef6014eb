"""A pool of impostor render targets: released targets are reused by size, and the idle ones are bounded.

Every target the renderer holds is either in use (counted in `bytes_in_use`)
or idle in the pool; idle ones beyond `idle_limit_bytes` are deleted, oldest
first, so texture memory is bounded by what the current frame uses plus that
limit.
"""

from __future__ import annotations

from collections import OrderedDict

from cloudcore.gl.targets import TextureTarget

IDLE_LIMIT_BYTES = 32 * 2**20


class TexturePool:
    def __init__(self, idle_limit_bytes: int = IDLE_LIMIT_BYTES, own_depth: bool = False):
        """`own_depth`: each target with a depth texture of its own (`TextureTarget`)."""
        self._idle: OrderedDict[int, TextureTarget] = OrderedDict()  # keyed by id(), oldest first
        self.idle_limit_bytes = idle_limit_bytes
        self.own_depth = own_depth
        self.bytes_in_use = 0

    @property
    def bytes_idle(self) -> int:
        return sum(t.nbytes for t in self._idle.values())

    @property
    def bytes_total(self) -> int:
        return self.bytes_in_use + self.bytes_idle

    def acquire(self, width: int, height: int) -> TextureTarget:
        for key, target in self._idle.items():
            if (target.width, target.height) == (width, height):
                del self._idle[key]
                break
        else:
            target = TextureTarget(width, height, own_depth=self.own_depth)
        self.bytes_in_use += target.nbytes
        return target

    def release(self, target: TextureTarget) -> None:
        self.bytes_in_use -= target.nbytes
        self._idle[id(target)] = target
        while self._idle and self.bytes_idle > self.idle_limit_bytes:
            self._idle.popitem(last=False)[1].close()

    def close(self) -> None:
        for target in self._idle.values():
            target.close()
        self._idle.clear()
