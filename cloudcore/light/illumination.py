"""Precomputed illumination of a scene's clouds: incident light per particle and light direction.

Harris shades each cloud on its own once per light; this module maps a scene's clouds, shading defaults and
lights onto `cloudcore.light.shading.incident_light`.  The sun (the first light) then reaches each cloud through
the others too, where asked (`between_clouds`): the clouds' light-space map less each cloud's own part
(`cloudcore.light.cloud_shadows`), or for a cloud field's cells, pair by pair (`cloudcore.light.cell_shadows`).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from cloudcore.field.shadow_cells import CellShadowing
from cloudcore.light.cell_shadows import SunThroughCells, sun_through_other_cells
from cloudcore.light.cloud_shadows import beam_opacity, between_clouds_transmittance
from cloudcore.light.lighting import active_lights
from cloudcore.light.shading import ALL_LIGHT, DEFAULT_RASTER_RESOLUTION, RETURNED_LIGHT, light_parts
from cloudcore.model.scene import Cloud, Shading


def cloud_optics(cloud: Cloud, shading: Shading) -> tuple[np.ndarray, np.ndarray]:
    """Per-particle optical depth and albedo: the cloud's override or the scene default."""
    n = len(cloud.particles)
    tau = shading.optical_depth if cloud.optical_depth is None else cloud.optical_depth
    albedo = shading.albedo if cloud.albedo is None else cloud.albedo
    return np.full(n, tau), np.full(n, albedo)


def illuminate_clouds(
    clouds,
    shading: Shading,
    lights,
    method: str = "exact",
    *,
    resolution: int = DEFAULT_RASTER_RESOLUTION,
    between_clouds: bool | CellShadowing = False,
) -> list[np.ndarray]:
    """Incident light (N_i, L) of each cloud for each light that contributes (`active_lights`), all of it
    (`ALL_LIGHT`); with `between_clouds`, the sun's (the first light's) through the other clouds too
    (`sun_through_others`; a `CellShadowing`: a cloud field's cells through one another, `sun_through_other_cells`)."""
    clouds = list(clouds)
    columns = [
        illuminate_direction(clouds, shading, light.direction, method, resolution=resolution)
        for light in active_lights(lights)
    ]
    incident = [
        np.column_stack([column[i][:, ALL_LIGHT] for column in columns])
        if columns
        else np.zeros((len(cloud.particles), 0))
        for i, cloud in enumerate(clouds)
    ]
    sun = shadowing_sun(lights) if between_clouds is not False else None
    if sun is None:
        return incident
    if isinstance(between_clouds, CellShadowing):
        centres, radii, opacity, starts = beam_of(clouds, shading)
        through = sun_through_other_cells(centres, radii, opacity, starts, between_clouds, sun)
        return _dimmed(incident, np.split(through, starts[1:-1]))
    return _dimmed(incident, sun_through_others(clouds, shading, sun))


def shadowing_sun(lights) -> tuple[float, ...] | None:
    """The direction of the light the clouds shadow (the sun, or the first of a scene's lights), None where it
    gives no light: it is then not among the incident light's columns."""
    lights = tuple(lights)
    return light_directions(lights[:1])[0] if lights and active_lights(lights[:1]) else None


def sun_through_others(clouds, shading: Shading, sun_direction) -> list[np.ndarray]:
    """Per cloud (N_i,): the share of the sun's beam from `sun_direction` the other clouds let reach each
    particle (`cloudcore.light.cloud_shadows.between_clouds_transmittance`)."""
    clouds = list(clouds)
    centres, radii, opacity, starts = beam_of(clouds, shading)
    if len(radii) == 0:
        return [np.ones(0) for _ in clouds]
    return np.split(between_clouds_transmittance(centres, radii, opacity, starts, sun_direction), starts[1:-1])


def beam_of(clouds, shading: Shading) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(centres (n, 3), radii (n,), beam opacity (n,), where each cloud's particles start (clouds + 1,)): the
    clouds' particles concatenated as they take the sun's beam out (`beam_opacity`)."""
    clouds = list(clouds)
    starts = np.concatenate([[0], np.cumsum([len(c.particles) for c in clouds])]).astype(np.int64)
    if not clouds:
        return np.zeros((0, 3)), np.zeros(0), np.zeros(0), starts
    optics = [cloud_optics(c, shading) for c in clouds]
    opacity = beam_opacity(
        np.concatenate([o[0] for o in optics]), np.concatenate([o[1] for o in optics]), shading.phase, shading.g
    )
    return np.concatenate([c.centres for c in clouds]), np.concatenate([c.radii for c in clouds]), opacity, starts


def _dimmed(incident: list[np.ndarray], through: list[np.ndarray]) -> list[np.ndarray]:
    """`incident` with its first column (the sun's) times `through`."""
    return [np.column_stack([light[:, 0] * share, light[:, 1:]]) for light, share in zip(incident, through)]


def illuminate_direction(
    clouds, shading: Shading, direction, method: str = "exact", *, resolution: int = DEFAULT_RASTER_RESOLUTION
) -> list[np.ndarray]:
    """The fraction (N_i, 2) of light from `direction` that reaches each particle of each cloud: all of it and the
    part a lit face sends back (`cloudcore.light.shading.light_parts`).

    All clouds go through one `incident_light` call, each its own shadowing group,
    which lets the raster method share its slab walk.  What fraction arrives does
    not depend on the light's colour or intensity, only on where it comes from.
    """
    clouds = list(clouds)
    counts = [len(c.particles) for c in clouds]
    if sum(counts) == 0:
        return [np.zeros((n, 2)) for n in counts]
    optics = [cloud_optics(c, shading) for c in clouds]
    method = light_pass_method(shading, method)
    incident = light_parts(
        np.concatenate([c.centres for c in clouds]),
        np.concatenate([c.radii for c in clouds]),
        np.concatenate([o[0] for o in optics]),
        np.concatenate([o[1] for o in optics]),
        direction,
        phase=shading.phase,
        g=shading.g,
        method=method,
        groups=np.repeat(np.arange(len(clouds)), counts),
        resolution=resolution,
    )
    return np.split(incident, np.cumsum(counts)[:-1])


def light_pass_method(shading: Shading, method: str) -> str:
    """The incident-light method that runs when `method` is asked under `shading`: Yusov's occlusion
    estimate or Harris's pass with multiple-scattering octaves (with or without the light a lit face sends back)
    in place of Harris's exact and raster passes where `shading.light_pass` says so; the editor's preview
    (Harris's, fast while a slider moves) and an explicit method stay as asked."""
    if shading.light_pass in ("occlusion", "octaves", "octaves-lit-face") and method in ("exact", "raster"):
        return shading.light_pass
    return method


def light_directions(lights) -> tuple[tuple[float, ...], ...]:
    """The directions of the lights that contribute, in `active_lights` order: what illumination depends on."""
    return tuple(tuple(float(v) for v in light.direction) for light in active_lights(lights))


class IlluminationCache:
    """Incident light per cloud and light direction, recomputing only what it has not seen.

    The editor changes one cloud at a time; recomputing the other 33 clouds of
    the default scene would freeze it for seconds.  Clouds are immutable, so a
    cloud object seen before (by identity) has the same particles.  A light's
    colour and intensity scale what reaches a particle but not the fraction that
    does, so the entries are per light direction: a new time of day moves the sun
    and recolours the skylight, and only the sun is shaded again.  `incident`
    keeps only what it was last asked for; `store` adds work done elsewhere
    (`cloudcore.light.relighting`) beside it.  The sun through the other clouds depends on every cloud: it is
    held for the last set of clouds, shading and sun asked for, and made again when any of them changes.
    """

    def __init__(self):
        #: (id of the cloud, shading, method) -> (the cloud, {light direction: incident (N, 2): `light_parts`})
        self._entries: dict[tuple, tuple[Cloud, dict[tuple, np.ndarray]]] = {}
        self.last_recomputed = 0  # (cloud, light direction) pairs shaded by the last call
        #: ((the clouds, shading, sun direction, how they shadow one another), the sun through the others per
        #: cloud): the last asked
        self._between: tuple[tuple, list[np.ndarray]] | None = None
        self.between_made = 0  # how many times the sun through the others was made
        self._cells = SunThroughCells()  # a cloud field's cells through one another, per cloud

    def incident(
        self,
        clouds,
        shading: Shading,
        lights,
        method: str = "exact",
        *,
        between_clouds: bool | CellShadowing = False,
    ) -> list[np.ndarray]:
        """`illuminate_clouds(clouds, shading, lights, method, between_clouds=...)`, from what is held where it
        can be."""
        return self.light_parts(clouds, shading, lights, method, between_clouds=between_clouds)[0]

    def light_parts(
        self, clouds, shading: Shading, lights, method: str = "exact", *, between_clouds: bool | CellShadowing = False
    ) -> tuple[list[np.ndarray], list[np.ndarray]]:
        """(`incident`, and per cloud (N_i, L) the part of it a lit face sends back: `RETURNED_LIGHT`)."""
        clouds = list(clouds)
        work = self.missing(clouds, shading, lights, method)
        for direction, stale in work:
            self.store(stale, shading, method, direction, illuminate_direction(stale, shading, direction, method))
        directions = light_directions(lights)
        keys = self._keys(clouds, shading, method)
        kept = {key: (cloud, {d: self._entries[key][1][d] for d in directions}) for key, cloud in zip(keys, clouds)}
        self._entries = kept
        self.last_recomputed = sum(len(stale) for _, stale in work)
        parts = [
            [
                np.column_stack([kept[key][1][d][:, part] for d in directions])
                if directions
                else np.zeros((len(c.particles), 0))
                for key, c in zip(keys, clouds)
            ]
            for part in (ALL_LIGHT, RETURNED_LIGHT)
        ]
        sun = shadowing_sun(lights) if between_clouds is not False else None
        if sun is None:
            return parts[0], parts[1]
        through = self._sun_through_others(clouds, shading, sun, method, between_clouds)
        return _dimmed(parts[0], through), _dimmed(parts[1], through)

    def _sun_through_others(
        self, clouds, shading: Shading, sun, method: str, between_clouds: bool | CellShadowing
    ) -> list[np.ndarray]:
        """`sun_through_others`, or a cloud field's cells' (`SunThroughCells`, which makes again only the clouds a
        new set of cells reaches), kept while the clouds (by identity), their optics and the sun stay.  A dragged
        slider's look (the preview method) takes the one held for these clouds and optics whatever its sun: made on
        the thread that draws every look, it held a time-of-day drag's frames over a second (docs/atmosphere.md,
        "Cloud shadows": the clouds on one another); the look after the drag (the exact pass) makes it for its
        sun."""
        source = (clouds, dataclasses.replace(shading, eye_pass=Shading().eye_pass), sun, between_clouds)
        held = self._between
        # a field's shadowing can change with the same clouds (a clear cell came): held by its identity too
        same_shadowing = held is not None and held[0][3] is between_clouds
        if same_shadowing and _same_clouds(held[0][0], clouds) and held[0][1] == source[1]:
            if held[0][2] == sun or method == "preview":  # `cloudcore.light.shading`'s preview method
                return held[1]
        if isinstance(between_clouds, CellShadowing):
            centres, radii, opacity, starts = beam_of(clouds, shading)
            through = self._cells.through(clouds, centres, radii, opacity, starts, between_clouds, sun, source[1])
        else:
            through = sun_through_others(clouds, shading, sun)
        self._between = (source, through)
        self.between_made += 1
        return through

    def missing(self, clouds, shading: Shading, lights, method: str = "exact") -> list[tuple[tuple, list[Cloud]]]:
        """(light direction, the clouds not held for it) for each direction some cloud lacks."""
        work = []
        keys = self._keys(clouds, shading, method)
        for direction in light_directions(lights):
            stale = [
                c
                for c, key in zip(clouds, keys)
                if (hit := self._entries.get(key)) is None or hit[0] is not c or direction not in hit[1]
            ]
            if stale:
                work.append((direction, stale))
        return work

    def store(self, clouds, shading: Shading, method: str, direction, incident) -> None:
        """Hold `incident` (`illuminate_direction` of `clouds` from `direction`, computed elsewhere)."""
        direction = tuple(float(v) for v in direction)
        clouds = list(clouds)
        for cloud, key, light in zip(clouds, self._keys(clouds, shading, method), incident):
            hit = self._entries.get(key)
            held = hit[1] if hit is not None and hit[0] is cloud else {}
            self._entries[key] = (cloud, held | {direction: light})

    @staticmethod
    def _keys(clouds, shading: Shading, method: str) -> list[tuple]:
        """Each cloud's entry key (a scene field's hundreds of clouds share the one shading key, made once)."""
        # the light pass does not depend on what the eye pass makes of its result
        light_pass = dataclasses.replace(shading, eye_pass=Shading().eye_pass)
        return [(id(cloud), light_pass, method) for cloud in clouds]


def _same_clouds(these, those) -> bool:
    """Whether two lists hold the same cloud objects in the same order."""
    return len(these) == len(those) and all(a is b for a, b in zip(these, those))
