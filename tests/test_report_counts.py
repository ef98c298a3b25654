"""The report's cell figures (twin/report.py): per-part fields, `counts`, `components`, and
`[counts]` in an expectation file (twin/check.py)."""

from __future__ import annotations

import json

import pytest

from twin.check import ExpectError, check
from twin.report import Report, ReportError


def _report(counts=None, parts=None) -> Report:
    parts = parts if parts is not None else [
        {"id": 0, "type": "block", "pose": [230.0, -7.5, 810.0, 1.0, 0.0, 0.0, 0.0], "region": "tray",
         "dropped": False, "picked": True, "missed": False, "tray": "tray", "cell": 0},
        {"id": 1, "type": "block", "pose": [600.0, 350.0, 770.0, 1.0, 0.0, 0.0, 0.0], "region": "reject",
         "dropped": False, "picked": False, "missed": True}]
    return Report(program="p.pg", scene="s.toml", seed=1, sim_time_s=10.0, wall_time_s=1.0, output="",
                  parts=parts, counts=counts, components={"conveyor.infeed": {"counts": 1000}})


COUNTS = {"created": 2, "picked": 1, "placed": 1, "missed": 1, "dropped": 0}


def test_counts_round_trip_and_are_checkable():
    r = Report.from_dict(json.loads(_report(COUNTS).to_json()))
    assert r.counts == COUNTS and r.parts[0]["cell"] == 0 and r.components["conveyor.infeed"]["counts"] == 1000
    assert check(r, {"counts": {"placed": 1, "missed": {"max": 1}, "dropped": 0}}) == []
    (failure,) = check(r, {"counts": {"missed": 0}})
    assert "1 part missed, expected exactly 0" in failure


def test_counts_expectations_on_a_report_without_counts_fail():
    (failure,) = check(_report(None), {"counts": {"placed": 1}})
    assert "no counts" in failure


def test_unknown_count_name_is_an_expectation_error():
    with pytest.raises(ExpectError, match="unknown key.*plaed"):
        check(_report(COUNTS), {"counts": {"plaed": 1}})


@pytest.mark.parametrize("counts, parts, message", [
    ({"created": 2}, None, "counts must map at least"),
    ({**COUNTS, "placed": -1}, None, "counts must map at least"),
    (COUNTS, [{"id": 0, "pose": [0.0] * 7, "region": None, "dropped": False, "colour": "red"}], "may have"),
    (COUNTS, [{"id": 0, "pose": [0.0] * 7, "region": None, "dropped": False, "cell": "3"}], "parts[0].cell"),
    (COUNTS, [{"id": 0, "pose": [0.0] * 7, "region": None, "dropped": False, "picked": 1}], "parts[0].picked"),
])
def test_bad_counts_or_part_fields_are_refused(counts, parts, message):
    with pytest.raises(ReportError) as err:
        _report(counts, parts)
    assert message in str(err.value)
