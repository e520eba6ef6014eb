"""`--workers N` and `--cluster ADDRESS`: a long job's independent pieces spread over N local processes or Ray
tasks, the results in the pieces' order (docs/workers.md).

A job is a worker class, the arguments to make one, and the pieces.  A worker is made once per process, on the
process's first piece (its own scene read from the file, its own headless GL context), and is called with each
piece handed to it; without --workers one worker is made in this process and called with every piece in turn, so
both ways run the same code.  Each process is a pool of one (`ProcessPoolExecutor(1)`) that holds one piece at a
time: a pool whose process dies names the piece that was in it, which runs again in a fresh process, at most
`RETRIES` more times, each rerun said on stderr; one more death fails the job (a SceneError: one line, exit 2).
On Ray (`_RayTasks`) the same loop hands the pieces out as tasks, Ray's own retries off so that it says so too.
Where the cluster has GPUs each task asks for one (or the share `--gpus-per-task` says), as many at a time as
they allow, and its worker draws on the GPU Ray gave it (`_use_the_task_s_gpu`).

Processes are started with `spawn`, never forked: a fork of a process holding a GL context shares the driver's
state with it.  Workers ignore Ctrl-C (the terminal sends it to the whole process group): this process decides
what stops, and kills the workers still holding a piece when it stops early.
"""

from __future__ import annotations

import argparse
import importlib.util
import multiprocessing
import os
import signal
import socket
import sys
import uuid
from collections import deque
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from typing import Any

from cloudcore.model.errors import SceneError

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


def cluster_address(text: str) -> str:
    """--cluster: a Ray address, refused here where Ray is not installed (argparse prints the reason)."""
    if importlib.util.find_spec("ray") is None:
        raise argparse.ArgumentTypeError("needs Ray, which is not installed: pip install 'cloudview[cluster]'")
    return text


def gpu_share(text: str) -> float:
    """--gpus-per-task: a share of a GPU in [0, 64]; argparse names this function in its refusal."""
    value = float(text)
    if not 0.0 <= value <= 64.0:
        raise ValueError(text)
    return value


def add_workers_arguments(parser, pieces: str) -> None:
    parser.add_argument(
        "--workers",
        type=worker_count,
        metavar="N",
        help=f"spread the {pieces} over N worker processes, or N tasks at a time with --cluster (docs/workers.md); "
        "the output is one process's wherever that is deterministic",
    )
    parser.add_argument(
        "--cluster",
        type=cluster_address,
        metavar="ADDRESS",
        help="run the pieces as tasks on the Ray cluster at ADDRESS ('auto': the one this machine is part of; "
        "'local': start one here), as many at a time as it has CPUs (or GPUs) unless --workers says",
    )
    parser.add_argument(
        "--gpus-per-task",
        type=gpu_share,
        metavar="F",
        help="with --cluster: the GPUs each task asks Ray for (0.25: four tasks share one); by default 1 where the "
        "cluster has GPUs, else 0",
    )


def spread(args) -> bool:
    """Whether the command's arguments spread its job (--workers or --cluster)."""
    return args.workers is not None or args.cluster is not None


@dataclass(frozen=True)
class Job:
    """`make_worker(*arguments)` is called with a piece (and is a context manager, to run in this process); both
    must pickle (a module's class, and arguments sent once to each worker: a scene goes as its file, which each
    worker reads)."""

    name: str  # the command, for the progress bar and the messages
    make_worker: Callable[..., Any]
    arguments: tuple
    pieces: Sequence
    unit: str  # what the progress bar counts
    label: Callable[[int], str]  # piece i in a message: "frames 8-15"
    size: Callable[[Any], int] = lambda piece: 1  # how many `unit`s a piece holds
    bar: dict = field(default_factory=dict)  # tqdm's options for the job's one progress bar


def run_job(job: Job, workers: int | None, cluster: str | None = None, gpus_per_task: float | None = None) -> Iterator:
    """The results of the job's pieces, in the pieces' order: made in this process when neither `workers` nor
    `cluster` is given, on `workers` processes, or as Ray tasks on `cluster` (each asking `gpus_per_task`)."""
    from tqdm import tqdm

    if gpus_per_task is not None and cluster is None:
        raise SceneError("--gpus-per-task", f"{gpus_per_task:g}", "asks Ray for GPUs: it needs --cluster")
    with tqdm(total=sum(map(job.size, job.pieces)), desc=job.name, unit=job.unit, **job.bar) as bar:
        if workers is None and cluster is None:
            with job.make_worker(*job.arguments) as worker:
                for piece in job.pieces:
                    result = worker(piece)
                    bar.update(job.size(piece))
                    yield result
        else:
            places = (
                _RayTasks(job, cluster, workers, gpus_per_task)
                if cluster
                else _LocalProcesses(job, min(workers, len(job.pieces)))
            )
            try:
                yield from _spread(job, places, bar)
            finally:
                places.close()


# ---------------------------------------------------------------- in a worker process

#: a local worker process's job, (token, worker class, its arguments), given once when the process starts
_job = None
#: this process's worker, (its job's token, the worker), made on its first piece
_worker = None


def _start_worker(job: tuple) -> None:
    global _job
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    os.environ.setdefault("PYOPENGL_PLATFORM", "egl")  # headless: before OpenGL is first imported
    _job = job


def _run_piece(index: int, piece, attempt: int, job: tuple | None = None):
    """Piece `index` of `job` (a Ray task's: a Ray worker process may serve several jobs in turn), or of the job
    this local process was started for."""
    global _worker
    token, make_worker, arguments = job or _job
    _die_if_asked(index, attempt)
    if _worker is None or _worker[0] != token:
        if job is not None:
            _use_the_task_s_gpu()
        # never closed: it goes with the process (closing a FrameRenderer stores its cost fit for the next run,
        # which N workers would write over one another)
        _worker = token, make_worker(*arguments)
    return _worker[1](piece)


def _use_the_task_s_gpu() -> None:
    """In a Ray task given a GPU, the headless context made next is made on it (pyrender's `EGL_DEVICE_ID`);
    without one, or where EGL cannot tell which device it is, on the default device."""
    import ray

    gpus = ray.get_gpu_ids()
    if gpus:
        from cloudcore.gl.context import egl_device_of_cuda

        device = egl_device_of_cuda(int(gpus[0]))
        if device is not None:
            os.environ["EGL_DEVICE_ID"] = str(device)


def _die_if_asked(index: int, attempt: int) -> None:
    """The tests' stand-in for a worker killed mid-job (`KILL_PIECE_ENV`)."""
    wanted, _, attempts = os.environ.get(KILL_PIECE_ENV, "").partition(":")
    if wanted == str(index) and attempt <= int(attempts or 1):
        os._exit(70)


# ---------------------------------------------------------------- in this process


class _WorkerDied(Exception):
    """The process running a piece ended before the piece did."""


def _spread(job: Job, places, bar) -> Iterator:
    """The pieces' results in order, each piece handed to `places` (`_LocalProcesses` or `_RayTasks`) as it
    has room, a piece whose worker died handed out again."""
    waiting = deque(range(len(job.pieces)))
    attempts = [0] * len(job.pieces)
    finished: dict[int, Any] = {}
    running: dict[Any, int] = {}  # a place's handle of a piece -> the piece
    next_out = 0  # the piece the output waits for
    while next_out < len(job.pieces):
        while places.has_room() and waiting and waiting[0] < next_out + RUN_AHEAD * places.capacity:
            index = waiting.popleft()
            attempts[index] += 1
            running[places.submit(index, job.pieces[index], attempts[index])] = index
        for handle in places.finished(list(running)):
            index = running.pop(handle)
            try:
                finished[index] = places.result(handle)
            except _WorkerDied:
                if attempts[index] > RETRIES:
                    raise SceneError(
                        f"cloudview {job.name}",
                        job.label(index),
                        f"its worker died on each of {attempts[index]} tries: the job is given up",
                    ) from None
                bar.write(
                    f"cloudview {job.name}: {job.label(index)}: its worker died; running it again "
                    f"(try {attempts[index] + 1} of {RETRIES + 1})",
                    file=sys.stderr,
                )
                waiting.appendleft(index)
            else:
                bar.update(job.size(job.pieces[index]))
        while next_out in finished:
            yield finished.pop(next_out)
            next_out += 1


class _Process:
    """One worker process: a pool of one, which holds at most one piece."""

    def __init__(self, context, job: tuple):
        self.pool = ProcessPoolExecutor(1, mp_context=context, initializer=_start_worker, initargs=(job,))
        self.pid = self.pool.submit(os.getpid)  # to kill it by, should the job stop while it holds a piece
        self.busy: Future | None = None

    def stop(self) -> None:
        if self.busy is not None and not self.busy.done() and self.pid.done():
            os.kill(self.pid.result(), signal.SIGKILL)
        self.pool.shutdown(wait=True, cancel_futures=True)


class _LocalProcesses:
    """`capacity` spawned processes, a piece at a time each: the process a piece died in is known, and replaced."""

    def __init__(self, job: Job, capacity: int):
        self.capacity = capacity
        self._context = multiprocessing.get_context("spawn")
        self._job = (None, job.make_worker, job.arguments)  # sent once to each process as it starts
        self._idle = [_Process(self._context, self._job) for _ in range(capacity)]
        self._holding: dict[Future, _Process] = {}

    def has_room(self) -> bool:
        return bool(self._idle)

    def submit(self, index: int, piece, attempt: int) -> Future:
        process = self._idle.pop()
        process.busy = process.pool.submit(_run_piece, index, piece, attempt)
        self._holding[process.busy] = process
        return process.busy

    def finished(self, futures: list[Future]) -> set[Future]:
        return wait(futures, return_when=FIRST_COMPLETED).done

    def result(self, future: Future):
        process = self._holding.pop(future)
        process.busy = None
        try:
            return future.result()
        except BrokenProcessPool:
            process.stop()
            process = _Process(self._context, self._job)  # in the dead one's place
            raise _WorkerDied from None
        finally:
            self._idle.append(process)

    def close(self) -> None:
        for process in self._idle + list(self._holding.values()):
            process.stop()


#: seconds to wait for a cluster's head to answer before the job is refused (Ray's own wait is minutes)
CONNECT_TIMEOUT_S = 5.0


def _check_reachable(address: str) -> None:
    """A cluster named by HOST:PORT (or ray://HOST:PORT) answers on that port, else a SceneError at once."""
    host, separator, port = address.removeprefix("ray://").rpartition(":")
    if not (separator and host and port.isdigit()):
        return  # "auto", "local": Ray finds or starts the cluster itself
    try:
        socket.create_connection((host, int(port)), timeout=CONNECT_TIMEOUT_S).close()
    except OSError as error:
        raise SceneError("--cluster", address, f"cannot be reached: {error.strerror or error}") from None


def task_gpus(resources: dict, asked: float | None, address: str) -> tuple[float, int]:
    """(the GPUs a task asks for, the tasks the cluster holds at a time) on a cluster of `resources` (Ray's
    `cluster_resources`): `asked`, or by default one GPU where it has any; a job asking GPUs of a cluster with too
    few is refused in one line, since Ray would wait for them forever."""
    gpus, cpus = float(resources.get("GPU", 0.0)), float(resources.get("CPU", 1.0))
    share = asked if asked is not None else (1.0 if gpus >= 1.0 else 0.0)
    if share > gpus:
        raise SceneError("--gpus-per-task", f"{share:g}", f"the cluster at {address} has {gpus:g} GPUs")
    return share, max(1, int(gpus // share if share > 0.0 else cpus))


class _RayTasks:
    """Pieces as Ray tasks on the cluster at `address`, at most `capacity` at a time (None: its CPUs).  Ray's own
    retries are off: a task whose worker died comes back to `_spread`, which says so and hands it out again."""

    def __init__(self, job: Job, address: str, capacity: int | None, gpus_per_task: float | None = None):
        _check_reachable(address)
        import ray

        self._ray = ray
        try:
            ray.init(
                address=address,
                runtime_env={"env_vars": {"PYOPENGL_PLATFORM": "egl"}},  # headless GL in every worker
                log_to_driver=False,
                logging_level="error",
            )
        except (ConnectionError, RuntimeError, ValueError) as error:
            raise SceneError("--cluster", address, str(error).strip().splitlines()[0]) from None
        try:
            share, room = task_gpus(ray.cluster_resources(), gpus_per_task, address)
        except SceneError:
            ray.shutdown()
            raise
        self.capacity = capacity or room
        self._run = ray.remote(max_retries=0, num_gpus=share)(_run_piece)
        # put in Ray's object store once, fetched once a node, whatever the pieces; the token tells the jobs apart
        self._job = ray.put((uuid.uuid4().hex, job.make_worker, job.arguments))
        self._pending = set()

    def has_room(self) -> bool:
        return len(self._pending) < self.capacity

    def submit(self, index: int, piece, attempt: int):
        task = self._run.remote(index, piece, attempt, self._job)
        self._pending.add(task)
        return task

    def finished(self, tasks: list) -> list:
        return self._ray.wait(tasks, num_returns=1)[0]

    def result(self, task):
        self._pending.discard(task)
        try:
            return self._ray.get(task)
        except self._ray.exceptions.WorkerCrashedError:
            raise _WorkerDied from None
        except self._ray.exceptions.RayTaskError as error:
            raise error.cause from None  # the piece's own exception, a SceneError one line as here

    def close(self) -> None:
        for task in self._pending:
            self._ray.cancel(task, force=True)
        self._ray.shutdown()
