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

import numpy as np

from cloudcore.maths.vectors import unit_rows
from cloudcore.model.cloud_records import ArtistShading

#: shading groups: grid cells this many median particle radii wide, a few to a few tens of
#: sprites each in the presets (Wang: groups of 1 to 30 sprites)
DEFAULT_GROUP_RADII = 3.0


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
    """Whether `shading_groups` can number this cloud's groups (cloudcore.scenes.limits checks scenes with it)."""
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
