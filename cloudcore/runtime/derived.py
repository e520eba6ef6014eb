"""A resource made from part of the scene, kept in step with it: made again only when its source changes.

The renderer keeps its GL passes and its particle buffer between frames (`cloudcore.gl.frame`); each follows
its own source (the terrain and lighting for the world pass, the objects for theirs, the clouds and their
shading for the particles, the particles' clouds and grouping for the LOD units) through one `Derived`, so that
what a resource was made from is written once, beside how it is made.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Generic, TypeVar

Resource = TypeVar("Resource")

#: the source of a resource not made yet: equal to no source
_NOTHING = object()


class Derived(Generic[Resource]):
    """A resource made by `make(source, *inputs)`, made again whenever `follow` is given a source that differs
    (`!=`) from the one it was made from.  `inputs` are what the source stands for (the lights of a lighting):
    passed to `make`, never compared.

    With `close`, the old resource is closed before the new one is made, and forgotten: a new one that fails to
    build leaves none to close again, and none to use (the next `follow` tries again).  Without it, the old one
    (`value`, `source`) is still there while `make` runs, for a make that reuses what it can of it."""

    def __init__(self, make: Callable[..., Resource], close: Callable[[Resource], None] | None = None):
        self._make, self._close = make, close
        self.value: Resource | None = None
        self.source: Any = _NOTHING

    @property
    def made(self) -> bool:
        return self.source is not _NOTHING

    def follow(self, source, *inputs) -> bool:
        """Make the resource again for `source` unless it was made from an equal one; whether it was made."""
        if self.made and not (source != self.source):
            return False
        if self._close is not None:
            self.close()
        self.value = self._make(source, *inputs)
        self.source = source
        return True

    def close(self) -> None:
        """Close the resource (with `close`, where there is one) and forget it and its source."""
        if self._close is not None and self.value is not None:
            self._close(self.value)
        self.value, self.source = None, _NOTHING
