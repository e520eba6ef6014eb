"""What the renderer asks of the air: the tables for its parameters (cached on disk), the sky seen from an
altitude, the sun's light where it reaches that altitude, and the sky's irradiance on an upward surface.

Radiances and irradiances are per unit of the sun's irradiance at the top of the air.  World directions
are y up; the scene's origin stands at `altitude_m` on the planet, and the sky is the one seen from there.
"""

from __future__ import annotations

import dataclasses
import functools
import time
from dataclasses import dataclass

import numpy as np

from cloudcore.atmosphere import multiple_scattering, sky_view, transmittance
from cloudcore.atmosphere.geometry import distance_to_top, horizon_cosine
from cloudcore.atmosphere.parameters import AtmosphereParameters
from cloudcore.atmosphere.scattering import in_scattering
from cloudcore.atmosphere.sun_disc import visible_fraction
from cloudcore.runtime import disk_cache

#: the disk cache's name for the transmittance and multiple-scattering tables (`cloudcore.runtime.disk_cache`)
CACHE_KIND = "atmosphere"
#: bump when what the tables hold or how they are computed changes: older cache entries are rebuilt
FORMAT_VERSION = 2


@dataclass(frozen=True, eq=False)
class AtmosphereTables:
    """The tables that depend on the air alone."""

    params: AtmosphereParameters
    transmittance: np.ndarray  # (64, 256, 3)
    multiple_scattering: np.ndarray  # (32, 32, 3)
    #: seconds the build took (0 when read from the cache), and whether it was read from the cache
    build_s: float = 0.0
    cached: bool = False


def cache_key(params: AtmosphereParameters) -> dict:
    """Every parameter the tables depend on, as the disk cache keys them."""
    return {
        "format": FORMAT_VERSION,
        "params": dataclasses.asdict(params),
        "transmittance": [transmittance.TRANSMITTANCE_TABLE_SIZE, transmittance.TRANSMITTANCE_SAMPLES],
        "multiple_scattering": [
            multiple_scattering.MULTIPLE_SCATTERING_TABLE_SIZE,
            multiple_scattering.SQRT_DIRECTIONS,
            multiple_scattering.MULTIPLE_SCATTERING_SAMPLES,
        ],
    }


def build_tables(params: AtmosphereParameters) -> dict[str, np.ndarray]:
    """The tables' arrays, computed (a quarter of a second on two cores: `atmosphere_tables` caches them)."""
    transmittance_table = transmittance.build_transmittance_table(params)
    return {
        "transmittance": transmittance_table,
        "multiple_scattering": multiple_scattering.build_multiple_scattering_table(params, transmittance_table),
    }


@functools.lru_cache(maxsize=8)
def atmosphere_tables(params: AtmosphereParameters) -> AtmosphereTables:
    """The tables of `params`: from memory, from the disk cache (shipped for the default air), or built."""
    start = time.perf_counter()
    arrays, cached = disk_cache.load_or_build(CACHE_KIND, cache_key(params), lambda: build_tables(params))
    return AtmosphereTables(params, **arrays, build_s=0.0 if cached else time.perf_counter() - start, cached=cached)


@dataclass(frozen=True, eq=False)
class SkyView:
    """The sky seen from one altitude under one sun: its sky-view table and the lookup into it.

    The table is built when first read: the editor's world pass reads the sky from the eye's altitude
    (`SkyBackground.seen_from`), not the scene origin's it is made from, whose table, built for nothing, cost each
    look of a dragged time-of-day slider a coarse table more and a released one a full table more
    (docs/performance.md, "A look's parts")."""

    tables: AtmosphereTables
    altitude_m: float
    sun_direction: np.ndarray  # (3,) unit, toward the sun
    #: a dragged slider's coarser sky (`sky_seen_from`), whose air between the eye and what it sees is coarser too
    preview: bool = False

    @property
    def table(self) -> np.ndarray:
        """(108, 192, 3): the air's light along each view, in front of the ground below the horizon
        (`sky_view.build_sky_view_table`)."""
        return self._tables()[0]

    @property
    def row_transmittance(self) -> np.ndarray:
        """(108, 3): the air's transmittance along each of the table's rows, to the ground below the horizon."""
        return self._tables()[1]

    def built(self) -> SkyView:
        """This sky with its table built now: where a worker makes it (`cloudcore.light.live_air`), not in the
        frame that first reads it."""
        self._tables()
        return self

    def _tables(self) -> tuple[np.ndarray, np.ndarray]:
        # held on the instance without a lock (functools.cached_property's is one for every instance in Python
        # 3.11: the frame would wait on the air worker's build of another sky); two threads that both build it
        # build the same table
        tables = self.__dict__.get("_built_tables")
        if tables is None:
            below, above, share = altitude_knots(self.altitude_m)
            if share == 0.0 and below == self.altitude_m:
                tables = sky_view.build_sky_view_table(
                    self.tables.params,
                    self.tables.transmittance,
                    self.tables.multiple_scattering,
                    self.altitude_m,
                    float(self.sun_direction[1]),
                    self.preview,
                )
            else:  # between two knots: their tables blended, as `altitude_knots` says
                sun = tuple(float(c) for c in self.sun_direction)
                low, high = (
                    _sky_view(self.tables.params, knot, sun, self.preview)._tables() for knot in (below, above)
                )
                tables = tuple((1.0 - share) * a + share * b for a, b in zip(low, high, strict=True))
            object.__setattr__(self, "_built_tables", tables)
        return tables

    def radiance(self, directions) -> np.ndarray:
        """(..., 3): the sky's radiance along unit `directions` (..., 3); below the horizon the air's in front of
        the ground, which it leaves out (`ground_transmittance` lets a ground's light through)."""
        return sky_view.sky_view_lookup(self.tables.params, self.table, self.altitude_m, directions, self.sun_direction)

    def ground_transmittance(self, directions) -> np.ndarray:
        """(..., 3): the air's transmittance along unit `directions` (..., 3) to the ground, where they meet it."""
        rows = self.row_transmittance[:, None, :]
        return sky_view.sky_view_lookup(self.tables.params, rows, self.altitude_m, directions, self.sun_direction)


#: the tables seen from an altitude (the sky-view table, the air's volume: `aerial_perspective`) are built at knots
#: and blended linearly between the two around an altitude between them: a knot at every altitude asked for up to
#: `KNOTS_FROM_M`, where the horizon's rows and the rays that meet the ground change too fast with the eye's
#: altitude to blend, then every `KNOT_STEP_M`, where a blend strays from the tables built at its own altitude by
#: less than two neighbouring 100 m steps' tables differ.  A climb built both tables at every 100 m step, most of a
#: climbing eye's world pass (docs/atmosphere.md, "The tables between altitude knots")
KNOTS_FROM_M = 1000.0
KNOT_STEP_M = 500.0


def altitude_knots(altitude_m: float) -> tuple[float, float, float]:
    """(the knot at or below `altitude_m`, the knot above it, the share of the one above in the blend): the
    altitudes whose tables make the tables seen from `altitude_m`; (it, it, 0) at a knot."""
    altitude_m = float(altitude_m)
    if altitude_m <= KNOTS_FROM_M:
        return altitude_m, altitude_m, 0.0
    below = KNOTS_FROM_M + KNOT_STEP_M * np.floor((altitude_m - KNOTS_FROM_M) / KNOT_STEP_M)
    share = (altitude_m - below) / KNOT_STEP_M
    return (float(below), float(below), 0.0) if share == 0.0 else (float(below), float(below) + KNOT_STEP_M, share)


def sky_seen_from(params: AtmosphereParameters, altitude_m: float, sun_direction, preview: bool = False) -> SkyView:
    """The sky of `params` from `altitude_m` with the sun toward unit `sun_direction` (y up), its table coarser
    for a `preview`; the last few are kept in memory, since a scene asks for its sky again whenever its light
    is remade."""
    return _sky_view(params, float(altitude_m), tuple(float(c) for c in sun_direction), preview)


@functools.lru_cache(maxsize=16)
def _sky_view(params: AtmosphereParameters, altitude_m: float, sun_direction: tuple, preview: bool) -> SkyView:
    return SkyView(atmosphere_tables(params), altitude_m, np.asarray(sun_direction, dtype=np.float64), preview)


def sky_irradiance(tables: AtmosphereTables, altitude_m: float, sun_direction, rings: int = 16, sectors: int = 16):
    """(3,): the irradiance the sky gives a horizontal surface facing up at `altitude_m`, the sun's direct beam
    left out: the in-scattered radiance of rays over the upper hemisphere (the midpoints of `rings` in the cosine
    and `sectors` of the azimuth on one side of the sun's vertical plane, the sky being symmetric about it),
    weighted by the cosine.  Marched directly, not read from a sky-view table: the lights need these 256 rays,
    not the table's 20,736."""
    params = tables.params
    r = sky_view.eye_radius(params, altitude_m)
    mu = ((np.arange(rings) + 0.5) / rings)[:, None]
    azimuth = (np.pi * (np.arange(sectors) + 0.5) / sectors)[None, :]
    sun = np.asarray(sun_direction, dtype=np.float64)
    mu_s = float(np.clip(sun[1], -1.0, 1.0))
    nu = mu * mu_s + np.sqrt(1.0 - mu * mu) * np.sqrt(1.0 - mu_s * mu_s) * np.cos(azimuth)
    distance = distance_to_top(r, mu, params.top_radius_m)
    radiance, _ = in_scattering(
        params, tables.transmittance, tables.multiple_scattering, r, mu, mu_s, nu, distance, sky_view.SKY_VIEW_SAMPLES
    )
    return np.einsum("rsc,rs->c", radiance, np.broadcast_to(mu, nu.shape)) * (1.0 / rings) * (2.0 * np.pi / sectors)


def sun_transmittance(tables: AtmosphereTables, altitude_m: float, sun_direction) -> np.ndarray:
    """(3,): the share of the sun's irradiance that reaches `altitude_m`: the air's transmittance toward it
    times the share of its disc above the horizon (so it sets smoothly, and is 0 once it has set)."""
    params = tables.params
    r = sky_view.eye_radius(params, altitude_m)
    sun_cosine = float(np.clip(np.asarray(sun_direction, dtype=np.float64)[1], -1.0, 1.0))
    through_air = transmittance.transmittance_to_top(params, tables.transmittance, r, sun_cosine)
    return through_air * visible_fraction(sun_cosine, horizon_cosine(r, params.bottom_radius_m))
