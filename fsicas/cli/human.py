"""The report a command prints without ``--json``: labelled values with sensible digits,
tables where there are rows.

One generic layout for every command's result (the same object ``--json`` prints):

- a number: 6 significant digits; a list of numbers: one line of them;
- a complex number given as ``[re, im]`` (eigenvalues, multipliers): ``re ± im i``,
  with ``(unstable)`` where the real part is positive, one per line;
- a list of records (dicts: the points of a branch or a boundary): a table of their
  plain columns, the first and last :data:`ROWS` // 2 rows when there are more, and a
  line saying how many and that ``--json`` gives all;
- a dict: its keys indented under its name (a record of records: ``key.sub``);
- warnings: one line each.
"""
from __future__ import annotations

import numbers

__all__ = ["print_report", "ROWS"]

#: Rows of a table shown at most (the first and last half).
ROWS = 12
#: Columns of a table at most; text wider than this per cell is cut.
COLUMNS, CELL = 11, 14
_WIDTH = 16


def print_report(result: dict) -> None:
    """Print ``result`` (a command's JSON object) for a person."""
    for line in _lines(result, ""):
        print(line)


def _lines(result: dict, prefix: str) -> list[str]:
    out = []
    for key, value in result.items():
        name = prefix + key
        if isinstance(value, dict):
            out += _lines(value, name + ".")
        elif _is_records(value):
            out += [f"{name:>{_WIDTH}}: {len(value)} rows"] + _table(value)
        elif _is_complex_list(value):
            out += [f"{name:>{_WIDTH}}:"] + [" " * (_WIDTH + 2) + _complex(v) for v in value]
        elif key == "warnings" and isinstance(value, list):
            out += [f"{'warning':>{_WIDTH}}: {w}" for w in value]
        else:
            out.append(f"{name:>{_WIDTH}}: {_value(value)}")
    return out


def _value(value) -> str:
    """A number with 6 significant digits; a list of plain values on one line."""
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return str(value)
    if isinstance(value, numbers.Real):
        return f"{value:.6g}"
    if isinstance(value, (list, tuple)):
        return ", ".join(_value(v) for v in value) if value else "none"
    return str(value)


def _is_records(value) -> bool:
    return isinstance(value, list) and bool(value) and all(isinstance(v, dict) for v in value)


def _is_complex_list(value) -> bool:
    return (isinstance(value, list) and bool(value) and all(
        isinstance(v, (list, tuple)) and len(v) == 2
        and all(isinstance(x, numbers.Real) and not isinstance(x, bool) for x in v)
        for v in value))


def _complex(pair) -> str:
    re, im = pair
    text = f"{re:.6g} {'+' if im >= 0 else '-'} {abs(im):.6g}i"
    return text + ("   (unstable)" if re > 0 else "")


def _table(records: list[dict]) -> list[str]:
    """The plain (number, text, bool, None) columns of ``records`` as a table."""
    columns = [k for k in dict.fromkeys(k for r in records for k in r)
               if all(_plain(r.get(k)) for r in records)][:COLUMNS]
    shown = records if len(records) <= ROWS else records[:ROWS // 2] + [None] + records[-ROWS // 2:]
    rows = [[_cell(r.get(k)) for k in columns] if r is not None else None for r in shown]
    widths = [max([len(k)] + [len(row[i]) for row in rows if row]) for i, k in enumerate(columns)]
    pad = " " * (_WIDTH + 2)
    out = [pad + "  ".join(k.rjust(w) for k, w in zip(columns, widths))]
    for row in rows:
        out.append(pad + ("  ".join(c.rjust(w) for c, w in zip(row, widths)) if row else
                          f"... {len(records) - ROWS} more rows (--json gives them all)"))
    return out


def _plain(value) -> bool:
    return value is None or isinstance(value, (str, bool, numbers.Real))


def _cell(value) -> str:
    text = _value(value)
    return text if len(text) <= CELL else text[:CELL - 1] + "…"
