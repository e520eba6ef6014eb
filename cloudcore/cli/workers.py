"""`--workers N`: a long job's independent pieces spread over N local processes, the results in the pieces' order.

A job is a worker class, the arguments to make one, and the pieces.  A worker is made once per process, on the
process's first piece (its own scene read from the file, its own headless GL context), and is called with each
piece handed to it; without --workers one worker is made in this process and called with every piece in turn, so
both ways run the same code.  Each process is a pool of one (`ProcessPoolExecutor(1)`) that holds one piece at a
time: a pool whose process dies names the piece that was in it, which runs again in a fresh process, at most
`RETRIES` more times, each rerun said on stderr; one more death fails the job (a SceneError: one line, exit 2).

Processes are started with `spawn`, never forked: a fork of a process holding a GL context shares the driver's
state with it.  Workers ignore Ctrl-C (the terminal sends it to the whole process group): this process decides
what stops, and kills the workers still holding a piece when it stops early.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import sys
from collections import deque
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from contextlib import ExitStack
from dataclasses import dataclass, field
from typing import Any

from cloudcore.errors import SceneError

#: times a piece whose worker died is run again before the job fails
RETRIES = 2
#: pieces per worker that may be finished ahead of the one the output waits for (their results wait in memory)
RUN_AHEAD = 2
#: tests only: "INDEX" kills the worker running piece INDEX on its first attempt, "INDEX:K" on its first K
KILL_PIECE_ENV = "CLOUDVIEW_TEST_KILL_PIECE"


def worker_count(text: str) -> int:
    """--workers: a number of processes, >= 1; argparse names this function in its refusal."""
    value = int(text)
    if value < 1:
        raise ValueError(text)
    return value


def add_workers_argument(parser, piece: str) -> None:
    parser.add_argument(
        "--workers",
        type=worker_count,
        metavar="N",
        help=f"spread the {piece} over N worker processes (docs/workers.md); the output is the same for any N",
    )


@dataclass(frozen=True)
class Job:
    """`make_worker(*arguments)` is called with a piece (and is a context manager, to run in this process); both
    must pickle (a module's class, plain arguments: a scene goes as its file, which each worker reads)."""

    name: str  # the command, for the progress bar and the messages
    make_worker: Callable[..., Any]
    arguments: tuple
    pieces: Sequence
    unit: str  # what the progress bar counts
    label: Callable[[int], str]  # piece i in a message: "frames 8-15"
    size: Callable[[Any], int] = lambda piece: 1  # how many `unit`s a piece holds
    bar: dict = field(default_factory=dict)  # tqdm's options for the job's one progress bar


def run_job(job: Job, workers: int | None) -> Iterator:
    """The results of the job's pieces, in the pieces' order: made in this process when `workers` is None, on
    `workers` processes otherwise."""
    from tqdm import tqdm

    with tqdm(total=sum(map(job.size, job.pieces)), desc=job.name, unit=job.unit, **job.bar) as bar:
        if workers is None:
            with job.make_worker(*job.arguments) as worker:
                for piece in job.pieces:
                    result = worker(piece)
                    bar.update(job.size(piece))
                    yield result
        else:
            yield from _on_processes(job, workers, bar)


# ---------------------------------------------------------------- in a worker process

#: this process's worker, made on its first piece
_worker = None


def _start_worker() -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    os.environ.setdefault("PYOPENGL_PLATFORM", "egl")  # headless: before OpenGL is first imported


def _run_piece(make_worker, arguments: tuple, index: int, piece, attempt: int):
    global _worker
    _die_if_asked(index, attempt)
    if _worker is None:
        # never closed: it goes with the process (closing a FrameRenderer stores its cost fit for the next run,
        # which N workers would write over one another)
        _worker = make_worker(*arguments)
    return _worker(piece)


def _die_if_asked(index: int, attempt: int) -> None:
    """The tests' stand-in for a worker killed mid-job (`KILL_PIECE_ENV`)."""
    wanted, _, attempts = os.environ.get(KILL_PIECE_ENV, "").partition(":")
    if wanted == str(index) and attempt <= int(attempts or 1):
        os._exit(70)


# ---------------------------------------------------------------- in this process


class _Process:
    """One worker process: a pool of one, which holds at most one piece."""

    def __init__(self, context):
        self.pool = ProcessPoolExecutor(1, mp_context=context, initializer=_start_worker)
        self.pid = self.pool.submit(os.getpid)  # to kill it by, should the job stop while it holds a piece
        self.busy: Future | None = None

    def stop(self) -> None:
        if self.busy is not None and not self.busy.done() and self.pid.done():
            os.kill(self.pid.result(), signal.SIGKILL)
        self.pool.shutdown(wait=True, cancel_futures=True)


def _on_processes(job: Job, workers: int, bar) -> Iterator:
    context = multiprocessing.get_context("spawn")
    waiting = deque(range(len(job.pieces)))
    attempts = [0] * len(job.pieces)
    finished: dict[int, Any] = {}
    running: dict[Future, tuple[_Process, int]] = {}
    next_out = 0  # the piece the output waits for
    with ExitStack() as processes:
        idle = []
        for _ in range(min(workers, len(job.pieces))):
            idle.append(_Process(context))
            processes.callback(idle[-1].stop)
        while next_out < len(job.pieces):
            while idle and waiting and waiting[0] < next_out + RUN_AHEAD * workers:
                process, index = idle.pop(), waiting.popleft()
                attempts[index] += 1
                process.busy = process.pool.submit(
                    _run_piece, job.make_worker, job.arguments, index, job.pieces[index], attempts[index]
                )
                running[process.busy] = process, index
            done, _ = wait(running, return_when=FIRST_COMPLETED)
            for future in done:
                process, index = running.pop(future)
                process.busy = None
                try:
                    finished[index] = future.result()
                except BrokenProcessPool:
                    _check_attempts(job, index, attempts[index])
                    bar.write(
                        f"cloudview {job.name}: {job.label(index)}: its worker died; running it again "
                        f"(try {attempts[index] + 1} of {RETRIES + 1})",
                        file=sys.stderr,
                    )
                    waiting.appendleft(index)
                    process.stop()
                    process = _Process(context)
                    processes.callback(process.stop)
                else:
                    bar.update(job.size(job.pieces[index]))
                idle.append(process)
            while next_out in finished:
                yield finished.pop(next_out)
                next_out += 1


def _check_attempts(job: Job, index: int, attempts: int) -> None:
    if attempts > RETRIES:
        raise SceneError(
            f"cloudview {job.name}",
            job.label(index),
            f"its worker died on each of {attempts} tries: the job is given up",
        )
