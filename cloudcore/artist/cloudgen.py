"""Deterministic particle clouds: ellipsoid cumulus, artist boxes filled with sprites, named cloud types.

A cumulus (`cumulus`) is modelled as the union of ellipsoidal "turrets"
resting on a common flat bottom (the condensation level), filled by rejection
sampling with particles whose radii vary around a base size.

Wang (2004, section 3.1) lets artists build a cloud from boxes that a tool
fills with randomly placed sprites, then drops every sprite closer than a cull
distance to one already kept (`box_fill`, `cull_close`); a cull distance of a
third of the sprite size suits typical clouds, a fifth to a sixth dense ones.
`PRESETS` are cloud types built that way (`preset_cloud`), each with the
per-type colour and transparency of his section 5.1 twice over: as Harris
shading overrides and as an artist shading model (`cloudcore.artist.artist_shading`),
and with the atlas sprites it draws (`cloudcore.artist.sprites`, section 3.2).

Same seed, same cloud (the shipped scenes also store the particles, so
goldens never depend on numpy's generator streams).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from cloudcore.model.cloud_records import FOGGY, PUFFY, WISPY, ArtistShading, SpriteStyle
from cloudcore.model.scene import Cloud, Vec3

#: Wang's cull distance for typical clouds, as a fraction of the sprite size (its diameter)
TYPICAL_CULL_FRACTION = 1.0 / 3.0
#: ... and for dense clouds
DENSE_CULL_FRACTION = 1.0 / 5.0
#: the most sprites one box fill scatters: a million take 1.3 s here (660,000 kept at Wang's cull in an 8 km box);
#: the Build panel took 2**31 - 1 typed in and ran out of memory
MAX_BOX_FILL = 1_000_000


def cumulus(centre, size, count: int, particle_radius: float, seed: int) -> np.ndarray:
    """Particles (count, 4) as (x, y, z, radius) for a cumulus whose base centre is `centre`.

    `size` = (width x, height y, depth z) in metres; the base sits at centre y.
    """
    rng = np.random.default_rng(seed)
    width, height, depth = (float(v) for v in size)
    centre = np.asarray(centre, dtype=np.float64)
    turrets = max(3, int(rng.integers(4, 8)))
    offsets = rng.uniform(-0.5, 0.5, (turrets, 3)) * np.array([width * 0.55, 0.0, depth * 0.55])
    radii = np.stack(
        [
            rng.uniform(0.30, 0.45, turrets) * width,
            rng.uniform(0.55, 1.0, turrets) * height,
            rng.uniform(0.30, 0.45, turrets) * depth,
        ],
        axis=1,
    )
    # the biggest turret sits in the middle so the cloud has a dominant head
    offsets[0] = 0.0
    radii[0] = (0.5 * width, height, 0.5 * depth)

    accepted = np.zeros((0, 3))
    while len(accepted) < count:
        batch = rng.uniform(-0.5, 0.5, (4 * count, 3)) * np.array([width * 1.3, 2 * height, depth * 1.3])
        batch[:, 1] = np.abs(batch[:, 1])  # flat bottom: nothing below the base
        inside = np.zeros(len(batch), dtype=bool)
        for offset, radius in zip(offsets, radii):
            inside |= (((batch - offset) / radius) ** 2).sum(axis=1) <= 1.0
        accepted = np.concatenate([accepted, batch[inside]])
    positions = centre + accepted[:count]
    # bigger puffs deep inside, smaller at the rim keep the silhouette crisp
    reach = np.min([(((accepted[:count] - o) / r) ** 2).sum(axis=1) for o, r in zip(offsets, radii)], axis=0)
    radius = particle_radius * rng.uniform(0.75, 1.25, count) * (1.15 - 0.35 * np.sqrt(np.clip(reach, 0, 1)))
    return np.column_stack([positions, radius])


def cull_close(positions: np.ndarray, cull_distance: float) -> np.ndarray:
    """Indices of the particles kept when walking `positions` in order and dropping each one
    within `cull_distance` of a particle already kept (Wang 2004, section 3.1).

    No two kept particles are within `cull_distance` of each other; a distance
    of 0 keeps them all.
    """
    positions = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
    if not cull_distance > 0 or len(positions) < 2:
        return np.arange(len(positions))
    pairs = cKDTree(positions).query_pairs(cull_distance, output_type="ndarray")  # rows (i, j), i < j
    pairs = pairs[np.argsort(pairs[:, 0], kind="stable")]
    firsts, starts = np.unique(pairs[:, 0], return_index=True)
    ends = np.append(starts[1:], len(pairs))
    dropped = np.zeros(len(positions), dtype=bool)
    # the walk is sequential (whether j is dropped depends on whether its earlier neighbours were kept),
    # but it visits only particles that have a neighbour later in the list
    for first, start, end in zip(firsts, starts, ends):
        if not dropped[first]:
            dropped[pairs[start:end, 1]] = True
    return np.flatnonzero(~dropped)


def box_fill(
    box_min, box_max, particle_radius: float, count: int, cull_distance: float | None = None, seed: int = 0
) -> np.ndarray:
    """Particles (n, 4) as (x, y, z, radius), n <= count: `count` sprite centres placed uniformly in
    the box [box_min, box_max], then culled (`cull_close`).

    The cull distance defaults to a third of the sprite size (2 `particle_radius`), Wang's value
    for typical clouds.
    """
    box_min, box_max = _checked_box(box_min, box_max)
    _check_positive("particle_radius", particle_radius)
    if cull_distance is None:
        cull_distance = TYPICAL_CULL_FRACTION * 2.0 * particle_radius
    elif not (math.isfinite(cull_distance) and cull_distance >= 0):
        raise ValueError(f"cull_distance must be finite and >= 0, got {cull_distance}")
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or not 0 <= count <= MAX_BOX_FILL:
        raise ValueError(f"count must be an integer within [0, {MAX_BOX_FILL:,}], got {count!r}")
    centres = np.random.default_rng(seed).uniform(box_min, box_max, (int(count), 3))
    kept = centres[cull_close(centres, cull_distance)]
    return np.column_stack([kept, np.full(len(kept), float(particle_radius))])


def _checked_box(box_min, box_max) -> tuple[np.ndarray, np.ndarray]:
    low = np.asarray(box_min, dtype=np.float64)
    high = np.asarray(box_max, dtype=np.float64)
    if low.shape != (3,) or high.shape != (3,):
        raise ValueError(f"box corners must be 3-vectors, got shapes {low.shape} and {high.shape}")
    with np.errstate(over="ignore"):  # an infinite extent is refused just below
        extent = high - low
    if not (np.all(np.isfinite(low)) and np.all(np.isfinite(extent))):
        raise ValueError(f"box corners must be finite with a finite extent, got {low.tolist()} and {high.tolist()}")
    if np.any(high < low):
        raise ValueError(f"box_max must be >= box_min in every axis, got {low.tolist()} and {high.tolist()}")
    return low, high


def _check_positive(name: str, value: float) -> None:
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"{name} must be finite and > 0, got {value}")


@dataclass(frozen=True)
class CloudPreset:
    """A cloud type as an artist builds it: boxes filled with sprites, its sprites and its shading (Wang 2004).

    Lengths are metres at scale 1.  Each box is (low corner, high corner) in
    fractions of `size`: x and z from -0.5 to 0.5 about the cloud's centre, y
    from 0 (the base) to 1 (the top).  `count` sprites are shared among the
    boxes by volume, and culled at `cull_fraction` of the sprite size.
    """

    size: Vec3  # width (x), height (y), depth (z)
    boxes: tuple[tuple[Vec3, Vec3], ...]
    particle_radius: float
    count: int
    cull_fraction: float
    optical_depth: float
    albedo: float
    color: Vec3
    sprite: SpriteStyle  # its seed is replaced by preset_cloud's
    artist: ArtistShading


_WHOLE = ((-0.5, 0.0, -0.5), (0.5, 1.0, 0.5))


def _levels(bottom: Vec3, top: Vec3, alpha: tuple[float, ...] = (1.0,) * 5) -> tuple:
    """Five colour levels at heights 0, 0.2, 0.45, 0.75, 1 from `bottom` to `top`, lightening fastest
    low down, where Wang's artists darken the bases; one alpha per level."""
    heights = (0.0, 0.2, 0.45, 0.75, 1.0)
    weights = (0.0, 0.4, 0.7, 0.9, 1.0)
    # rounded so that scene files show the numbers an artist would type
    return tuple(
        (h, *(round(b + w * (t - b), 3) for b, t in zip(bottom, top)), a) for h, w, a in zip(heights, weights, alpha)
    )


#: camera-facing puffs and wisps, any rotation, flat-bottom sprites along the base
_CUMULUS_SPRITES = SpriteStyle(rows=(PUFFY, PUFFY, WISPY), flat_bottom_fraction=0.12)

#: cloud types by name.  Colour levels after Wang section 5.1: stratus light grey and more transparent,
#: cumulus humilis nearly uniformly white, cumulonimbus dark from top to bottom; the others between,
#: darker at the base.  Directional ranges: more contrast for towering clouds, little for layers.
#: Sprites after section 3.2: foggy textures for stratus, puffy ones with flat bottoms for cumulus,
#: wisps everywhere; cirrus as flat textured quads (section 7.1).
PRESETS: dict[str, CloudPreset] = {
    "cumulus_humilis": CloudPreset(
        size=(900.0, 450.0, 800.0),
        boxes=(((-0.5, 0.0, -0.5), (0.5, 0.45, 0.5)), ((-0.3, 0.3, -0.3), (0.3, 1.0, 0.3))),
        particle_radius=75.0,
        count=160,
        cull_fraction=TYPICAL_CULL_FRACTION,
        optical_depth=6.0,
        albedo=0.9,
        color=(1.0, 1.0, 1.0),
        sprite=_CUMULUS_SPRITES,
        artist=ArtistShading(levels=_levels((0.62, 0.64, 0.68), (0.82, 0.82, 0.84))),
    ),
    "cumulus_congestus": CloudPreset(
        size=(1800.0, 3000.0, 1600.0),
        boxes=(
            ((-0.5, 0.0, -0.5), (0.5, 0.3, 0.5)),
            ((-0.35, 0.2, -0.35), (0.35, 0.8, 0.35)),
            ((-0.2, 0.7, -0.2), (0.25, 1.0, 0.2)),
        ),
        particle_radius=170.0,
        count=700,
        cull_fraction=TYPICAL_CULL_FRACTION,
        optical_depth=10.0,
        albedo=0.9,
        color=(0.96, 0.96, 0.98),
        sprite=dataclasses.replace(_CUMULUS_SPRITES, flat_bottom_fraction=0.06),
        artist=ArtistShading(levels=_levels((0.36, 0.38, 0.43), (0.80, 0.80, 0.82)), directional_range=(0.1, 0.6, 1.0)),
    ),
    "stratus": CloudPreset(
        size=(9000.0, 300.0, 7000.0),
        boxes=(_WHOLE,),
        particle_radius=220.0,
        count=1000,
        cull_fraction=TYPICAL_CULL_FRACTION,
        optical_depth=3.0,
        albedo=0.85,
        color=(0.80, 0.82, 0.86),
        sprite=SpriteStyle(rows=(FOGGY, FOGGY, FOGGY, WISPY)),
        artist=ArtistShading(
            levels=_levels((0.50, 0.52, 0.56), (0.62, 0.63, 0.66), (0.5, 0.55, 0.55, 0.5, 0.4)),
            directional_range=(0.4, 0.75, 1.0),
        ),
    ),
    "stratocumulus": CloudPreset(
        size=(4500.0, 600.0, 4000.0),
        boxes=(
            ((-0.5, 0.0, -0.5), (0.5, 0.55, 0.5)),
            ((-0.4, 0.3, -0.35), (-0.05, 1.0, 0.05)),
            ((0.05, 0.3, -0.1), (0.4, 0.9, 0.4)),
            ((-0.3, 0.3, 0.15), (0.1, 0.85, 0.45)),
        ),
        particle_radius=200.0,
        count=800,
        cull_fraction=TYPICAL_CULL_FRACTION,
        optical_depth=5.0,
        albedo=0.88,
        color=(0.86, 0.87, 0.90),
        sprite=SpriteStyle(rows=(FOGGY, PUFFY, PUFFY, WISPY), flat_bottom_fraction=0.1),
        artist=ArtistShading(
            levels=_levels((0.40, 0.42, 0.46), (0.66, 0.67, 0.70), (0.9, 0.95, 1.0, 1.0, 0.95)),
            directional_range=(0.2, 0.65, 1.0),
        ),
    ),
    "cumulonimbus": CloudPreset(
        size=(6000.0, 11000.0, 6000.0),
        boxes=(
            ((-0.45, 0.0, -0.45), (0.45, 0.25, 0.45)),
            ((-0.3, 0.15, -0.3), (0.3, 0.85, 0.3)),
            ((-0.5, 0.82, -0.5), (0.5, 1.0, 0.5)),
        ),
        particle_radius=600.0,
        count=1400,
        cull_fraction=DENSE_CULL_FRACTION,
        optical_depth=16.0,
        albedo=0.95,
        color=(0.62, 0.64, 0.68),
        sprite=SpriteStyle(rows=(PUFFY, PUFFY, FOGGY, WISPY), flat_bottom_fraction=0.05),
        artist=ArtistShading(
            levels=_levels((0.12, 0.13, 0.16), (0.42, 0.43, 0.46)), directional_range=(0.05, 0.5, 1.0)
        ),
    ),
    "altocumulus": CloudPreset(
        size=(3000.0, 250.0, 3000.0),
        boxes=(_WHOLE,),
        particle_radius=70.0,
        count=600,
        cull_fraction=TYPICAL_CULL_FRACTION,
        optical_depth=4.0,
        albedo=0.9,
        color=(0.95, 0.95, 0.97),
        sprite=SpriteStyle(rows=(PUFFY, PUFFY, WISPY)),
        artist=ArtistShading(
            levels=_levels((0.58, 0.60, 0.64), (0.76, 0.77, 0.79), (0.8, 0.85, 0.9, 0.9, 0.85)),
            directional_range=(0.25, 0.7, 1.0),
        ),
    ),
    # few large wisps lying flat, all within 20 degrees of one heading, as high winds comb cirrus
    "cirrus": CloudPreset(
        size=(7000.0, 300.0, 5000.0),
        boxes=(_WHOLE,),
        particle_radius=500.0,
        count=120,
        cull_fraction=TYPICAL_CULL_FRACTION,
        optical_depth=1.5,
        albedo=0.9,
        color=(0.97, 0.97, 1.0),
        sprite=SpriteStyle(rows=(WISPY,), rotation_deg=(-20.0, 20.0), facing="horizontal"),
        artist=ArtistShading(
            levels=_levels((0.74, 0.76, 0.80), (0.80, 0.82, 0.86), (0.45, 0.5, 0.5, 0.5, 0.45)),
            directional_range=(0.5, 0.8, 1.0),
        ),
    ),
}


def preset_cloud(preset: str, name: str, base_centre, scale: float = 1.0, seed: int = 0) -> Cloud:
    """A `Cloud` of type `preset` (a key of PRESETS) whose base is centred on `base_centre`.

    `scale` multiplies every length of the preset (boxes and sprites), so the
    same seed gives the same cloud shape at any scale.  The cloud carries the
    preset's sprite style (with `seed`, an integer in [0, 2^31 - 1]) and artist
    shading model; its shading groups take the default size.
    """
    if preset not in PRESETS:
        raise ValueError(f"unknown cloud preset {preset!r}; presets: {', '.join(PRESETS)}")
    _check_positive("scale", scale)
    base_centre = np.asarray(base_centre, dtype=np.float64)
    if base_centre.shape != (3,) or not np.all(np.isfinite(base_centre)):
        raise ValueError(f"base_centre must be a finite 3-vector, got {base_centre.tolist()}")
    p = PRESETS[preset]
    with np.errstate(over="ignore", invalid="ignore"):  # a cloud too large for float64 is refused just below
        corners = base_centre + np.array(p.boxes, dtype=np.float64) * (scale * np.asarray(p.size))  # (boxes, 2, 3)
        extents = corners[:, 1] - corners[:, 0]
    radius = scale * p.particle_radius
    if not (np.all(np.isfinite(corners)) and np.all(np.isfinite(extents))):
        raise ValueError(f"scale {scale} at {base_centre.tolist()} puts the cloud beyond finite coordinates")
    volumes = np.prod(extents, axis=1)
    rng = np.random.default_rng(seed)
    per_box = rng.multinomial(p.count, volumes / volumes.sum())
    centres = np.concatenate([rng.uniform(low, high, (n, 3)) for (low, high), n in zip(corners, per_box)])
    kept = centres[cull_close(centres, p.cull_fraction * 2.0 * radius)]
    return Cloud(
        name,
        np.column_stack([kept, np.full(len(kept), radius)]),
        optical_depth=p.optical_depth,
        albedo=p.albedo,
        color=p.color,
        sprite=dataclasses.replace(p.sprite, seed=seed),
        artist=p.artist,
    )
