"""The one exception type for bad input."""

from __future__ import annotations


class SceneError(ValueError):
    """Bad input in a scene: which file, which field, what is wrong.

    The CLI prints `str(error)` as one line and exits 2; the GUI shows it.
    """

    def __init__(self, source: str, field: str, problem: str):
        self.source = str(source)
        self.field = field
        self.problem = problem
        super().__init__(f"{self.source}: {field}: {problem}")
