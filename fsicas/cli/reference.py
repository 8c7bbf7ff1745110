"""docs/cli.md, the command-line reference, written from :func:`fsicas.cli.build_parser`:
every command with its help, and every option with its value, default and help, by group.

``python3 -m fsicas.cli.reference [FILE]`` writes it (default ``docs/cli.md``);
tests/test_cli_meta.py checks that the committed file is the one the parser gives.
"""
from __future__ import annotations

import argparse
import re
from pathlib import Path

__all__ = ["cli_reference", "write_reference"]

_HEADER = """# Command line reference

Generated from the parser (`fsicas.cli.build_parser()`) by `python3 -m fsicas.cli.reference`;
do not edit by hand (a test checks that this file is current). `fsicas <command> --help`
prints the same. The keys of each command's JSON are described in `README.md` and the
documents of its analysis.

With `--json`, stdout holds one JSON object and nothing else. Every such object (and the
branch file of `lco --out`, and `report.json` of `paper`) carries a `meta` object:
`fsicas`, `casadi`, `numpy`, `scipy`, `python` (versions), `created` (UTC, ISO 8601),
`command` (the command line), `scene` (the scene used, as `Scene.to_dict()`; null for
`paper`, whose sections each hold their own `scene`), `settings` (the other options as
parsed, and the settings the command resolved from them) and `units` (field of the
result: its unit, for the fields the result has; lengths by L, time by
T = L^2 sqrt(rho_s e / D), pressure by D / L^3). No file or output holds NaN or
Infinity: a number that is not finite is written as null and a `warnings` entry says
where.

On stderr: by default, progress bars when stderr is a terminal (continuation runs of
`boundary`, `lco`, `onset`, `paper`; the points of `map`) and the stage lines of `paper`;
`--quiet`: none of these; `--verbose`: a stage line at each stage of every command, and
solver statistics (per kind of continuation run: runs, points, Newton iterations,
rejected steps, located points, restarts, time; the steps of a time integration).
"""

_STATED_DEFAULT = re.compile(r" \(default ([^()]*)\)$")


def cli_reference(parser: argparse.ArgumentParser | None = None) -> str:
    """The reference of ``parser`` (default: the ``fsicas`` parser) as Markdown."""
    if parser is None:
        from . import build_parser
        parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    parts = [_HEADER, _plain(parser.description or ""), "", "## Global options", "",
             "Before or after the command (`fsicas --quiet boundary ...` or "
             "`fsicas boundary ... --quiet`).", "", *_table(parser._actions, skip={sub})]
    for choice in sub._choices_actions:
        parts += ["", f"## fsicas {choice.dest}", "", _plain(choice.help or "") + _aliases(choice)]
        parts += _command(sub.choices[choice.dest])
    return "\n".join(parts).rstrip() + "\n"


def write_reference(path="docs/cli.md") -> None:
    """Write :func:`cli_reference` to ``path``."""
    Path(path).write_text(cli_reference())


def _aliases(choice) -> str:
    names = choice.metavar or ""
    return f" (alias: {names.split('(', 1)[1].rstrip(')')})" if "(" in names else ""


def _command(parser: argparse.ArgumentParser) -> list:
    """The option tables of one command, one per group (global options left out)."""
    out = []
    for group in parser._action_groups:
        actions = [a for a in group._group_actions if a.dest not in ("help", "quiet", "verbose")]
        if actions:
            out += ["", f"### {group.title}", "", *_table(actions)]
    return out


def _table(actions, skip=()) -> list:
    rows = ["| option | default | meaning |", "| --- | --- | --- |"]
    for a in actions:
        if a in skip or a.dest == "help":
            continue
        default, meaning = _default(a), _help(a)
        stated = _STATED_DEFAULT.search(meaning)
        if not default and stated:       # a default stated in the help (the scene options)
            default, meaning = f"`{stated.group(1)}`", meaning[:stated.start()]
        rows.append(f"| {_cell(_names(a))} | {_cell(default)} | {_cell(meaning)} |")
    return rows


def _names(action) -> str:
    value = "" if action.nargs == 0 else f" {action.metavar or action.dest.upper()}"
    return ", ".join(f"`{name}{value}`" for name in action.option_strings)


def _default(action) -> str:
    default = action.default
    if action.nargs == 0 and not isinstance(action, argparse.BooleanOptionalAction):
        return "" if action.dest == "version" else "off"
    if default is None or default is argparse.SUPPRESS:
        return ""
    return f"`{default}`"


def _help(action) -> str:
    text = (action.help or "") % {"default": action.default, "prog": "fsicas"}
    if action.choices and not isinstance(action.choices, dict):
        text += f" (one of: {', '.join(map(str, action.choices))})"
    if action.required:
        text += " (required)"
    return _plain(text)


def _plain(text: str) -> str:
    """Help text as Markdown: reStructuredText's double backticks as code spans."""
    return " ".join(text.replace("``", "`").split())


def _cell(text: str) -> str:
    return text.replace("|", "\\|")


def main(argv=None) -> None:
    """``python3 -m fsicas.cli.reference [FILE]`` (``--help`` prints the usage)."""
    parser = argparse.ArgumentParser(prog="python3 -m fsicas.cli.reference",
                                     description="Write the command-line reference.")
    parser.add_argument("file", nargs="?", default="docs/cli.md",
                        help="where to write it (default: docs/cli.md)")
    write_reference(parser.parse_args(argv).file)


if __name__ == "__main__":  # pragma: no cover
    main()
