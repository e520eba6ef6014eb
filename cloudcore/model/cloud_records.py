"""What a cloud carries besides its particles: Wang's artist shading model, sprite style and formation.

These are records of the scene model (`cloudcore.model.scene.Cloud` holds them), validated on
construction, so the model depends on no feature: the features that use them
(`cloudcore.artist`: artist_shading, sprites, formation) import them from here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from cloudcore.model.errors import FieldError

LEVEL_COUNT = 5

#: percent of the level colours by hour; more keys around dawn and dusk, where it changes fastest
#: (Wang: "we allow more samples around dawn and dusk").  The sun of cloudcore.light.lighting rises near
#: 05:15 and sets near 18:45.
DEFAULT_LEVEL_PERCENT_BY_HOUR = (
    (0.0, 10.0),
    (4.5, 12.0),
    (5.0, 25.0),
    (5.5, 45.0),
    (6.0, 70.0),
    (7.0, 90.0),
    (9.0, 100.0),
    (15.0, 100.0),
    (17.0, 90.0),
    (18.0, 70.0),
    (18.5, 45.0),
    (19.0, 25.0),
    (19.5, 12.0),
)
#: the maximum directional colour by hour: cloudcore.light.lighting's sun beam at these hours (red low in the
#: sky, warm white by day, none at night), scaled to leave the levels room below white
DEFAULT_DIRECTIONAL_COLOUR_BY_HOUR = (
    (0.0, 0.0, 0.0, 0.0),
    (4.75, 0.0, 0.0, 0.0),
    (5.25, 0.22, 0.08, 0.02),
    (5.75, 0.38, 0.24, 0.10),
    (6.5, 0.42, 0.35, 0.24),
    (8.0, 0.44, 0.41, 0.34),
    (12.0, 0.45, 0.43, 0.38),
    (16.0, 0.44, 0.41, 0.34),
    (17.5, 0.42, 0.35, 0.24),
    (18.25, 0.38, 0.24, 0.10),
    (18.75, 0.22, 0.08, 0.02),
    (19.25, 0.0, 0.0, 0.0),
)
#: (min, median, max) fractions of the directional colour.  Wang leaves them to the artist and gives
#: no numbers; a median above the middle keeps the terminator lit and puts the gradient on the far side.
DEFAULT_DIRECTIONAL_RANGE = (0.2, 0.7, 1.0)
#: a nearly white cloud, greyer at the bottom
DEFAULT_LEVELS = (
    (0.0, 0.62, 0.64, 0.68, 1.0),
    (0.15, 0.70, 0.71, 0.74, 1.0),
    (0.4, 0.76, 0.77, 0.79, 1.0),
    (0.7, 0.80, 0.80, 0.82, 1.0),
    (1.0, 0.82, 0.82, 0.84, 1.0),
)


@dataclass(frozen=True)
class ArtistShading:
    """One cloud's artist shading model (Wang 2004, section 5).

    levels: five rows (height_fraction, r, g, b, a), heights strictly
        increasing in [0, 1] (0 = cloud bottom, 1 = top), colours in [0, 1];
        below the first and above the last level the end colours hold.
    level_percent_by_hour: rows (hour, percent), hours strictly increasing in
        [0, 24), percent >= 0; multiplies the levels' RGB (not their alpha: a
        cloud at night is dark, not gone).
    directional_colour_by_hour: rows (hour, r, g, b), the maximum directional
        colour, hours as above, colours in [0, 1].
    directional_range: (min, median, max) in [0, 1], min <= median <= max: the
        fraction of the directional colour where the dot product is -1, 0, 1.
    """

    levels: tuple[tuple[float, float, float, float, float], ...] = DEFAULT_LEVELS
    level_percent_by_hour: tuple[tuple[float, float], ...] = DEFAULT_LEVEL_PERCENT_BY_HOUR
    directional_colour_by_hour: tuple[tuple[float, float, float, float], ...] = DEFAULT_DIRECTIONAL_COLOUR_BY_HOUR
    directional_range: tuple[float, float, float] = DEFAULT_DIRECTIONAL_RANGE

    def __post_init__(self):
        levels = _rows("levels", self.levels, 5)
        if len(levels) != LEVEL_COUNT:
            raise FieldError("levels", f"expected {LEVEL_COUNT} levels, got {len(levels)}")
        heights = levels[:, 0]
        if np.any(heights < 0.0) or np.any(heights > 1.0) or np.any(np.diff(heights) <= 0.0):
            raise FieldError("levels", f"heights must increase strictly within [0, 1], got {heights.tolist()}")
        _check_unit_interval("levels", levels[:, 1:], "colours")
        percent = _hour_keys("level_percent_by_hour", self.level_percent_by_hour, 2)
        if np.any(percent[:, 1] < 0.0):
            raise FieldError("level_percent_by_hour", f"percentages must be >= 0, got {percent[:, 1].tolist()}")
        directional = _hour_keys("directional_colour_by_hour", self.directional_colour_by_hour, 4)
        _check_unit_interval("directional_colour_by_hour", directional[:, 1:], "colours")
        mapping = _rows("directional_range", [self.directional_range], 3)[0]
        if not 0.0 <= mapping[0] <= mapping[1] <= mapping[2] <= 1.0:
            raise FieldError("directional_range", f"expected 0 <= min <= median <= max <= 1, got {mapping.tolist()}")
        for name, value in (
            ("levels", levels),
            ("level_percent_by_hour", percent),
            ("directional_colour_by_hour", directional),
        ):
            object.__setattr__(self, name, tuple(tuple(row) for row in value.tolist()))
        object.__setattr__(self, "directional_range", tuple(mapping.tolist()))


def _rows(name: str, value, columns: int) -> np.ndarray:
    try:
        array = np.array(value, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        raise FieldError(name, f"expected rows of {columns} numbers") from None
    if array.ndim != 2 or array.shape[1] != columns or len(array) == 0:
        raise FieldError(name, f"expected one or more rows of {columns} numbers, got shape {array.shape}")
    if not np.all(np.isfinite(array)):
        raise FieldError(name, "values must be finite")
    return array


def _check_unit_interval(name: str, values: np.ndarray, what: str) -> None:
    if np.any(values < 0.0) or np.any(values > 1.0):
        raise FieldError(name, f"{what} must be within [0, 1]")


def _hour_keys(name: str, value, columns: int) -> np.ndarray:
    keys = _rows(name, value, columns)
    hours = keys[:, 0]
    if np.any(hours < 0.0) or np.any(hours >= 24.0) or np.any(np.diff(hours) <= 0.0):
        raise FieldError(name, f"hours must increase strictly within [0, 24), got {hours.tolist()}")
    return keys


ATLAS_GRID = 4
#: atlas rows, top to bottom
ROWS = ("flat_bottom", "foggy", "puffy", "wispy")
FLAT_BOTTOM, FOGGY, PUFFY, WISPY = range(len(ROWS))
FACINGS = ("camera", "horizontal")
MAX_SEED = 2**31 - 1
#: Wang: "all other sprites the full range of rotation (0 to 360 degrees)"
FULL_CIRCLE_DEG = (0.0, 360.0)
#: Wang: "cumulus cloud bottoms a narrow range" of about 5 degrees either way, so the flat edge stays down
NARROW_DEG = (-5.0, 5.0)


@dataclass(frozen=True)
class SpriteStyle:
    """How a cloud's particles draw from the atlas (Wang 2004, sections 3.2 and 7.1).

    rows: atlas rows the sprites are drawn from, uniformly per entry (a row
        listed twice is drawn twice as often).
    rotation_deg: (low, high) range of each sprite's rotation in its plane,
        counter-clockwise as seen by the viewer, 0 = upright; at most 360 wide.
    facing: "camera" (billboards turned toward the eye, locked near it:
        `cloudcore.artist.facing`) or "horizontal" (flat quads parallel to the ground,
        Wang's cirrus: "flat textured rectangles").
    seed: the per-cloud seed of every choice.
    flat_bottom_fraction: particles whose centres lie in this lowest fraction
        of the cloud's height draw the flat-bottom row instead, with rotations
        in `flat_bottom_rotation_deg` (Wang: flat textures "create flat bottoms
        in cumulus clouds", with a narrow rotation range); 0 = none.
    """

    rows: tuple[int, ...] = (PUFFY, WISPY)
    rotation_deg: tuple[float, float] = FULL_CIRCLE_DEG
    facing: str = "camera"
    seed: int = 0
    flat_bottom_fraction: float = 0.0
    flat_bottom_rotation_deg: tuple[float, float] = NARROW_DEG

    def __post_init__(self):
        rows = tuple(self.rows)
        if not rows or not all(
            isinstance(r, (int, np.integer)) and not isinstance(r, bool) and 0 <= r < ATLAS_GRID for r in rows
        ):
            raise FieldError("rows", f"expected one or more atlas rows in 0..{ATLAS_GRID - 1}, got {list(rows)}")
        object.__setattr__(self, "rows", tuple(int(r) for r in rows))
        for name in ("rotation_deg", "flat_bottom_rotation_deg"):
            object.__setattr__(self, name, _rotation_range(name, getattr(self, name)))
        if self.facing not in FACINGS:
            raise FieldError("facing", f"{self.facing!r} is not one of: {', '.join(FACINGS)}")
        if (
            isinstance(self.seed, bool)
            or not isinstance(self.seed, (int, np.integer))
            or not 0 <= self.seed <= MAX_SEED
        ):
            raise FieldError("seed", f"expected an integer in [0, {MAX_SEED}], got {self.seed!r}")
        object.__setattr__(self, "seed", int(self.seed))
        fraction = float(self.flat_bottom_fraction)
        if not 0.0 <= fraction <= 1.0:
            raise FieldError("flat_bottom_fraction", f"must be within [0, 1], got {fraction}")
        object.__setattr__(self, "flat_bottom_fraction", fraction)


def _rotation_range(name: str, value) -> tuple[float, float]:
    low, high = (float(v) for v in value)
    if not (math.isfinite(low) and math.isfinite(high)):
        raise FieldError(name, f"must be finite, got [{low}, {high}]")
    if not low <= high <= low + 360.0:
        raise FieldError(name, f"expected [low, high] with low <= high <= low + 360, got [{low}, {high}]")
    return low, high


FORMATION_KINDS = ("form", "dissipate")


@dataclass(frozen=True)
class Formation:
    """A cloud forming or dissipating over `duration_s` seconds from `start_s` on the scene clock."""

    kind: str
    start_s: float
    duration_s: float

    def __post_init__(self):
        object.__setattr__(self, "start_s", float(self.start_s))
        object.__setattr__(self, "duration_s", float(self.duration_s))
        if self.kind not in FORMATION_KINDS:
            raise ValueError(f"formation kind {self.kind!r} is not one of: {', '.join(FORMATION_KINDS)}")
        if not math.isfinite(self.start_s):
            raise ValueError(f"formation start_s must be finite, got {self.start_s}")
        if not (math.isfinite(self.duration_s) and self.duration_s >= 0):
            raise ValueError(f"formation duration_s must be finite and >= 0, got {self.duration_s}")
