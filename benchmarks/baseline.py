"""Side-by-side timing of the working tree against an earlier revision, in one run.

``Baseline(rev)`` unpacks ``git archive rev`` into a temporary folder; ``compare`` runs
the same child script against both trees in turn (A B A B ...), each run a fresh
process whose ``sys.path`` starts with its tree, and reports the median time of each,
the median of the pairwise ratios (old / new: the speed-up, robust to a machine whose
speed drifts) and the largest difference of the values both return (the error between
the two routes). The child prints one JSON object ``{"time": s, "value": [...]}``.
"""
from __future__ import annotations

import json
import subprocess
import sys
import tarfile
import tempfile
from dataclasses import dataclass
from io import BytesIO
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


class Baseline:
    """The source tree of ``rev`` in a temporary folder (removed on exit)."""

    def __init__(self, rev: str):
        self.rev = rev
        self._tmp = tempfile.TemporaryDirectory(prefix="fsicas-baseline-")
        archive = subprocess.run(["git", "archive", rev], cwd=ROOT, check=True,
                                 capture_output=True).stdout
        with tarfile.open(fileobj=BytesIO(archive)) as tar:
            tar.extractall(self._tmp.name, filter="data")
        self.path = Path(self._tmp.name)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self._tmp.cleanup()


@dataclass(frozen=True)
class Comparison:
    """Median times (s) of the old and new tree, median pairwise speed-up, max |Δvalue|."""

    old: float
    new: float
    speedup: float
    difference: float


def run_child(tree: Path, script: str, args) -> dict:
    """Run ``script`` with ``sys.path[0] = tree``; its JSON output."""
    code = f"import sys; sys.path.insert(0, {str(tree)!r})\n" + script
    out = subprocess.run([sys.executable, "-c", code, *map(str, args)], check=True,
                         capture_output=True, text=True, cwd=tree).stdout
    return json.loads(out.strip().splitlines()[-1])


def compare(old_tree: Path, script: str, args, repeats: int = 3) -> Comparison:
    """Interleaved runs of ``script`` on ``old_tree`` and on the working tree."""
    old, new = [], []
    for _ in range(repeats):
        old.append(run_child(old_tree, script, args))
        new.append(run_child(ROOT, script, args))
    t_old = np.array([r["time"] for r in old])
    t_new = np.array([r["time"] for r in new])
    diff = max(float(np.max(np.abs(np.subtract(a["value"], b["value"]))))
               for a, b in zip(old, new))
    return Comparison(float(np.median(t_old)), float(np.median(t_new)),
                      float(np.median(t_old / t_new)), diff)
