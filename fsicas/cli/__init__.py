"""Command line: ``fsicas <command> [scene options] [--scene FILE.toml] [--json]``.

With ``--json`` stdout holds one JSON object and nothing else (a stable contract).
Warnings of the analyses (e.g. a modal truncation too short to resolve the onset) are
returned in its ``"warnings"`` list (printed as a line of the summary without ``--json``).
Exit status: 0 when the command succeeded; 1 when it ran to the end but its result
reports a failure (``"status": "failed"``, also of a sub-result such as the impacting
branch of ``lco --through-contact``: a time integration whose gap closed or whose
solver failed, a continuation whose corrector failed), the result still printed; 2 for
bad input, an analysis that could not start or a sweep whose worker process died
(its finished points kept: run it again to resume) (the error on stderr, or as
``{"error": ...}`` with ``--json``); 130 after Ctrl-C (one line on stderr); 141 when the
reader of stdout went away (``| head``), silently.
No NaN or Infinity is printed: such a value is written as null and a warning names
where it was (:mod:`fsicas.strict_json`). Every JSON printed carries a ``"meta"`` object (versions, UTC time, the command line,
the scene, the settings and the units of each field; :mod:`fsicas.cli.meta`).
``--quiet`` and ``--verbose`` (before or after the command) set what is told on stderr
while it runs (:mod:`fsicas.cli.progress`). docs/cli.md lists every command and option
(:mod:`fsicas.cli.reference` writes it from :func:`build_parser`).
Figures are written with Matplotlib's non-interactive file backend, which the command
line (not the library) selects before a command that writes figures runs.
"""
from __future__ import annotations

import argparse
import os
import re
import sys
import time
import warnings

import casadi

from .. import __version__, strict_json
from ..linear.hopf import CriticalVelocityError
from ..linear.steady import SteadyStateError
from ..plots.backend import select_file_backend
from .curves import add_curve_command
from .cycles import add_cycle_commands
from .design import add_design_command
from .diagram import add_diagram_command
from .explore import add_explore_command
from .human import print_report
from .linear import add_linear_commands
from .meta import cli_meta, with_meta
from .onset import add_onset_command
from .outputs import check_outputs
from .paper import add_paper_command
from .progress import reporting
from .scene_options import check_ustar_max
from .sound import add_sound_command
from .study import add_study_command
from .timedomain import add_time_commands
from ..workers import WorkerLost

__all__ = ["main", "build_parser", "EXIT_OK", "EXIT_FAILED_RESULT", "EXIT_ERROR",
           "EXIT_INTERRUPTED", "EXIT_BROKEN_PIPE"]

#: Commands that write figures whether or not ``--plot`` is given.
_ALWAYS_PLOTTING = frozenset({"paper"})


def build_parser() -> argparse.ArgumentParser:
    """The ``fsicas`` parser: each subcommand's ``run`` maps its parsed args to a dict."""
    parser = argparse.ArgumentParser(
        prog="fsicas", description="fsicas: a flexible cantilever in confined axial flow "
        "(flutter onset, limit cycles, wall impacts). fsicas <command> [scene options] "
        "[--scene FILE.toml] [--json]; fsicas <command> --help for each command.")
    parser.add_argument("--version", action="version",
                        version=f"fsicas {__version__} (CasADi {casadi.__version__})")
    sub = parser.add_subparsers(dest="command", required=True)
    add_linear_commands(sub)        # modes, steady, eig, boundary (docs/stability.md)
    add_paper_command(sub)          # paper
    add_time_commands(sub)          # simulate, map (docs/simulate.md)
    add_cycle_commands(sub)         # lco, alias cycles (docs/cycles.md)
    add_curve_command(sub)          # grazing, Fig. 4's boundaries as curves (docs/cycles.md)
    add_diagram_command(sub)        # diagram, the bifurcation diagram by itself (docs/cli.md)
    add_onset_command(sub)          # onset, in physical units (docs/units.md)
    add_sound_command(sub)          # sound, the radiated snore (docs/sound.md)
    add_design_command(sub)         # design, what change stops the snore (docs/design.md)
    add_study_command(sub)          # study, an analysis over many parameters (docs/studies.md)
    add_explore_command(sub)        # explore, the model in a browser (docs/explore.md)
    _add_global_options(parser)
    for command in dict.fromkeys(sub.choices.values()):     # aliases share a parser
        _add_global_options(command, argparse.SUPPRESS)
    return parser


def _add_global_options(parser: argparse.ArgumentParser, default=False) -> None:
    """``--quiet`` and ``--verbose``, before the command or after it (``default``
    SUPPRESS on the commands, so that they keep a value given before the command)."""
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--quiet", "-q", action="store_true", default=default,
                       help="no progress bars and no stage lines on stderr")
    group.add_argument("--verbose", "-v", action="store_true", default=default,
                       help="stage lines of every command and solver statistics on stderr")


def _writes_figures(args: argparse.Namespace) -> bool:
    return args.command in _ALWAYS_PLOTTING or bool(getattr(args, "plot", None))


_NEGATIVE = re.compile(r"^-(\d|\.\d)")


def _negative_values_attached(argv: list) -> list:
    """``--opt -1e6`` as ``--opt=-1e6``: argparse reads a value that starts with ``-``
    and is not a plain decimal (``-1e6``, ``-5:-1:3``) as an option and fails with
    "expected one argument"; no fsicas option starts with ``-`` and a digit."""
    out, k = [], 0
    while k < len(argv):
        token = argv[k]
        if (token.startswith("--") and "=" not in token and k + 1 < len(argv)
                and _NEGATIVE.match(argv[k + 1])):
            out.append(f"{token}={argv[k + 1]}")
            k += 2
        else:
            out.append(token)
            k += 1
    return out


def _notes(caught) -> list:
    """The messages of the analyses' warnings (user warnings, and any warning raised from
    fsicas or continuation, e.g. a compiled-kernel fallback), once each; other warnings
    are shown on stderr as Python would have."""
    notes = []
    for w in caught:
        ours = any(part in w.filename for part in ("/fsicas/", "/continuation/"))
        if issubclass(w.category, UserWarning) or ours:
            notes.append(str(w.message))
        else:
            warnings.showwarning(w.message, w.category, w.filename, w.lineno)
    return list(dict.fromkeys(notes))


#: Exit statuses (module docstring).
EXIT_OK, EXIT_FAILED_RESULT, EXIT_ERROR = 0, 1, 2
EXIT_INTERRUPTED, EXIT_BROKEN_PIPE = 130, 141     # 128 + SIGINT, 128 + SIGPIPE, as shells say


def main(argv=None) -> int:
    """Run one command; its exit status (:data:`EXIT_OK`, :data:`EXIT_FAILED_RESULT`,
    :data:`EXIT_ERROR`; module docstring). Ctrl-C ends it with one line and
    :data:`EXIT_INTERRUPTED` (results files keep every point finished); a reader of its
    output that goes away (``| head``) ends it quietly with :data:`EXIT_BROKEN_PIPE`."""
    try:
        return _main(argv)
    except KeyboardInterrupt:
        print("fsicas: interrupted; the points already saved are kept (run the same command "
              "again to resume)", file=sys.stderr)
        return EXIT_INTERRUPTED
    except BrokenPipeError:
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())   # no second error
        return EXIT_BROKEN_PIPE


def _main(argv) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    args = build_parser().parse_args(_negative_values_attached(argv))
    args.argv = argv
    start = time.perf_counter()
    try:
        check_outputs(args)
        check_ustar_max(args)
        if _writes_figures(args):
            select_file_backend()
        with warnings.catch_warnings(record=True) as caught, reporting(args):
            warnings.simplefilter("always", UserWarning)
            result = args.run(args)
    except (ValueError, SteadyStateError, CriticalVelocityError, WorkerLost) as err:
        if getattr(args, "json", False):
            print(strict_json.dumps(with_meta({"error": str(err)}, cli_meta(args))))
        else:
            print(f"fsicas {args.command}: error: {err}", file=sys.stderr)
        return EXIT_ERROR
    if args.json:
        result = {**result, "meta": result.get("meta") or cli_meta(args)}
    result, places = strict_json.finite(result)
    notes = _notes(caught) + ([strict_json.nonfinite_note(places)] if places else [])
    if notes:
        own = result.get("warnings") or []
        result = {**result, "warnings": own + [n for n in notes if n not in own]}
    if args.json:
        print(strict_json.dumps(with_meta(result, result["meta"])))
    else:
        (getattr(args, "human", None) or print_report)(result)
        print(f"{'wall time':>16}: {time.perf_counter() - start:.3f} s")
    return EXIT_FAILED_RESULT if failed(result) else EXIT_OK


def failed(result: dict) -> bool:
    """Whether ``result`` or a sub-result in it (a dict value at any depth, e.g. the
    impacting branch of ``lco --through-contact``) has ``"status": "failed"``; the
    records of a list (the points of a sweep) are each point's own."""
    return result.get("status") == "failed" or any(
        failed(v) for k, v in result.items() if isinstance(v, dict) and k != "meta")


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
