"""The placement report (twin.report) and `twin check` (twin.check)."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from twin.check import ExpectError, check, evaluate, load_expect, main_check
from twin.report import Report, ReportError

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(__file__).resolve().parent / "data"
SCARA_EXPECT = ROOT / "scenes" / "scara_pick.expect.toml"


def make_report(in_bin: int = 100, dropped: int = 0, loose: int = 0, *, sim_time_s: float = 250.0,
                output: str = "Start\nAll done. 100 parts processed\n", errors=None, events=None,
                cycle_times_s=None, regions=None) -> Report:
    parts = []
    for region, n, drop in (("bin", in_bin, False), (None, dropped, True), (None, loose, False)):
        for _ in range(n):
            parts.append({"id": len(parts), "pose": [400.0, 10.0 * len(parts), 5.0, 1.0, 0.0, 0.0, 0.0],
                          "region": region, "dropped": drop})
    return Report(program="programs/vplus/move_parts.pg", scene="scenes/scara_pick.toml", seed=7,
                  sim_time_s=sim_time_s, wall_time_s=20.0, output=output, errors=errors or [],
                  parts=parts, regions=regions, events=events or [], cycle_times_s=cycle_times_s or [])


SCARA = {
    "regions": {"bin": 100},
    "parts": {"dropped": 0},
    "time": {"cycle_time_s": {"max": 3.0}},
    "program": {"errors": 0, "output_contains": ["All done. 100 parts processed"]},
}


# ---- report ------------------------------------------------------------------

def test_report_round_trip(tmp_path):
    r = make_report(98, dropped=1, loose=1, events=[{"time": 3.5, "kind": "drop", "part": 98}],
                    errors=[{"code": -413, "message": "*Undefined value*", "file": "a.pg", "line": 3,
                             "column": 1, "time": 2.0}], cycle_times_s=[0.5, 0.7])
    path = tmp_path / "sub" / "report.json"
    r.write(path)
    data = json.loads(path.read_text())
    assert data["twin_report"] == 1
    assert data["regions"] == {"bin": 98}
    back = Report.load(path)
    assert back == r
    assert back.dropped == 1 and back.unplaced == 1
    assert not list(path.parent.glob("*.tmp"))


def test_output_kept_exactly(tmp_path):
    text = "  x = 1.50\r\n\ttab é ü \u2603\n\n"
    r = make_report(output=text)
    r.write(tmp_path / "r.json")
    assert Report.load(tmp_path / "r.json").output == text


def test_regions_derived_and_unplaced_not_counted():
    r = make_report(3, dropped=2, loose=1)
    assert r.regions == {"bin": 3}
    # Declared empty regions are kept, so the checker can tell an empty region from a typo.
    r = make_report(3, regions={"bin": 3, "nest": 0})
    assert r.regions == {"bin": 3, "nest": 0}
    with pytest.raises(ReportError, match="regions\\['bin'\\] = 4 but 3 part"):
        make_report(3, regions={"bin": 4})


def test_error_fields_default_to_null():
    r = make_report(errors=[{"message": "boom"}])
    assert r.errors == [{"message": "boom", "code": None, "file": None, "line": None,
                         "column": None, "text": None, "step": None, "program": None,
                         "time": None}]


def test_non_finite_value_is_refused():
    r = make_report(1)
    r.parts[0]["pose"][2] = float("nan")
    with pytest.raises(ValueError, match=r"parts.*\[0\].*pose.*nan"):
        r.to_json()


@pytest.mark.parametrize("content, message", [
    (None, "no such report file"),
    ("{not json", "not valid JSON"),
    ("[1, 2]", "expected a JSON object"),
    ('{"program": "p"}', "missing key(s) scene, seed, sim_time_s, wall_time_s, output"),
    ('{"program": "p", "scene": "s", "seed": 1, "sim_time_s": 1, "wall_time_s": 1, "output": "",'
     ' "colour": 1}', "unknown key(s) colour"),
    ('{"program": "p", "scene": "s", "seed": "one", "sim_time_s": 1, "wall_time_s": 1, "output": ""}',
     "seed must be an integer"),
    ('{"program": "p", "scene": "s", "seed": 1, "sim_time_s": 1, "wall_time_s": 1, "output": "",'
     ' "parts": [{"id": 1, "pose": [1, 2, 3], "region": null, "dropped": false}]}', "parts[0].pose must be 7"),
    ('{"twin_report": 9, "program": "p"}', "format 9 is not supported"),
])
def test_load_rejects_bad_files(tmp_path, content, message):
    path = tmp_path / "report.json"
    if content is not None:
        path.write_text(content)
    with pytest.raises(ReportError) as info:
        Report.load(path)
    assert message in str(info.value)
    assert str(path) in str(info.value)


# ---- check -----------------------------------------------------------------

def test_good_run_passes():
    assert check(make_report(), SCARA) == []


def test_failures_are_sentences():
    r = make_report(99, dropped=1, output="Start\n", sim_time_s=400.0,
                    errors=[{"code": -413, "message": "*Undefined value*", "file": "move_parts.pg",
                             "line": 12}])
    failures = check(r, SCARA)
    assert failures == [
        "region 'bin' holds 99 parts, expected exactly 100",
        "1 part dropped, expected exactly 0",
        "cycle time was 4.040 s (400.000 s / 99 parts in a place region), expected at most 3 s",
        "the program raised 1 error, expected exactly 0: move_parts.pg:12: *Undefined value* (-413)",
        "the program output does not contain 'All done. 100 parts processed'; its last lines were: Start",
    ]


def test_bounds_and_other_figures():
    r = make_report(5, dropped=1, loose=2, sim_time_s=100.0,
                    events=[{"time": 1.25, "kind": "collision"}, {"time": 2.0, "kind": "collision"}],
                    regions={"bin": 5, "nest": 0})
    expect = {
        "regions": {"bin": {"min": 1, "max": 4}, "nest": {"max": 1}},
        "parts": {"total": 8, "unplaced": {"max": 1}},
        "time": {"sim_time_s": {"max": 90}, "wall_time_s": {"min": 1, "max": 30},
                 "realtime_factor": {"min": 10}},
        "program": {"output_excludes": ["Start"]},
        "events": {"collision": 0, "dropped": {"max": 3}},
    }
    assert check(r, expect) == [
        "region 'bin' holds 5 parts, expected between 1 and 4",
        "2 parts in no region (not dropped), expected at most 1",
        "simulated time was 100.000 s, expected at most 90 s",
        "the run went 5.00x real time (100.000 s simulated in 20.000 s), expected at least 10 x",
        "the program output contains 'Start', which it must not (in line 'Start')",
        "2 'collision' events occurred, expected exactly 0 (first at t = 1.250 s)",
    ]


def test_region_missing_from_report_is_a_failure_not_zero():
    r = make_report(100, regions={"bin": 100, "nest": 0})
    assert check(r, {"regions": {"nest": 0}}) == []
    assert check(r, {"regions": {"bni": 0}}) == [
        "region 'bni' is not in the report (its regions: 'bin', 'nest'); expected exactly 0 parts"]


def test_cycle_time_sources():
    # Mean of measured cycles wins over sim_time / parts placed.
    r = make_report(10, sim_time_s=100.0, cycle_times_s=[2.0, 4.0, 3.5])
    assert check(r, {"time": {"cycle_time_s": {"max": 3.0}}}) == [
        "cycle time was 3.167 s (mean of 3 measured cycles), expected at most 3 s"]
    r = make_report(10, sim_time_s=25.0)
    assert check(r, {"time": {"cycle_time_s": {"max": 3.0}}}) == []
    assert check(r, {"time": {"cycle_time_s": {"max": 3.0}, "place_regions": ["nest"]}}) == [
        "cycle time is undefined: no part reached region 'nest' and no cycle was measured"]


@pytest.mark.parametrize("expect, message", [
    ({"region": {"bin": 1}}, "unknown section(s) [region]"),
    ({"parts": {"droped": 0}}, "unknown key(s) in [parts]: droped"),
    ({"time": {"cycle_time": {"max": 3}}}, "unknown key(s) in [time]: cycle_time"),
    ({"program": {"output_contain": "x"}}, "unknown key(s) in [program]: output_contain"),
    ({"regions": {"bin": {"maximum": 3}}}, "regions.bin: unknown bound 'maximum'"),
    ({"regions": {"bin": {}}}, "regions.bin: empty bounds"),
    ({"regions": {"bin": 2.5}}, "regions.bin must be an integer"),
    ({"regions": {"bin": True}}, "regions.bin must be an integer"),
    ({"regions": {"bin": {"min": 5, "max": 1}}}, "min 5 is greater than max 1"),
    ({"time": {"sim_time_s": 400}}, "time.sim_time_s must be written as bounds"),
    ({"program": {"output_contains": [1]}}, "program.output_contains must be a string or a list"),
    ({"events": "none"}, "[events] must be a table"),
])
def test_invalid_expectations_raise(expect, message):
    with pytest.raises(ExpectError) as info:
        check(make_report(), expect)
    assert message in str(info.value)


def test_scara_expectation_file():
    expect = load_expect(SCARA_EXPECT)
    assert expect == SCARA
    assert check(make_report(), expect) == []
    assert check(make_report(100, output="All done. 99 parts processed\n"), expect) != []


# ---- command line ------------------------------------------------------------

def run(argv, capsys):
    code = main_check([str(a) for a in argv])
    out = capsys.readouterr()
    return code, out.out, out.err


def test_cli_pass_fail_and_junit(tmp_path, capsys):
    good, bad = tmp_path / "good.json", tmp_path / "bad.json"
    make_report().write(good)
    make_report(99, dropped=1).write(bad)
    junit = tmp_path / "junit" / "check.xml"

    code, out, err = run([good, "--expect", SCARA_EXPECT, "--junit", junit], capsys)
    assert code == 0, out + err
    assert "OK: all 5 expectations hold" in out
    suite = ET.parse(junit).getroot().find("testsuite")
    assert suite.get("tests") == "5" and suite.get("failures") == "0"

    code, out, err = run([bad, "--expect", SCARA_EXPECT, "--junit", junit], capsys)
    assert code == 1
    assert "FAILED: 2 of 5 expectations" in out
    assert "  - region 'bin' holds 99 parts, expected exactly 100" in out
    assert "  - 1 part dropped, expected exactly 0" in out
    suite = ET.parse(junit).getroot().find("testsuite")
    cases = suite.findall("testcase")
    assert [c.get("name") for c in cases] == [
        "bin = 100", "dropped = 0", "cycle_time_s = { max = 3 }", "errors = 0",
        "output contains 'All done. 100 parts processed'"]
    failed = {c.get("name"): c.find("failure").get("message") for c in cases if c.find("failure") is not None}
    assert failed["bin = 100"] == "region 'bin' holds 99 parts, expected exactly 100"
    assert suite.get("failures") == "2"
    assert set(failed) == {"bin = 100", "dropped = 0"}


def test_cli_bad_inputs_exit_2_without_traceback(tmp_path, capsys):
    good = tmp_path / "good.json"
    make_report().write(good)
    typo = DATA / "expect_typo.toml"
    broken = tmp_path / "broken.toml"
    broken.write_text("[regions\nbin = 1\n")
    cases = [
        ([tmp_path / "missing.json", "--expect", SCARA_EXPECT], "no such report file"),
        ([DATA / "report_invalid.json", "--expect", SCARA_EXPECT], "parts[1].dropped must be true or false"),
        ([good, "--expect", tmp_path / "missing.toml"], "no such expectation file"),
        ([good, "--expect", broken], "not valid TOML"),
        ([good, "--expect", typo], "unknown key(s) in [parts]: dropped_parts"),
        ([good], "the following arguments are required: --expect"),
    ]
    for argv, message in cases:
        code, out, err = run(argv, capsys)
        assert code == 2, (argv, out, err)
        assert message in err, (argv, err)
        assert "Traceback" not in out + err


def test_cli_junit_records_load_error(tmp_path, capsys):
    junit = tmp_path / "j.xml"
    code, _, _ = run([tmp_path / "nope.json", "--expect", SCARA_EXPECT, "--junit", junit], capsys)
    assert code == 2
    suite = ET.parse(junit).getroot().find("testsuite")
    assert suite.get("errors") == "1"
    assert "no such report file" in suite.find("testcase/error").get("message")


def test_fixture_report_passes(capsys):
    code, out, err = run([DATA / "report_ok.json", "--expect", SCARA_EXPECT], capsys)
    assert code == 1   # the fixture holds 3 parts in the bin, not 100
    assert "region 'bin' holds 3 parts, expected exactly 100" in out
    r = Report.load(DATA / "report_ok.json")
    assert [o.failure is None for o in evaluate(r, {"regions": {"bin": 3, "nest": 0}, "parts": {"dropped": 1}})] \
        == [True, True, True]
