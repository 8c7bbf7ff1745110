"""Jobs of the slower tiers, each in its own forked process: the page never waits for
one, a newer request replaces an older one of the same kind (which is ended), a job can
be cancelled, and finished results are cached by their key (the scene and the kind), so
moving back to a scene costs nothing."""
from __future__ import annotations

import multiprocessing
import time
import traceback
from dataclasses import dataclass, field

__all__ = ["Job", "Jobs"]


def _child(conn, target, args) -> None:
    """Run ``target(*args)`` and send ``("done", result)`` or ``("error", message)``: a
    ValueError's message alone (the library refusing the scene, or a value), another
    error's type and message (its traceback goes to the server's log, never the page)."""
    try:
        conn.send(("done", target(*args)))
    except ValueError as err:
        conn.send(("error", str(err)))
    except Exception as err:                            # noqa: BLE001 - reported, logged
        traceback.print_exc()
        conn.send(("error", f"{type(err).__name__}: {err}"))
    finally:
        conn.close()


@dataclass
class Job:
    """One running job: its key, process and pipe, and when it started."""

    key: tuple
    process: object
    conn: object
    started: float = field(default_factory=time.monotonic)

    @property
    def elapsed(self) -> float:
        return time.monotonic() - self.started

    def end(self) -> None:
        """End the process (if still running) and close the pipe."""
        if self.process.is_alive():
            self.process.kill()
        self.process.join(timeout=1.0)
        self.conn.close()


class Jobs:
    """At most one running job per kind (``key[0]``), a cache of finished results."""

    def __init__(self, cache: dict | None = None):
        self.running: dict[str, Job] = {}
        self.cache = {} if cache is None else cache
        self._context = multiprocessing.get_context("fork")

    def start(self, key: tuple, target, *args) -> dict | None:
        """The cached result of ``key``, or None after starting ``target(*args)`` in a
        new process (ending the running job of the same kind)."""
        if key in self.cache:
            self.cancel(key[0])
            return self.cache[key]
        running = self.running.get(key[0])
        if running is not None and running.key == key:
            return None
        self.cancel(key[0])
        parent, child = self._context.Pipe(duplex=False)
        process = self._context.Process(target=_child, args=(child, target, args), daemon=True)
        process.start()
        child.close()
        self.running[key[0]] = Job(key, process, parent)
        return None

    def cancel(self, kind: str) -> bool:
        """End the running job of ``kind``; True if there was one."""
        job = self.running.pop(kind, None)
        if job is not None:
            job.end()
        return job is not None

    def poll(self, kind: str):
        """``(status, value)`` of the job of ``kind``: ("running", seconds),
        ("done", result) (cached), ("error", message) or ("idle", None)."""
        job = self.running.get(kind)
        if job is None:
            return "idle", None
        if not job.conn.poll():
            if job.process.is_alive():
                return "running", job.elapsed
            self.running.pop(kind)
            job.end()
            return "error", f"the job ended without a result (exit code {job.process.exitcode})"
        status, value = job.conn.recv()
        self.running.pop(kind)
        job.end()
        if status == "done":
            self.cache[job.key] = value
        return status, value

    def close(self) -> None:
        """End every running job."""
        for kind in list(self.running):
            self.cancel(kind)
