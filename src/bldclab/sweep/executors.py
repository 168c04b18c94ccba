"""Where the cases run: serially, on local processes or on a Dask cluster; what each worker does with a case.

Every executor receives resolved cases (plain data) and runs :func:`run_case` on them, so all give the same bits.
"""

from __future__ import annotations

import concurrent.futures
import importlib
import json
import multiprocessing
import os
import signal
import threading
import time
import tomllib
from abc import ABC, abstractmethod
from collections.abc import Collection, Iterable, Mapping, Sequence
from dataclasses import dataclass
from functools import lru_cache
from typing import Any, Literal, NamedTuple

from .._version import __version__
from ..analysis.experiments import EXPERIMENTS
from ..control import Control
from ..errors import BldclabError
from ..model.motor import Drive
from .keys import _canonical
from .registry import _build

__all__ = [
    "Dask",
    "Executor",
    "Processes",
    "Serial",
    "run_case",
]


@lru_cache(maxsize=32)
def _drive_of(text: str) -> Drive:
    return Drive.from_dict(tomllib.loads(text))


@lru_cache(maxsize=64)
def _control_of(spec: str) -> Control:
    data = json.loads(spec)
    module, _, qualname = data["class"].partition(":")
    obj: Any = importlib.import_module(module)
    for part in qualname.split("."):
        obj = getattr(obj, part)
    return _build(obj, data["params"], "control")


def run_case(inputs: Mapping[str, Any]) -> dict[str, float | int]:
    """Run one case from its canonical inputs (:attr:`ResolvedCase.inputs`) and return its result row.

    This is what every executor calls, in a worker or in this process.

    Raises
    ------
    RuntimeError
        If the inputs were resolved by another bldclab version (a cluster with mixed installations).
    """
    if inputs.get("bldclab") != __version__:
        raise RuntimeError(f"case resolved by bldclab {inputs.get('bldclab')}, this worker runs {__version__}")
    drive = _drive_of(inputs["drive"])
    control = _control_of(_canonical(inputs["control"]))
    settings = dict(inputs["experiment"])
    experiment = EXPERIMENTS[settings.pop("kind")](**settings)
    return experiment.run(drive, control)


class _Outcome(NamedTuple):
    index: int  # type: ignore[assignment]  # the case number; a NamedTuple field may shadow tuple.index
    key: str
    row: dict[str, float | int] | None
    error: str | None
    elapsed: float


def _run_chunk(chunk: Sequence[tuple[int, str, dict[str, Any]]]) -> list[_Outcome]:
    """Run cases ``(index, key, inputs)``; an exception becomes the case's error (the others still run)."""
    out = []
    for index, key, inputs in chunk:
        t0 = time.perf_counter()
        try:
            row, error = run_case(inputs), None
        except Exception as exc:
            row, error = None, f"{type(exc).__name__}: {exc}"
        out.append(_Outcome(index, key, row, error, time.perf_counter() - t0))
    return out


def _worker_init(parent: int) -> None:
    """Worker process setup: Ctrl-C is the parent's business; exit when orphaned (parent killed with -9).

    Parameters
    ----------
    parent : int
        Process id of the sweep's process, taken there: a worker still starting when its parent is killed would
        otherwise read its new parent (init) as the one to watch, and never exit.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if os.getppid() != parent:
        os._exit(1)

    def watch() -> None:
        while True:
            time.sleep(0.5)
            if os.getppid() != parent:
                os._exit(1)

    threading.Thread(target=watch, name="bldclab-orphan-watch", daemon=True).start()


class _ChunkLostError(Exception):
    """A chunk's cases could not be run (worker lost); they are recorded as failed and retried on a rerun."""


class _Backend(ABC):
    """An open executor: submit chunks, wait for some, fetch their outcomes."""

    slots = 1

    @abstractmethod
    def submit(self, chunk: list[tuple[int, str, dict[str, Any]]]) -> Any:
        """Start a chunk of cases; return a handle."""

    @abstractmethod
    def wait(self, handles: Collection[Any]) -> Iterable[Any]:
        """Block until some of the handles are done; return those."""

    @abstractmethod
    def result(self, handle: Any) -> list[_Outcome]:
        """Return the outcomes of a finished chunk."""

    def close(self, abort: bool) -> None:  # noqa: B027 - a backend without workers has nothing to release
        """Release the workers; ``abort``: stop running work as soon as possible."""


class Executor(ABC):
    """Where the cases run: :class:`Serial`, :class:`Processes` or :class:`Dask`."""

    @abstractmethod
    def _open(self) -> _Backend:
        """Start the workers and return the open backend."""

    def describe(self) -> str:
        """Return a short description for messages."""
        return type(self).__name__.lower()


class _Done:
    """A chunk already run (the serial executor's handle)."""

    def __init__(self, outcomes: list[_Outcome]) -> None:
        self.outcomes = outcomes


class _SerialBackend(_Backend):
    def submit(self, chunk: list[tuple[int, str, dict[str, Any]]]) -> Any:
        return _Done(_run_chunk(chunk))

    def wait(self, handles: Collection[Any]) -> Iterable[Any]:
        return list(handles)

    def result(self, handle: Any) -> list[_Outcome]:
        return handle.outcomes


@dataclass(frozen=True)
class Serial(Executor):
    """Run the cases one after the other in this process."""

    def _open(self) -> _Backend:
        return _SerialBackend()


def _cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


class _PoolBackend(_Backend):
    def __init__(self, workers: int, context: str) -> None:
        self.slots = workers
        self.pool = concurrent.futures.ProcessPoolExecutor(
            max_workers=workers, mp_context=multiprocessing.get_context(context), initializer=_worker_init,
            initargs=(os.getpid(),))

    def submit(self, chunk: list[tuple[int, str, dict[str, Any]]]) -> Any:
        return self.pool.submit(_run_chunk, chunk)

    def wait(self, handles: Collection[Any]) -> Iterable[Any]:
        return concurrent.futures.wait(handles, return_when=concurrent.futures.FIRST_COMPLETED).done

    def result(self, handle: Any) -> list[_Outcome]:
        return handle.result()  # BrokenProcessPool: fatal, propagates

    def close(self, abort: bool) -> None:
        if not abort:
            self.pool.shutdown(wait=True)
            return
        self.pool.shutdown(wait=False, cancel_futures=True)
        # Stop the cases still running instead of waiting for them: Python >= 3.14 has a public method for it;
        # before, the pool's process table is the only handle on its workers.
        terminate = getattr(self.pool, "terminate_workers", None)
        if terminate is not None:
            terminate()
            return
        procs = list((getattr(self.pool, "_processes", None) or {}).values())
        for p in procs:
            p.terminate()
        for p in procs:
            p.join(timeout=5.0)


@dataclass(frozen=True)
class Processes(Executor):
    """Run the cases on local worker processes (each loads the C library once).

    Parameters
    ----------
    workers : int, optional
        Number of processes; default one per core available to this process.
    context : {"spawn", "forkserver"}
        How workers start (never ``fork``: the parent may hold threads and an open database).
    """

    workers: int | None = None
    context: Literal["spawn", "forkserver"] = "spawn"

    def __post_init__(self) -> None:
        if self.workers is not None and (isinstance(self.workers, bool) or not isinstance(self.workers, int)
                                         or self.workers < 1):
            raise BldclabError("workers", f"must be an integer >= 1, got {self.workers!r}")
        if self.context not in ("spawn", "forkserver"):
            raise BldclabError("context", f"must be 'spawn' or 'forkserver', got {self.context!r}")

    @property
    def n(self) -> int:
        """The number of worker processes."""
        return self.workers if self.workers is not None else _cores()

    def _open(self) -> _Backend:
        return _PoolBackend(self.n, self.context)

    def describe(self) -> str:  # noqa: D102
        return f"{self.n} processes"


class _DaskBackend(_Backend):
    def __init__(self, address: str, timeout: float) -> None:
        try:
            import distributed
        except ImportError:
            raise BldclabError("scheduler", "needs dask.distributed: pip install 'bldclab[dask]'") from None
        self._distributed = distributed
        try:
            self.client = distributed.Client(address, timeout=timeout, set_as_default=False)
        except Exception as exc:  # OSError, TimeoutError, ValueError for a malformed address
            raise BldclabError("scheduler", f"cannot connect to {address!r}: {exc}") from None
        self.slots = max(1, sum(self.client.nthreads().values()))
        self._pending: set[Any] = set()
        # this client's own event loop: no process-wide default client is set or needed
        self._completed = distributed.as_completed(loop=self.client.loop)

    def submit(self, chunk: list[tuple[int, str, dict[str, Any]]]) -> Any:
        fut = self.client.submit(_run_chunk, chunk, pure=False)
        self._pending.add(fut)
        self._completed.add(fut)
        return fut

    def wait(self, handles: Collection[Any]) -> Iterable[Any]:
        return self._completed.next_batch(block=True)

    def result(self, handle: Any) -> list[_Outcome]:
        self._pending.discard(handle)
        try:
            return handle.result()
        except Exception as exc:  # KilledWorker, CancelledError: the scheduler gave up on the chunk
            raise _ChunkLostError(f"{type(exc).__name__}: {exc}") from None

    def close(self, abort: bool) -> None:
        try:
            if abort and self._pending:
                self.client.cancel(list(self._pending))
        finally:
            self.client.close()


@dataclass(frozen=True)
class Dask(Executor):
    """Run the cases on a Dask cluster (``dask.distributed``), given its scheduler's address.

    Workers need the same bldclab version installed (a case carries its version and a worker refuses another).

    Parameters
    ----------
    address : str
        Scheduler address, ``tcp://HOST:PORT``.
    timeout : float
        Connection timeout (s).
    """

    address: str
    timeout: float = 10.0

    def __post_init__(self) -> None:
        if not isinstance(self.address, str) or not self.address:
            raise BldclabError("scheduler", f"expected an address like tcp://HOST:PORT, got {self.address!r}")

    def _open(self) -> _Backend:
        return _DaskBackend(self.address, self.timeout)

    def describe(self) -> str:  # noqa: D102
        return f"dask {self.address}"
