"""No NaN or Infinity in the JSON fsicas prints, and nested failures exit 1."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from fsicas import strict_json
from fsicas.cli import EXIT_FAILED_RESULT, EXIT_OK, main
import fsicas.cli.linear as linear_cli


def _strict(text: str):
    """Parse as a strict reader does: NaN, Infinity and -Infinity are errors."""
    def refuse(token):
        raise ValueError(f"not JSON: {token}")
    return json.loads(text, parse_constant=refuse)


def test_finite_replaces_every_nonfinite_number_and_names_it():
    value = {"a": float("nan"), "b": [1.0, np.float64(np.inf), (2, -math.inf)],
             "c": {"d": np.float32("nan"), "e": "nan", "f": 3}}
    clean, places = strict_json.finite(value)
    assert clean == {"a": None, "b": [1.0, None, [2, None]], "c": {"d": None, "e": "nan", "f": 3}}
    assert places == ["a: nan", "b[1]: inf", "b[2][1]: -inf", "c.d: nan"]
    assert _strict(strict_json.dumps(value)) == clean
    note = strict_json.nonfinite_note(places)
    assert note.startswith("4 value(s)") and "b[2][1]" in note
    assert strict_json.nonfinite_note([]) is None


@pytest.fixture
def fake_eig(monkeypatch):
    """``fsicas eig`` answering with a result given by the test."""
    answer = {}
    monkeypatch.setattr(linear_cli, "_cmd_eig", lambda args: dict(answer))
    return answer


def test_the_cli_prints_null_and_a_warning_for_nan(fake_eig, capsys):
    fake_eig.update(status="success", growth=float("nan"), points=[{"u": float("inf")}])
    assert main(["eig", "--json"]) == EXIT_OK
    out = _strict(capsys.readouterr().out)
    assert out["growth"] is None and out["points"] == [{"u": None}]
    assert any("growth: nan" in w and "points[0].u: inf" in w for w in out["warnings"])


@pytest.mark.parametrize("result, code", [
    ({"status": "success", "impacting": {"status": "failed"}}, EXIT_FAILED_RESULT),
    ({"status": "contact", "a": {"b": {"status": "failed"}}}, EXIT_FAILED_RESULT),
    ({"status": "success", "points": [{"status": "failed"}]}, EXIT_OK),   # one point's own
    ({"status": "failed"}, EXIT_FAILED_RESULT),
])
def test_a_nested_failure_exits_1(fake_eig, capsys, result, code):
    fake_eig.update(result)
    assert main(["eig", "--json"]) == code
    _strict(capsys.readouterr().out)
