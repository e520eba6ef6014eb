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

    def __reduce__(self):
        # raised in a worker process (`cloudcore.cli.workers`), it is pickled back to the command
        return SceneError, (self.source, self.field, self.problem)


class FieldError(ValueError):
    """A value that breaks a record's own rule, naming the field (`levels`, `rotation_deg`...).

    Records check their rules once, in `__post_init__`; the scene loader turns
    this into a SceneError under the field's full path.
    """

    def __init__(self, field: str, problem: str):
        self.field = field
        self.problem = problem
        super().__init__(f"{field}: {problem}")
