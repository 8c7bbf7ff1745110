"""What a command prints without --json: labelled values, tables, no Python reprs."""
from __future__ import annotations

from fsicas.cli import main
from fsicas.cli.human import ROWS, print_report


def test_eigenvalues_are_complex_numbers_marked_unstable(capsys):
    assert main(["eig", "--modes", "4", "--ustar", "9"]) == 0
    out = capsys.readouterr().out
    unstable = [line for line in out.splitlines() if "(unstable)" in line]
    assert len(unstable) == 2 and all(line.strip()[0].isdigit() for line in unstable)
    assert "[[" not in out and "stable: False" in out


def test_records_are_a_table_with_the_middle_left_out(capsys):
    points = [{"ustar": 5 + k / 3, "stable": k % 2 == 0, "state": [1.0, 2.0]} for k in range(40)]
    print_report({"status": "bound", "points": points, "hopf": {"omega": 45.55707987818798},
                  "warnings": ["a first", "a second"]})
    out = capsys.readouterr().out
    lines = out.splitlines()
    assert "{" not in out and "45.5571" in out and "45.55707987818798" not in out
    header = next(line for line in lines if "ustar" in line and "stable" in line)
    assert "state" not in header                               # not a plain column
    assert f"... {40 - ROWS} more rows (--json gives them all)" in out
    assert sum(line.strip().endswith(("True", "False")) for line in lines) == ROWS
    assert out.count("warning: a ") == 2 and "hopf.omega: 45.5571" in out
