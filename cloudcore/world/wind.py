"""The air's motion over the scene clock: clouds drift with the wind and churn inside (pure numpy, float64).

`[wind]` (`cloudcore.model.scene.Wind`) gives the wind by altitude band.  A cloud
drifts rigidly with the wind at the altitude of its centre, so it does not
shear apart; the bands are interpolated as velocity vectors (east, south),
not as angles, so a wind veering through north turns the short way and a
calm between two opposed bands is a calm.  Below the lowest band and above
the highest the nearest band holds.

The drift is the integral of the wind over the scene clock from 0, in closed
form: gusts scale every band's speed by g(t) = 1 + a sin(2 pi t / P), whose
integral G(t) = t + a P (1 - cos(2 pi t / P)) / (2 pi) is continuous and
nondecreasing, so a cloud never jumps and never runs back (a <= 1).  At t = 0
nothing has moved: a scene's picture at time 0 is the one without wind.

Turbulence moves each particle about its place in its cloud, never away from
it: the displacement of a particle at rest position p is

    D(p, t) = A sum_i w_i c_i cos(k_i . p + omega_i t + phi_i),   c_i . k_i = 0,   sum_i w_i = 1,

the curl of the smooth vector potential A sum_i w_i (c_i x k_i) / |k_i|^2 sin(...), so divergence-free (each
term a transverse wave), bounded |D| <= A, and smooth in p and t.  A cloud keeps its particles, and its extent
grows by at most A (`turbulence_m`); its particles move at most A max omega_i metres a second
(`shape_change_bound_m`).  The modes come from an integer hash (`cloudcore.maths.noise.hash01`): the same on every
platform.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from cloudcore.maths.noise import hash01
from cloudcore.model.scene import Wind

#: the transverse waves the turbulence sums
TURBULENCE_MODES = 6
#: a mode's wavelength and period are the wind's `turbulence_scale_m` and `turbulence_period_s` times a factor in
#: [1 - SPREAD, 1 + SPREAD]: the modes do not beat in step
SPREAD = 0.35
_SEED = 57


def velocity_at(wind: Wind, altitudes) -> np.ndarray:
    """(n, 3) m/s: the steady wind (no gust) at each of `altitudes` (m), in world axes (x east, y up, z south)."""
    bands = np.asarray(wind.bands, dtype=np.float64)
    bearing = np.radians(bands[:, 2])
    # the wind blows from its bearing: toward -(sin b, 0, -cos b) in (east, up, south)
    east, south = -bands[:, 1] * np.sin(bearing), bands[:, 1] * np.cos(bearing)
    altitudes = np.asarray(altitudes, dtype=np.float64).reshape(-1)
    velocity = np.zeros((len(altitudes), 3))
    velocity[:, 0] = np.interp(altitudes, bands[:, 0], east)
    velocity[:, 2] = np.interp(altitudes, bands[:, 0], south)
    return velocity


def gust_factor(wind: Wind, time_s: float) -> float:
    """g(t): what multiplies every band's speed at `time_s`."""
    return 1.0 + wind.gust_amplitude * math.sin(2.0 * math.pi * time_s / wind.gust_period_s)


def carried_seconds(wind: Wind, time_s: float) -> float:
    """G(t), the integral of g from 0 to `time_s`: the steady wind's velocity times it is the drift."""
    period = wind.gust_period_s
    return time_s + wind.gust_amplitude * period * (1.0 - math.cos(2.0 * math.pi * time_s / period)) / (2.0 * math.pi)


def drift(wind: Wind, altitudes, time_s: float) -> np.ndarray:
    """(n, 3) metres each point at `altitudes` has been carried from time 0 to `time_s`."""
    return velocity_at(wind, altitudes) * carried_seconds(wind, time_s)


@dataclass(frozen=True)
class _Modes:
    directions: np.ndarray  # (m, 3) unit wave directions
    amplitudes: np.ndarray  # (m, 3) unit displacement directions, each across its wave
    numbers: np.ndarray  # (m,) wavelength factors
    rates: np.ndarray  # (m,) period factors
    phases: np.ndarray  # (m,)


def _modes() -> _Modes:
    """The turbulence's transverse waves, from the hash: unit directions, displacements across them."""
    index = np.arange(TURBULENCE_MODES)
    draws = np.stack([hash01(index, np.full(TURBULENCE_MODES, purpose), _SEED) for purpose in range(7)])
    # a uniform direction on the sphere from two draws
    z, azimuth = 2.0 * draws[0] - 1.0, 2.0 * math.pi * draws[1]
    ring = np.sqrt(1.0 - z * z)
    directions = np.column_stack([ring * np.cos(azimuth), ring * np.sin(azimuth), z])
    # two axes across each direction; the displacement at an angle between them
    helper = np.where(np.abs(directions[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    first = np.cross(directions, helper)
    first /= np.linalg.norm(first, axis=1, keepdims=True)
    second = np.cross(directions, first)
    angle = 2.0 * math.pi * draws[2]
    amplitudes = np.cos(angle)[:, None] * first + np.sin(angle)[:, None] * second
    numbers = 1.0 + SPREAD * (2.0 * draws[3] - 1.0)
    rates = 1.0 + SPREAD * (2.0 * draws[4] - 1.0)
    return _Modes(directions, amplitudes, numbers, rates, 2.0 * math.pi * draws[5])


_MODES = _modes()


def turbulent_offsets(wind: Wind, rest: np.ndarray, time_s: float) -> np.ndarray:
    """(n, 3) metres: D(p, t) of the particles at `rest` (n, 3) positions in their clouds; zeros in calm air."""
    rest = np.asarray(rest, dtype=np.float64).reshape(-1, 3)
    if wind.turbulence_m == 0.0:
        return np.zeros_like(rest)
    m = _MODES
    wave_vectors = m.directions * (2.0 * math.pi * m.numbers / wind.turbulence_scale_m)[:, None]
    omegas = 2.0 * math.pi * m.rates / wind.turbulence_period_s
    phases = rest @ wave_vectors.T + omegas * time_s + m.phases  # (n, m)
    return (wind.turbulence_m / TURBULENCE_MODES) * (np.cos(phases) @ m.amplitudes)


def shape_change_bound_m(wind: Wind | None, elapsed_s: float) -> float:
    """The most any particle's place in its cloud can change over `elapsed_s` seconds: A max omega |dt|, and
    never more than 2 A."""
    if wind is None or wind.turbulence_m == 0.0:
        return 0.0
    fastest = 2.0 * math.pi * float(np.max(_MODES.rates)) / wind.turbulence_period_s
    return min(2.0 * wind.turbulence_m, wind.turbulence_m * fastest * abs(elapsed_s))


def reshapes(wind: Wind | None) -> bool:
    """Whether the wind changes clouds other than by one translation of all: turbulence inside them, or bands
    that carry clouds at different altitudes apart (the light of one on another then changes)."""
    return wind is not None and (wind.turbulence_m > 0.0 or len({row[1:] for row in wind.bands}) > 1)


def light_time(wind: Wind | None, time_s: float) -> float:
    """The scene time the clouds' light is made for at `time_s`: 0 while the wind only translates them (Harris's
    self-shading is in each cloud's own frame: a translation leaves it), else the start of the current
    `relight_period_s`."""
    if not reshapes(wind):
        return 0.0
    return math.floor(time_s / wind.relight_period_s) * wind.relight_period_s


@dataclass(frozen=True)
class CloudMotion:
    """What the wind has done to a frame's clouds, for the level of detail: each cloud's drift from time 0 (its
    impostor follows it, and the error counts the eye's place relative to it), and how far turbulence may have
    changed a cloud since an impostor made at another time."""

    drifts: np.ndarray  # (clouds, 3) metres
    time_s: float
    wind: Wind | None
    velocities: np.ndarray  # (clouds, 3) m/s now, gusts included: what predicts how long an impostor lasts

    def shape_change_m(self, made_at_s) -> np.ndarray:
        """(n,) metres: the most a particle's place in its cloud has changed since `made_at_s` (n,)."""
        made_at_s = np.asarray(made_at_s, dtype=np.float64)
        if self.wind is None or self.wind.turbulence_m == 0.0:
            return np.zeros_like(made_at_s)
        rate = shape_change_bound_m(self.wind, 1.0)
        return np.minimum(2.0 * self.wind.turbulence_m, rate * np.abs(self.time_s - made_at_s))


class AirMotion:
    """The wind applied to a scene's authored clouds, made once for the clouds and the wind (the renderer holds
    one): every particle's offset from its rest place at a time, and the clouds as their light is made for it.

    A cloud field's clouds are not among them: the field's grid drifts whole with the wind at its mid altitude
    (`field_drift`), each cell still made from its seed, so its clouds keep their light; their particles swirl by
    the same turbulence about their places in the grid (the renderer adds `turbulent_offsets`), unrelit.
    """

    def __init__(self, wind: Wind, clouds):
        self.wind, self.clouds = wind, tuple(clouds)
        self.counts = np.array([len(c.particles) for c in self.clouds], dtype=np.int64)
        self.rest = np.concatenate([c.centres for c in self.clouds]) if self.clouds else np.zeros((0, 3))
        altitudes = np.array([c.bounding_sphere()[0][1] for c in self.clouds], dtype=np.float64)
        self.velocities = velocity_at(wind, altitudes)  # (clouds, 3) m/s, steady
        self._lit: dict[float, tuple] = {}  # lit_at -> the clouds then, oldest first

    def drifts(self, time_s: float) -> np.ndarray:
        """(clouds, 3) metres each cloud has drifted by `time_s`."""
        return self.velocities * carried_seconds(self.wind, time_s)

    def speeds(self, time_s: float) -> np.ndarray:
        """(clouds, 3) m/s each cloud moves at `time_s`, gusts included."""
        return self.velocities * gust_factor(self.wind, time_s)

    def offsets(self, time_s: float) -> np.ndarray:
        """(particles, 3) metres each particle is from its rest place at `time_s`: its cloud's drift and turbulence."""
        return np.repeat(self.drifts(time_s), self.counts, axis=0) + turbulent_offsets(self.wind, self.rest, time_s)

    def lit_clouds(self, lit_at: float) -> tuple:
        """The clouds as the wind has made them at scene time `lit_at` (`light_time`'s, or an older one whose light
        is at hand), the shapes their light is made from: the very clouds at rest for 0.  The last two asked for
        are kept (the editor asks for the next period's while it draws the last one's)."""
        if lit_at == 0.0:
            return self.clouds
        if lit_at not in self._lit:
            moved = self.rest + self.offsets(lit_at)
            starts = np.concatenate([[0], np.cumsum(self.counts)])
            self._lit[lit_at] = tuple(
                dataclasses.replace(cloud, particles=np.column_stack([moved[start:stop], cloud.radii]))
                for cloud, start, stop in zip(self.clouds, starts[:-1], starts[1:])
            )
            while len(self._lit) > 2:
                del self._lit[next(iter(self._lit))]
        return self._lit[lit_at]

    def carry(self, time_s: float, lit_at: float) -> np.ndarray:
        """(particles, 3) metres from where `lit_clouds(lit_at)` has each particle to where it is at `time_s`."""
        return self.offsets(time_s) - (self.offsets(lit_at) if lit_at != 0.0 else 0.0)


def field_drift(wind: Wind | None, field, time_s: float) -> np.ndarray:
    """(3,) metres a cloud field's grid has drifted by `time_s`: the wind at the middle of its altitudes carries it
    whole (zeros in still air, or without a field)."""
    if wind is None or field is None:
        return np.zeros(3)
    return drift(wind, [0.5 * (field.altitude[0] + field.altitude[1])], time_s)[0]


def field_speed(wind: Wind, field, time_s: float) -> np.ndarray:
    """(3,) m/s the cloud field's grid moves at `time_s`, gusts included (zeros without a field)."""
    if field is None:
        return np.zeros(3)
    return velocity_at(wind, [0.5 * (field.altitude[0] + field.altitude[1])])[0] * gust_factor(wind, time_s)
