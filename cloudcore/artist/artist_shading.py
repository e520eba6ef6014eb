"""Wang's artist-driven cloud shading (2004, section 5): an alternative to Harris's scattering, per cloud.

Two terms per sprite vertex, both set by an artist rather than computed from
light transport:

- ambient (section 5.1, equation 1): five colour levels up the cloud, each a
  height and an RGBA colour, interpolated at the vertex's height and
  multiplied by a percentage that follows the time of day;
- directional (section 5.2, equation 2): sprites belong to shading groups,
  "clumps on the cloud"; the dot product of the unit vectors from the group
  centre to the vertex and from the group centre to the sun, mapped with a bias
  so that [-1, 0] covers [min, median] and [0, 1] covers [median, max], is the
  fraction of the hour's maximum directional colour the vertex receives.

The vertex colour is their sum, clamped to [0, 1]; the renderer multiplies it
by the sprite texture and the formation factor (section 5.3, equation 3).
`artist_colours` is the reference; `artist_uniforms` gives the per-cloud values
a vertex shader needs to reproduce it.

Level heights are fractions of the cloud's vertical extent (0 its bottom,
1 its top), so a model suits a cloud of any size.  The time-of-day tables are
piecewise linear in the hour and wrap over midnight.  Wang has no separate
ambient colour by hour: the level percentage is that curve.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from cloudcore.errors import FieldError
from cloudcore.vectors import unit_rows

LEVEL_COUNT = 5
#: shading groups: grid cells this many median particle radii wide, a few to a few tens of
#: sprites each in the presets (Wang: groups of 1 to 30 sprites)
DEFAULT_GROUP_RADII = 3.0

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


def _at_hour(keys, hour: float) -> np.ndarray:
    """The table `keys` (rows hour, values...) interpolated linearly at `hour`, wrapping over 24 h."""
    if not (math.isfinite(hour) and 0.0 <= hour <= 24.0):
        raise ValueError(f"hour must be within [0, 24], got {hour}")
    keys = np.asarray(keys, dtype=np.float64)
    hours = np.concatenate([keys[-1:, 0] - 24.0, keys[:, 0], keys[:1, 0] + 24.0])
    values = np.concatenate([keys[-1:, 1:], keys[:, 1:], keys[:1, 1:]])
    return np.array([np.interp(hour, hours, column) for column in values.T])


def height_fractions(y, bottom_y: float, top_y: float) -> np.ndarray:
    """Heights `y` as fractions of the cloud's vertical extent, clamped to [0, 1].

    A cloud of zero height (a flat layer) puts every vertex at 0.5, the
    middle of its levels.
    """
    y = np.asarray(y, dtype=np.float64)
    if not (math.isfinite(bottom_y) and math.isfinite(top_y) and bottom_y <= top_y):
        raise ValueError(f"expected finite bottom_y <= top_y, got {bottom_y} and {top_y}")
    extent = top_y - bottom_y
    if not extent > 0.0:
        return np.full(y.shape, 0.5)
    return np.clip((y - bottom_y) / extent, 0.0, 1.0)


def _level_colours(model: ArtistShading, hour: float) -> np.ndarray:
    """The five level colours (5, 4) at `hour`: RGB times the hour's percentage, alpha as set."""
    colours = np.array(model.levels, dtype=np.float64)[:, 1:]
    colours[:, :3] *= _at_hour(model.level_percent_by_hour, hour)[0] / 100.0
    return colours


def vertical_colour(model: ArtistShading, heights_fraction, hour: float) -> np.ndarray:
    """Wang's ambient colour (n, 4) RGBA at height fractions (n,) and `hour` (section 5.1, equation 1):
    linear between levels, the end colours beyond."""
    fractions = np.clip(np.asarray(heights_fraction, dtype=np.float64).reshape(-1), 0.0, 1.0)
    heights, colours = np.array(model.levels)[:, 0], _level_colours(model, hour)
    return np.stack([np.interp(fractions, heights, channel) for channel in colours.T], axis=-1)


def directional_factor(vertex_positions, group_centres_per_vertex, sun_direction, model: ArtistShading) -> np.ndarray:
    """Each vertex's fraction (n,) of the directional colour (Wang section 5.2, the mapping of equation 2).

    d = dot(unit(vertex - group centre), unit(sun_direction)); [-1, 0] maps
    linearly to [min, median] and [0, 1] to [median, max] of
    `model.directional_range`.  A vertex at its group's centre, or a zero sun
    vector, has no direction: d = 0, the median.  `sun_direction` points from
    the scene toward the sun; below the horizon it is used as it is (the
    directional colour of those hours is what darkens it).
    """
    vertices = _finite_points("vertex_positions", vertex_positions)
    centres = _finite_points("group_centres_per_vertex", group_centres_per_vertex)
    if centres.shape != vertices.shape:
        raise ValueError(f"group_centres_per_vertex must match vertex_positions {vertices.shape}, got {centres.shape}")
    sun = _finite_points("sun_direction", sun_direction)
    if sun.shape != (1, 3):
        raise ValueError(f"sun_direction must be a 3-vector, got shape {np.shape(sun_direction)}")
    low, median, high = model.directional_range
    with np.errstate(over="ignore"):  # a difference beyond float range is refused just below
        outward = vertices - centres
    if not np.all(np.isfinite(outward)):
        raise ValueError("vertex_positions - group_centres_per_vertex overflows")
    d = np.clip(unit_rows(outward) @ unit_rows(sun)[0], -1.0, 1.0)
    return np.where(d < 0.0, median + d * (median - low), median + d * (high - median))


def _finite_points(name: str, value) -> np.ndarray:
    points = np.asarray(value, dtype=np.float64)
    if points.shape[-1:] != (3,):
        raise ValueError(f"{name} must be rows of 3 numbers, got shape {points.shape}")
    if not np.all(np.isfinite(points)):
        raise ValueError(f"{name} must be finite")
    return points.reshape(-1, 3)


def artist_uniforms(model: ArtistShading, hour: float, sun_direction) -> dict[str, np.ndarray]:
    """The per-cloud values the vertex shader needs at `hour`, as float64 arrays.

    level_heights (5,): height fractions of the levels.
    level_colours (5, 4): level RGBA, RGB already times the hour's percentage.
    directional_colour (3,): the hour's maximum directional colour.
    directional_range (3,): (min, median, max).
    sun_direction (3,): unit, toward the sun (zeros for a zero vector).

    Per vertex the shader then computes, exactly as `artist_colours` (bottom_y and top_y are the
    cloud's lowest and highest particle centre; GLSL's normalize(0) is NaN, hence the test on length):
    f = clamp((y - bottom_y) / (top_y - bottom_y), 0, 1) (0.5 when top_y == bottom_y);
    ambient = level_colours linearly interpolated at f over level_heights (end colours beyond);
    v = vertex - group centre, d = length(v) > 0 ? dot(v / length(v), sun_direction) : 0;
    t = d < 0 ? median + d (median - min) : median + d (max - median);
    colour = clamp(ambient + vec4(directional_colour * t, 0), 0, 1).
    """
    sun = _finite_points("sun_direction", sun_direction)
    if sun.shape != (1, 3):
        raise ValueError(f"sun_direction must be a 3-vector, got shape {np.shape(sun_direction)}")
    return {
        "level_heights": np.array(model.levels, dtype=np.float64)[:, 0],
        "level_colours": _level_colours(model, hour),
        "directional_colour": _at_hour(model.directional_colour_by_hour, hour),
        "directional_range": np.array(model.directional_range, dtype=np.float64),
        "sun_direction": unit_rows(sun)[0],
    }


def artist_colours(
    model: ArtistShading,
    vertex_positions,
    cloud_bottom_y: float,
    cloud_top_y: float,
    group_centres_per_vertex,
    sun_direction,
    hour: float,
) -> np.ndarray:
    """Wang's vertex colour (n, 4) RGBA in [0, 1]: ambient + directional, before texture and formation.

    `cloud_bottom_y` and `cloud_top_y` bound the cloud's vertical extent: its
    lowest and highest particle centre (as `cloudcore.artist.sprites.particle_sprites`
    measures it); vertices beyond take the end levels.

    The reference the GLSL matches (Wang section 5.3, equation 3 without its
    texture and formation factors): vertical colour levels at the vertex's
    height fraction times the hour's percentage, plus the hour's directional
    colour times `directional_factor`, clamped.  The directional term has no
    alpha: the vertex's alpha is its level's.
    """
    uniforms = artist_uniforms(model, hour, sun_direction)
    vertices = _finite_points("vertex_positions", vertex_positions)
    fractions = height_fractions(vertices[:, 1], cloud_bottom_y, cloud_top_y)
    ambient = vertical_colour(model, fractions, hour)
    factor = directional_factor(vertices, group_centres_per_vertex, sun_direction, model)
    directional = np.column_stack([factor[:, None] * uniforms["directional_colour"], np.zeros(len(factor))])
    return np.clip(ambient + directional, 0.0, 1.0)


def shading_groups(centres, group_size_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Shading groups of a cloud's particles: (group_index (n,) int64, group_centres (g, 3)).

    Wang's artists number the groups box by box (section 5.2); here they are
    the cells of a grid of `group_size_m` anchored at the particles' lowest
    corner (so moving a cloud never regroups it), each group's centre the
    mean of its particles.  Groups are numbered in the grid's lexicographic
    order; the vertices of particle i use group_centres[group_index[i]].
    """
    centres = _finite_points("centres", centres)
    if not (math.isfinite(group_size_m) and group_size_m > 0.0):
        raise ValueError(f"group_size_m must be finite and > 0, got {group_size_m}")
    if len(centres) == 0:
        return np.zeros(0, dtype=np.int64), np.zeros((0, 3))
    cells = _grid_cells(centres, group_size_m)
    if not _cells_exact(cells):
        raise ValueError(f"group_size_m {group_size_m} is too small for a cloud this large")
    _, group_index = np.unique(cells.astype(np.int64), axis=0, return_inverse=True)
    group_index = group_index.reshape(-1)
    counts = np.bincount(group_index)
    sums = np.stack([np.bincount(group_index, weights=centres[:, axis]) for axis in range(3)], axis=1)
    return group_index.astype(np.int64), sums / counts[:, None]


def shading_grid_fits(centres, group_size_m: float) -> bool:
    """Whether `shading_groups` can number this cloud's groups (cloudcore.limits checks scenes with it)."""
    centres = np.asarray(centres, dtype=np.float64).reshape(-1, 3)
    return len(centres) == 0 or _cells_exact(_grid_cells(centres, group_size_m))


def _grid_cells(centres: np.ndarray, group_size_m: float) -> np.ndarray:
    with np.errstate(over="ignore"):
        return np.floor((centres - centres.min(axis=0)) / group_size_m)


def _cells_exact(cells: np.ndarray) -> bool:
    """Beyond 2**53 the cell numbers stop being exact integers (an infinite extent is beyond too)."""
    return bool(np.all(cells < 2.0**53))


def default_group_size(radii) -> float:
    """The shading group size of a cloud that does not set one: DEFAULT_GROUP_RADII median radii."""
    radii = np.asarray(radii, dtype=np.float64)
    # a cloud without particles has no groups; any positive size will do
    return DEFAULT_GROUP_RADII * float(np.median(radii)) if len(radii) else 1.0
