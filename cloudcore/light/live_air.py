"""The air's volume for a moving eye without waiting for it: an interactive frame never stalls on a build.

An eye that climbs or sinks past `ALTITUDE_STEP_M` asks for an aerial-perspective volume not built yet (a tenth
of a second, docs/atmosphere.md#aerial-perspective): a flight that changes altitude would hitch at every step.
`LiveAir` answers at once with the coarse volume for that altitude (the one a dragged slider draws, built in a
few milliseconds) while one worker thread builds the exact one, which the frames after it is done draw.  A
thread, not a process as the light pass's worker (`cloudcore.light.relighting`): the build is a few dozen large
numpy operations, which let go of the interpreter lock, over tables this process holds already.  A request
made while another builds waits until it is done, then the newest is built: a climbing eye is followed at the
worker's pace, never queued behind.  The command line, tests and recordings wait for the exact volume
(`air_between`), so their pictures do not depend on timing.
"""

from __future__ import annotations

from collections import OrderedDict
from concurrent.futures import Future, ThreadPoolExecutor

from cloudcore.atmosphere.aerial_perspective import aerial_perspective_from, volume_altitude
from cloudcore.light.air_between import AirBetween, air_between, eye_altitude_m
from cloudcore.light.sky_background import SkyBackground

#: the exact volumes kept, most recently drawn last
KEPT_VOLUMES = 8


class LiveAir:
    """`air_between` for an interactive renderer: the exact volume once built, the coarse one until then."""

    def __init__(self):
        self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="aerial-perspective")
        self._building: tuple[tuple, Future] | None = None
        self._ready: OrderedDict[tuple, AirBetween] = OrderedDict()
        self._built = 0

    def __call__(self, sky: SkyBackground, eye_position) -> AirBetween | None:
        """The air an eye at `eye_position` sees through under `sky` (as `air_between`), now."""
        if not sky.physical or sky.view.preview:
            return air_between(sky, eye_position)
        view = sky.view
        altitude = volume_altitude(eye_altitude_m(sky, eye_position))
        key = (view.tables, altitude, tuple(float(c) for c in view.sun_direction))
        self._collect()
        if key in self._ready:
            self._ready.move_to_end(key)
            return self._ready[key]
        if self._building is None:
            self._building = (
                key,
                self._pool.submit(aerial_perspective_from, view.tables, altitude, view.sun_direction),
            )
        return air_between(sky, eye_position, coarse=True)

    @property
    def built(self) -> int:
        """How many exact volumes the worker has finished: a picture drawn with a coarse one is drawn again when
        this changes."""
        self._collect()
        return self._built

    def _collect(self) -> None:
        """Keep the volume the worker finished, if it has."""
        if self._building is None or not self._building[1].done():
            return
        key, future = self._building
        self._building = None
        self._ready[key] = AirBetween(future.result())
        self._built += 1
        while len(self._ready) > KEPT_VOLUMES:
            self._ready.popitem(last=False)

    def close(self) -> None:
        self._pool.shutdown(wait=True, cancel_futures=True)
