"""Output paths of the command line, checked before any work starts.

A command that would compute for minutes and then fail to write its file must fail at
once instead: every ``--out`` and ``--plot`` is checked when the arguments are parsed
(``ValueError`` naming the option, exit status 2). ``paper --out`` is a folder (created
if missing); every other ``--out`` and ``--plot`` is a file whose folder must exist
(``--plot fig`` writes ``fig.png``, Matplotlib's default format, so that name is checked).

No run damages a file it did not make: an existing ``--out`` must be a file of the kind
the command writes (a results file of ``map``, a JSON result of ``lco``/``grazing``/``diagram``, a
WAV of ``sound``; ``study`` checks its table); anything else is refused and left as it is.
"""
from __future__ import annotations

import argparse
import json
import os
from pathlib import Path

from ..results_file import check_results_path

__all__ = ["check_outputs"]

#: Commands whose ``--out`` is a folder.
_FOLDER_OUTPUTS = frozenset({"paper"})


def check_outputs(args: argparse.Namespace) -> None:
    """ValueError naming the option if an output of ``args`` cannot be written."""
    out, plot = getattr(args, "out", None), getattr(args, "plot", None)
    if out:
        if args.command in _FOLDER_OUTPUTS:
            _check_folder("--out", Path(out))
        else:
            _check_file("--out", Path(out))
            _check_kind(args.command, Path(out))
    if plot:
        _check_file("--plot", Path(plot))
        _check_figure_format(Path(plot))
        if not Path(plot).suffix:
            _check_file("--plot", Path(plot).with_suffix(".png"))


def _is_json_result(path: Path) -> bool:
    """A JSON object with its ``meta`` (what ``--out FILE.json`` writes)."""
    try:
        with open(path) as fh:
            data = json.load(fh)
    except (OSError, UnicodeDecodeError, ValueError):
        return False
    return isinstance(data, dict) and "meta" in data


def _is_wav(path: Path) -> bool:
    with open(path, "rb") as fh:
        head = fh.read(12)
    return head[:4] == b"RIFF" and head[8:12] == b"WAVE"


#: What an existing ``--out`` of each command must be to be overwritten (or resumed).
_KINDS = {"lco": (_is_json_result, "a JSON result of fsicas"),
          "cycles": (_is_json_result, "a JSON result of fsicas"),
          "grazing": (_is_json_result, "a JSON result of fsicas"),
          "diagram": (_is_json_result, "a JSON result of fsicas"),
          "sound": (_is_wav, "a WAV file")}


def _check_kind(command: str, path: Path) -> None:
    """ValueError if an existing ``--out`` is not of the kind ``command`` writes."""
    if command == "map":
        check_results_path(path)
        return
    if command not in _KINDS or not path.is_file() or path.stat().st_size == 0:
        return
    accepts, kind = _KINDS[command]
    if not accepts(path):
        raise ValueError(f"--out {path}: the file exists and is not {kind}; it was left as "
                         "it is: name a new file")


def _check_file(option: str, path: Path) -> None:
    if path.is_dir():
        raise ValueError(f"{option} {path}: is a folder, expected a file name")
    if path.exists() and not os.access(path, os.W_OK):
        raise ValueError(f"{option} {path}: the file exists and is not writable")
    folder = path.parent
    if not folder.is_dir():
        raise ValueError(f"{option} {path}: the folder {folder} does not exist")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise ValueError(f"{option} {path}: the folder {folder} is not writable")


def _check_folder(option: str, path: Path) -> None:
    if path.exists() and not path.is_dir():
        raise ValueError(f"{option} {path}: exists and is not a folder")
    existing = next(p for p in (path, *path.parents) if p.exists())
    if not existing.is_dir():
        raise ValueError(f"{option} {path}: {existing} is a file, not a folder")
    if not os.access(existing, os.W_OK | os.X_OK):
        raise ValueError(f"{option} {path}: the folder {existing} is not writable")


def _check_figure_format(path: Path) -> None:
    """The file name's extension is a format Matplotlib writes (none: its default)."""
    if not path.suffix:
        return
    from matplotlib.backend_bases import FigureCanvasBase
    formats = FigureCanvasBase.get_supported_filetypes()
    if path.suffix[1:].lower() not in formats:
        raise ValueError(f"--plot {path}: unknown figure format {path.suffix!r}; "
                         f"use one of {', '.join(sorted(formats))}")
