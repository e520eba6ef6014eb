"""Relighting without freezing the editor: the light pass in a worker process, the newest request winning.

Harris's light pass (`cloudcore.light.illumination`) takes over a second exactly for
the default scene's 90,000 particles.  Run where the GUI runs, every step of
the time-of-day or shading sliders would freeze the editor for that long.
`LiveIllumination` says each frame which lighting the viewport can show now:
the one asked for once its illumination is in the cache, else the newest one
that is, while a worker process computes the one asked for.  A request made
while another runs waits in a single slot that later requests overwrite, so
a dragged slider is followed at the worker's pace, never queued behind.

A process, not a thread: the light pass is numpy between Python loops (over
dependency levels or depth slabs) and would hold the interpreter lock the GUI
needs between them.  Small changes (an edit to a cloud or two) are shaded on
the spot, as before: the result is the next frame, and nothing stale shows.
"""

from __future__ import annotations

import dataclasses
import multiprocessing
import time
from concurrent.futures import Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass

from cloudcore.light.illumination import IlluminationCache, illuminate_direction
from cloudcore.light.lighting import scene_lights
from cloudcore.model.scene import Lighting, Scene, Shading
from cloudcore.model.settings import RenderSettings

#: the light pass while a slider is dragged (`cloudcore.light.shading`: a coarse raster), and once it is let go
PREVIEW_METHOD, EXACT_METHOD = "preview", "exact"
#: a change that leaves at most this many particles to shade is shaded in the frame that needs it: one cloud of
#: the default scene, shaded exactly in less than a frame of the editor on llvmpipe (docs/performance.md, "Live
#: time of day")
SYNCHRONOUS_PARTICLES = 6000


def dragged_look_settings(settings: RenderSettings) -> RenderSettings:
    """The settings a dragged slider's look (`PREVIEW_METHOD`) is drawn with: `settings` without the light shafts,
    whose march (the terrain's and the clouds' depths at its size) was the largest part of that frame after the
    shadows' map; the look on release draws them again (docs/performance.md, "The drag at 4 looks a second")."""
    return dataclasses.replace(settings, light_shafts=False) if settings.light_shafts else settings


@dataclass(frozen=True)
class Look:
    """The inputs of the clouds' colours apart from the clouds themselves: what the viewport shows."""

    shading: Shading
    lighting: Lighting
    method: str

    def lights(self):
        return scene_lights(self.lighting)[0]


class LiveIllumination:
    """Chooses the look to draw each frame and keeps the worker busy with the newest one asked for.

    `cache` is the renderer's (`FrameRenderer(illumination=...)`): finished work goes into it, so
    the frame that shows a look finds its illumination there and shades nothing.
    """

    def __init__(self, cache: IlluminationCache):
        self.cache = cache
        self._pool: ProcessPoolExecutor | None = None
        #: (future, the scene's clouds, their look, the clouds it shades: those the cache lacked)
        self._running: tuple[Future, tuple, Look, list] | None = None
        self._waiting: tuple[tuple, Look] | None = None
        self._shown: Look | None = None
        self.failure: str | None = None  # why the worker stopped, once it has; then everything is shaded here

    @property
    def busy(self) -> bool:
        """Whether a look is being computed or waits to be."""
        return self._running is not None or self._waiting is not None

    def pause(self, seconds: float) -> None:
        """Wait `seconds`, or less: until the look being computed is done.  A frame that shows the picture again
        while the worker runs leaves it the cores this long; the frame after shows the new look as soon as it is
        in, not a pause later."""
        if self._running is None:
            time.sleep(seconds)
        else:
            wait([self._running[0]], timeout=seconds)

    def look_for(self, scene: Scene, wanted: Look) -> Look:
        """The look to draw `scene` with this frame: `wanted` when it can be shown now, else the last shown."""
        self._collect()
        if self._shown is None or self.failure is not None or self._cheap(scene.clouds, wanted):
            self._waiting = None  # shaded on the spot: what waited is no longer wanted
            self._shown = wanted
            return wanted
        self._request(tuple(scene.clouds), wanted)
        if not self._cheap(scene.clouds, self._shown):
            self._shown = wanted  # nothing shown before fits these clouds (another scene): shade it here
        return self._shown

    def lit(self, clouds: tuple, look: Look) -> bool:
        """Whether `clouds`, shapes the wind will give the scene's clouds (`FrameRenderer.drawn_clouds`), can be
        drawn in `look` now: their light held, or few enough particles to shade in the frame.  Else the worker
        is asked for it when it is free (a look asked for meanwhile goes first: it is what the artist moves),
        and the frames draw the shapes lit before, carried on."""
        self._collect()
        if self.failure is not None or self._cheap(clouds, look):
            return True
        if not self.busy:
            self._submit(tuple(clouds), look)
        return False

    def _cheap(self, clouds, look: Look) -> bool:
        """Whether drawing `clouds` with `look` leaves few enough particles to shade in the frame."""
        work = self.cache.missing(clouds, look.shading, look.lights(), look.method)
        return sum(len(cloud.particles) for _, stale in work for cloud in stale) <= SYNCHRONOUS_PARTICLES

    def start(self) -> None:
        """Start the worker now (a second or so) rather than at the first relight."""
        if self._pool is None and self.failure is None:
            self._pool = ProcessPoolExecutor(max_workers=1, mp_context=multiprocessing.get_context("spawn"))
            self._pool.submit(illuminate_direction, (), Shading(), (0.0, 1.0, 0.0))  # the imports, now

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=False, cancel_futures=True)
            self._pool = None
        self._running = self._waiting = None

    def _request(self, clouds: tuple, look: Look) -> None:
        if self._running is not None and self._running[1] == clouds and self._running[2] == look:
            self._waiting = None
            return
        if self._running is None:
            self._submit(clouds, look)
        else:
            self._waiting = (clouds, look)

    def _submit(self, clouds: tuple, look: Look) -> None:
        work = self.cache.missing(clouds, look.shading, look.lights(), look.method)
        if not work:
            return
        self.start()
        try:
            future = self._pool.submit(_illuminate, work, look.shading, look.method)
        except (BrokenProcessPool, RuntimeError) as error:
            self._stop(error)
            return
        self._running = (future, clouds, look, work)

    def _collect(self) -> None:
        """Store a finished result, show its look, start what waits.  Clouds an edit has removed since are stored
        too: the renderer's next use of the cache keeps only the clouds it draws."""
        if self._running is None or not self._running[0].done():
            return
        future, _, look, work = self._running
        self._running = None
        try:
            results = future.result()
        except Exception as error:  # the worker died, or the light pass refused its input: shade here from now
            self._stop(error)
            return
        for (direction, clouds), incident in zip(work, results):
            self.cache.store(clouds, look.shading, look.method, direction, incident)
        self._shown = look
        if self._waiting is not None:
            waiting, self._waiting = self._waiting, None
            self._submit(*waiting)

    def _stop(self, error: BaseException) -> None:
        self.failure = f"the relighting worker stopped ({error or type(error).__name__}); shading in the editor"
        self.close()


def _illuminate(work, shading: Shading, method: str) -> list[list]:
    """In the worker: `illuminate_direction` for each (direction, clouds) of `IlluminationCache.missing`."""
    return [illuminate_direction(clouds, shading, direction, method) for direction, clouds in work]
