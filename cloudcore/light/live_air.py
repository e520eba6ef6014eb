"""The air's volume and the sky for a moving eye without waiting for them: an interactive frame never stalls on a
build.

An eye that climbs or sinks past `ALTITUDE_STEP_M` asks for an aerial-perspective volume and a sky-view table not
built yet (a tenth of a second each, docs/atmosphere.md#aerial-perspective): a flight that changes altitude would
hitch at every step.  `LiveAir` answers at once with the coarse volume for that altitude (the one a dragged slider
draws, built in a few milliseconds) and the sky of the nearest altitude it has, while one worker thread builds the
exact ones, which the frames after it is done draw.  A thread, not a process as the light pass's worker
(`cloudcore.light.relighting`): the build is a few dozen large numpy operations, which let go of the interpreter
lock, over tables this process holds already.  A request made while another builds waits until it is done, then
the newest is built: a climbing eye is followed at the worker's pace, never queued behind.  The command line,
tests and recordings wait for the exact volume and sky (`air_between`, `SkyBackground.seen_from`), so their
pictures do not depend on timing.
"""

from __future__ import annotations

import dataclasses
from collections import OrderedDict
from concurrent.futures import Future, ThreadPoolExecutor

from cloudcore.atmosphere.aerial_perspective import aerial_perspective_from, volume_altitude
from cloudcore.atmosphere.sky import SkyView, sky_seen_from
from cloudcore.light.air_between import AirBetween, air_between
from cloudcore.light.sky_background import SkyBackground, sky_view_altitude

#: the exact volumes and skies kept, most recently drawn last
KEPT_VOLUMES = 8


class LiveAir:
    """`air_between` and `SkyBackground.seen_from` for an interactive renderer: the exact volume and sky once built,
    the coarse volume and the nearest sky until then."""

    def __init__(self):
        self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="aerial-perspective")
        self._building: tuple[tuple, Future] | None = None
        self._ready: OrderedDict[tuple, tuple[AirBetween, SkyView]] = OrderedDict()
        self._built = 0

    def __call__(self, sky: SkyBackground, eye_position) -> AirBetween | None:
        """The air an eye at `eye_position` sees through under `sky` (as `air_between`), now."""
        if not sky.physical or sky.view.preview:
            return air_between(sky, eye_position)
        ready = self._built_for(sky, eye_position)
        return ready[0] if ready is not None else air_between(sky, eye_position, coarse=True)

    def sky_seen_from(self, sky: SkyBackground, eye_position) -> SkyBackground:
        """The sky an eye at `eye_position` sees under `sky` (as `SkyBackground.seen_from`), now: until the exact
        one for its altitude is built, the one built for the nearest altitude (a climb's last step: 55 dB from the
        next), or the scene's own where none is."""
        if not sky.physical or sky.view.preview:
            return sky.seen_from(eye_position)
        ready = self._built_for(sky, eye_position)
        if ready is not None:
            return dataclasses.replace(sky, view=ready[1])
        tables, altitude, sun = self._key(sky, eye_position)
        built = [(abs(key[1] - altitude), key) for key in self._ready if key[0] is tables and key[2] == sun]
        nearest = min(built, key=lambda distance_and_key: distance_and_key[0], default=None)
        return sky if nearest is None else dataclasses.replace(sky, view=self._ready[nearest[1]][1])

    @staticmethod
    def _key(sky: SkyBackground, eye_position) -> tuple:
        view = sky.view
        return (
            view.tables,
            volume_altitude(sky.eye_altitude_m(eye_position)),
            tuple(float(c) for c in view.sun_direction),
        )

    def _built_for(self, sky: SkyBackground, eye_position) -> tuple[AirBetween, SkyView] | None:
        """The exact volume and sky for the eye's altitude if built; else asks the worker for them (unless it is
        busy) and gives None."""
        key = self._key(sky, eye_position)
        self._collect()
        if key in self._ready:
            self._ready.move_to_end(key)
            return self._ready[key]
        if self._building is None:
            self._building = (key, self._pool.submit(_air_and_sky, *key))
        return None

    @property
    def built(self) -> int:
        """How many exact volumes (and skies) the worker has finished: a picture drawn with a coarse one is drawn
        again when this changes."""
        self._collect()
        return self._built

    def _collect(self) -> None:
        """Keep the volume the worker finished, if it has."""
        if self._building is None or not self._building[1].done():
            return
        key, future = self._building
        self._building = None
        volume, view = future.result()
        self._ready[key] = AirBetween(volume), view
        self._built += 1
        while len(self._ready) > KEPT_VOLUMES:
            self._ready.popitem(last=False)

    def close(self) -> None:
        self._pool.shutdown(wait=True, cancel_futures=True)


def _air_and_sky(tables, altitude_m: float, sun_direction: tuple):
    """The exact aerial-perspective volume and sky-view table for an eye at `altitude_m` (the worker's task)."""
    params = tables.params
    view = sky_seen_from(params, sky_view_altitude(params, altitude_m), sun_direction).built()
    return aerial_perspective_from(tables, altitude_m, sun_direction), view
