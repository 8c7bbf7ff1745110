"""Worker processes for sweeps that run points in parallel: a local pool whose workers
end with the process that started them (also when it is killed with SIGKILL), so an
interrupted sweep leaves nothing running, or the executor of a Dask scheduler."""
from __future__ import annotations

import ctypes
import os
import signal
import threading
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from contextlib import contextmanager

__all__ = ["die_with_parent", "local_pool", "dask_executor", "DASK_CONNECT_TIMEOUT", "check_workers",
           "OVERSUBSCRIBE_HELP", "WorkerLost", "finished"]


class WorkerLost(RuntimeError):
    """A worker process died while it computed a point (killed, out of memory)."""


def finished(futures, path):
    """The results of ``futures`` as they finish; :class:`WorkerLost` when a worker
    process died (a local pool broken, or Dask's ``KilledWorker``), saying that the
    points already saved in the results file ``path`` are kept."""
    try:
        for fut in as_completed(futures):
            yield fut.result()
    except Exception as err:
        if not isinstance(err, BrokenProcessPool) and type(err).__name__ != "KilledWorker":
            raise
        raise WorkerLost(f"a worker process died while computing a point (killed, or out "
                         f"of memory); the points finished are saved in {path}: run the "
                         "same command again to compute the rest") from None


def die_with_parent(parent: int) -> None:
    """Worker initializer: end this worker when the process ``parent`` dies (also by
    kill -9), by the kernel's parent-death signal on Linux and a watchdog thread
    elsewhere."""
    try:
        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL)     # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass
    if os.getppid() != parent:
        os._exit(1)

    def watch():
        while os.getppid() == parent:
            time.sleep(1.0)
        os._exit(1)
    threading.Thread(target=watch, daemon=True).start()


#: The help of ``--oversubscribe`` (the commands with ``--workers``).
OVERSUBSCRIBE_HELP = "allow --workers beyond the cores of this machine"


def check_workers(workers: int | None, oversubscribe: bool = False) -> None:
    """ValueError unless ``workers`` is None (the cores) or from 1 to the cores of this
    machine; more only with ``oversubscribe`` (``--oversubscribe``: processes beyond the
    cores share them and each point takes longer)."""
    cores = os.cpu_count() or 1
    if workers is None:
        return
    if workers < 1:
        raise ValueError(f"--workers must be >= 1, got {workers}")
    if workers > cores and not oversubscribe:
        raise ValueError(f"--workers {workers} is more than the {cores} cores of this "
                         f"machine: give --workers {cores} or fewer, or add --oversubscribe "
                         "to run more processes than cores")


def local_pool(workers: int | None = None) -> ProcessPoolExecutor:
    """A process pool of ``workers`` (default: the local cores) that die with this process."""
    return ProcessPoolExecutor(max_workers=workers or os.cpu_count() or 1,
                               initializer=die_with_parent, initargs=(os.getpid(),))


@contextmanager
def dask_executor(address: str):
    """The ``concurrent.futures`` executor of the Dask scheduler at ``address`` (the
    'parallel' extra), closed on exit; ValueError when Dask is not installed or the
    scheduler does not answer within :data:`DASK_CONNECT_TIMEOUT` seconds."""
    try:
        from distributed import Client
    except ImportError:
        raise ValueError("--dask needs Dask: pip install -e '.[parallel]'") from None
    try:
        client = Client(address, timeout=DASK_CONNECT_TIMEOUT)
    except (OSError, TimeoutError, ValueError) as err:
        raise ValueError(f"--dask {address}: no Dask scheduler answered there within "
                         f"{DASK_CONNECT_TIMEOUT:g} s ({type(err).__name__}: {err}); start one "
                         "(dask scheduler) or check the address") from None
    with client:
        yield client.get_executor()


#: Seconds to wait for a Dask scheduler to answer before giving up.
DASK_CONNECT_TIMEOUT = 10.0
