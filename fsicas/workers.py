"""Local worker processes for sweeps that run points in parallel: a pool whose workers
end with the process that started them (also when it is killed with SIGKILL), so an
interrupted sweep leaves nothing running."""
from __future__ import annotations

import ctypes
import os
import signal
import threading
import time
from concurrent.futures import ProcessPoolExecutor

__all__ = ["die_with_parent", "local_pool"]


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


def local_pool(workers: int | None = None) -> ProcessPoolExecutor:
    """A process pool of ``workers`` (default: the local cores) that die with this process."""
    return ProcessPoolExecutor(max_workers=workers or os.cpu_count() or 1,
                               initializer=die_with_parent, initargs=(os.getpid(),))
