"""Typed reading of TOML tables: every value checked as it is read, every problem one line naming the field.

`Table` wraps one table of a parsed document: `number`, `integer`, `string`,
`vector`, `matrix`... read a key with its type and bounds, `reject_unknown`
refuses keys nobody read, and each refusal is a `SceneError` naming the
source, the field's dotted path (`clouds[3].particles`) and what is wrong.
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np

from cloudcore.model.errors import FieldError, SceneError


def field_error(source, field: str, problem: str) -> SceneError:
    """A SceneError kept to one line: line breaks and other control characters (from keys,
    file names or library messages) are escaped."""

    def one_line(text) -> str:
        return "".join(ch if ch.isprintable() else ascii(ch)[1:-1] for ch in str(text))

    return SceneError(one_line(source), one_line(field), one_line(problem))


def read_toml(path: Path) -> dict:
    """The TOML document at `path`, parsed; every problem reading it a one-line SceneError naming the file."""
    source = str(path)
    if path.exists() and not (path.is_file() or path.is_dir()):  # a folder is refused by the read below
        raise field_error(source, "(file)", "not a regular file (a pipe or a device): reading it would wait forever")
    try:
        # utf-8-sig: a byte-order mark (Windows editors write one) is not part of the TOML
        return tomllib.loads(path.read_text(encoding="utf-8-sig"))
    except FileNotFoundError:
        raise field_error(source, "(file)", "no such file") from None
    except (OSError, UnicodeDecodeError) as error:
        raise field_error(source, "(file)", f"cannot read: {error}") from None
    except RecursionError:
        raise field_error(source, "(toml)", "arrays or tables nested too deeply") from None
    except ValueError as error:  # TOMLDecodeError, or tomllib's ValueError for an integer of over 4300 digits
        raise field_error(source, "(toml)", str(error)) from None


class Table:
    """Typed access to one TOML table; remembers which keys were read."""

    def __init__(self, source: str, field: str, data):
        if not isinstance(data, dict):
            raise field_error(source, field, f"expected a table, got {type(data).__name__}")
        self.source, self.field, self.data = source, field, data

    def path(self, key: str) -> str:
        return f"{self.field}.{key}" if self.field else key

    def fail(self, key: str, problem: str):
        raise field_error(self.source, self.path(key), problem)

    def reject_unknown(self, known: tuple[str, ...]):
        for key in self.data:
            if key not in known:
                self.fail(key, f"unknown key; valid keys: {', '.join(known)}")

    def has(self, key: str) -> bool:
        return key in self.data

    def raw(self, key: str, default=None):
        return self.data.get(key, default)

    def boolean(self, key: str, default: bool = False) -> bool:
        value = self.raw(key, default)
        if not isinstance(value, bool):
            self.fail(key, f"expected true or false, got {value!r}")
        return value

    def number(self, key, default=None, *, low=-math.inf, high=math.inf, low_open=False):
        if key not in self.data:
            if default is None:
                self.fail(key, "required number is missing")
            return default
        value = self.data[key]
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            self.fail(key, f"expected a number, got {value!r}")
        try:
            value = float(value)
        except OverflowError:
            self.fail(key, "must be finite, got an integer too large for a float")
        if not math.isfinite(value):
            self.fail(key, f"must be finite, got {value}")
        if value < low or (low_open and value == low) or value > high:
            bound = "(" if low_open else "["
            self.fail(key, f"must be within {bound}{low}, {high}], got {value}")
        return value

    def integer(self, key, default, *, low, high):
        value = self.data.get(key, default)
        if isinstance(value, bool) or not isinstance(value, int):
            self.fail(key, f"expected an integer, got {value!r}")
        if not low <= value <= high:
            self.fail(key, f"must be within [{low}, {high}], got {value}")
        return value

    def string(self, key, default=None, *, choices=None):
        if key not in self.data:
            if default is None:
                self.fail(key, "required string is missing")
            return default
        value = self.data[key]
        if not isinstance(value, str):
            self.fail(key, f"expected a string, got {value!r}")
        if choices is not None and value not in choices:
            self.fail(key, f"{value!r} is not one of: {', '.join(choices)}")
        return value

    def matrix(self, key, columns: int, *, allow_empty=False) -> np.ndarray:
        value = self.data.get(key)
        if value is None:
            self.fail(key, "required array is missing")
        return checked_matrix(value, columns, self.source, self.path(key), allow_empty)

    def row(self, key, length: int, default=None) -> tuple[float, ...]:
        """A flat array of `length` finite numbers."""
        if key not in self.data:
            if default is None:
                self.fail(key, f"required array of {length} numbers is missing")
            return default
        return tuple(float(x) for x in checked_matrix([self.data[key]], length, self.source, self.path(key), False)[0])

    def integers(self, key, default) -> tuple[int, ...]:
        """A flat array of integers (their range is the record's to check)."""
        value = self.data.get(key, default)
        if not isinstance(value, (list, tuple)) or not all(
            isinstance(x, int) and not isinstance(x, bool) for x in value
        ):
            self.fail(key, f"expected an array of integers, got {value!r}")
        return tuple(value)

    def vector(self, key, default=None, *, low=-math.inf, high=math.inf, unit=False):
        if key not in self.data:
            if default is None:
                self.fail(key, "required 3-vector is missing")
            return default
        row = np.array(self.row(key, 3))
        if np.any(row < low) or np.any(row > high):
            self.fail(key, f"components must be within [{low}, {high}], got {row.tolist()}")
        if unit:
            largest = float(np.abs(row).max())
            if not largest > 0:
                self.fail(key, "direction must not be the zero vector")
            if not 1e-150 < largest < 1e150:  # the norm would overflow to inf or underflow to 0
                row = row / largest
            row = row / np.linalg.norm(row)
        return tuple(float(x) for x in row)

    def table(self, key, parse):
        """`parse` of the sub-table `key`, or None where there is none."""
        return parse(Table(self.source, self.path(key), self.data[key])) if key in self.data else None

    def record(self, kind, **values):
        """`kind(**values)`, with a rule the record itself refuses (a FieldError) reported at its field."""
        try:
            return kind(**values)
        except FieldError as error:
            self.fail(error.field, error.problem)

    def tables(self, key) -> list[Table]:
        value = self.data.get(key, [])
        if not isinstance(value, list):
            self.fail(key, "expected an array of tables ([[...]])")
        return [Table(self.source, f"{self.path(key)}[{i}]", item) for i, item in enumerate(value)]


def checked_matrix(value, columns, source, field, allow_empty) -> np.ndarray:
    try:
        with np.errstate(over="ignore"):  # a long double past float64 becomes inf, refused below in one line
            array = np.array(value, dtype=np.float64)
        # numpy would take the strings "1.5" and booleans as numbers: TOML input must hold numbers
        if not isinstance(value, np.ndarray) and not all(
            isinstance(x, (int, float)) and not isinstance(x, bool) for x in np.array(value, dtype=object).flat
        ):
            raise TypeError
    except (TypeError, ValueError, OverflowError):  # OverflowError: an integer too large for a float
        raise field_error(source, field, f"expected rows of {columns} numbers") from None
    if array.size == 0 and allow_empty:
        return np.zeros((0, columns))
    if array.ndim != 2 or array.shape[1] != columns:
        raise field_error(source, field, f"expected rows of {columns} numbers, got shape {array.shape}")
    bad = np.flatnonzero(~np.isfinite(array).all(axis=1))
    if bad.size:
        raise field_error(source, field, f"row {bad[0]} is not finite: {array[bad[0]].tolist()}")
    return array


# ---------------------------------------------------------------- loading
