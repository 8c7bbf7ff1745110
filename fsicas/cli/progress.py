"""What a command tells on stderr while it runs: progress bars, stage lines, statistics.

Three levels, from the global options: ``--quiet`` (nothing but errors and Python's own
warnings), the default (progress bars when stderr is a terminal, and the stage lines of
``fsicas paper``), ``--verbose`` (stage lines of every command, and solver statistics:
each continuation run's kind, points, Newton iterations and time, summed per kind).

The progress bars are those the analyses already have: the continuation library's tqdm
bar, which :func:`reporting` switches on for the runs of the command when stderr is a
terminal (``continuation.observing``, which also hands each run's Branch to the
statistics), and the impact map's bar (tqdm, shown on
a terminal only; ``--quiet`` hides stderr's terminal from it). stdout is never written
here: with ``--json`` it holds the result only.
"""
from __future__ import annotations

import argparse
import sys
import time
from collections import defaultdict
from contextlib import contextmanager

import continuation as C

__all__ = ["QUIET", "NORMAL", "VERBOSE", "Reporter", "reporter", "reporting", "level"]

QUIET, NORMAL, VERBOSE = 0, 1, 2


def level(args: argparse.Namespace) -> int:
    """The level of ``--quiet`` / ``--verbose`` (default :data:`NORMAL`)."""
    if getattr(args, "quiet", False):
        return QUIET
    return VERBOSE if getattr(args, "verbose", False) else NORMAL


class Reporter:
    """Stage lines ``fsicas COMMAND [  12.3 s] text`` on stderr, by level."""

    def __init__(self, command: str, level: int = NORMAL):
        self.command, self.level, self.start = command, level, time.perf_counter()
        self.runs = defaultdict(lambda: defaultdict(float))   # kind -> continuation stats

    @property
    def bars(self) -> bool:
        """Progress bars are shown: not quiet, and stderr is a terminal."""
        return self.level >= NORMAL and _is_terminal(sys.stderr)

    def stage(self, text: str, always: bool = False) -> None:
        """A stage line: with ``--verbose``, or by default too if ``always``."""
        if self.level >= VERBOSE or (always and self.level >= NORMAL):
            print(f"fsicas {self.command} [{time.perf_counter() - self.start:6.1f} s] {text}",
                  file=sys.stderr, flush=True)

    def stats(self, text: str) -> None:
        """A line of solver statistics (``--verbose`` only)."""
        self.stage(text, always=False)

    def count(self, branch) -> None:
        """Add one continuation run (a ``continuation.Branch``) to the statistics."""
        run = self.runs[branch.kind]
        run["runs"] += 1
        run["points"] += len(branch.s)
        for key in ("newton_iterations", "rejected_steps", "located", "restarts", "time_total"):
            run[key] += branch.stats.get(key, 0)

    def summary(self) -> None:
        """One statistics line per kind of continuation run, then the wall time."""
        for kind, run in self.runs.items():
            self.stats(f"continuation {kind}: {run['runs']:g} runs, {run['points']:g} points, "
                       f"{run['newton_iterations']:g} Newton iterations, "
                       f"{run['rejected_steps']:g} rejected steps, {run['located']:g} located "
                       f"points, {run['restarts']:g} restarts, {run['time_total']:.2f} s")
        self.stage("done")


def reporter(args: argparse.Namespace) -> Reporter:
    """The command's reporter (a silent one for args not run through :func:`reporting`)."""
    return getattr(args, "reporter", None) or Reporter(getattr(args, "command", "?"), QUIET)


@contextmanager
def reporting(args: argparse.Namespace):
    """Run a command with ``args.reporter`` set; continuation runs inside show the
    library's progress bar (on a terminal) and are counted for ``--verbose``."""
    rep = args.reporter = Reporter(args.command, level(args))
    stderr = sys.stderr
    if rep.level == QUIET:
        sys.stderr = _NoTerminal(stderr)       # tqdm(disable=None) bars stay off
    try:
        with C.observing(on_branch=rep.count, progress=rep.bars):
            yield rep
        rep.summary()
    finally:
        sys.stderr = stderr


def _is_terminal(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False


class _NoTerminal:
    """A stream as it is, but never a terminal (tqdm bars with ``disable=None`` stay off)."""

    def __init__(self, stream):
        self._stream = stream

    def isatty(self) -> bool:
        return False

    def __getattr__(self, name):
        return getattr(self._stream, name)
