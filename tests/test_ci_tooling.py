"""CI tooling: the new expectations of twin check (pose, per-part region, event order,
cycle-time statistics), validation of every key and event kind, the JSON Schemas, JUnit
properties, `twin run --expect`, `twin run --seeds` and the pytest plugin with its example."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import jsonschema
import pytest

from twin.check import ExpectError, check, load_expect, percentile
from twin.cli import main as twin_main
from twin.report import EVENT_KINDS, Report
from twin.schemas import load_schema

from conftest import ROOT, SCARA_EXPECT, SCARA_SCENE

EXAMPLES = ROOT / "examples"
PICK_THREE = EXAMPLES / "pick_three.pg"
PICK_THREE_EXPECT = EXAMPLES / "pick_three.expect.toml"


@pytest.fixture(scope="module")
def pick_three(tmp_path_factory) -> tuple[int, Path]:
    """`twin run examples/pick_three.pg --expect ... --junit ...`: exit code and its folder."""
    out = tmp_path_factory.mktemp("pick3")
    code = twin_main(["run", str(PICK_THREE), "--scene", str(SCARA_SCENE), "--report", str(out / "report.json"),
                      "--expect", str(PICK_THREE_EXPECT), "--junit", str(out / "junit.xml")])
    return code, out


def test_run_and_check_in_one_command(pick_three, capsys):
    code, out = pick_three
    assert code == 0
    report = Report.load(out / "report.json")
    assert check(report, load_expect(PICK_THREE_EXPECT)) == []


def test_junit_has_the_runs_timing_and_properties(pick_three):
    _, out = pick_three
    suite = ET.parse(out / "junit.xml").getroot().find("testsuite")
    report = json.loads((out / "report.json").read_text())
    props = {p.get("name"): p.get("value") for p in suite.iter("property")}
    assert props["seed"] == str(report["seed"]) and props["scene"] == report["scene"]
    assert props["program"] == report["program"] and props["interrupted"] == "False"
    assert float(suite.get("time")) == pytest.approx(report["wall_time_s"], abs=1e-3)
    cases = suite.findall("testcase")
    assert len(cases) == int(suite.get("tests")) == 12 and suite.get("failures") == "0"
    assert all(float(c.get("time")) >= 0 for c in cases)


def test_a_misplaced_part_is_named_with_its_distance(pick_three):
    _, out = pick_three
    report = Report.load(out / "report.json")
    nest = [p for p in report.parts if p["id"] == 3][0]["pose"][:3]
    failures = check(report, {"parts": {"pose": [{"id": 3, "position": [nest[0] + 30, nest[1], nest[2]]},
                                                 {"id": 0, "position": [300, -180, 860], "tolerance_mm": 5}]}})
    assert len(failures) == 2
    assert re.match(r"part 3 is 30\.0 mm from \(3\d\d\.\d, -1\d\d\.\d, 8\d\d\.\d\) mm \(it is at .*\), "
                    r"expected within 1 mm", failures[0]), failures[0]
    assert failures[1].startswith("part 0 is ") and "expected within 5 mm" in failures[1]
    assert check(report, {"parts": {"pose": {"id": 42, "position": [0, 0, 0]}}}) == [
        "part 42 is not in the report (it has 4 parts)"]


def test_per_part_regions_and_event_order(pick_three):
    _, out = pick_three
    report = Report.load(out / "report.json")
    assert check(report, {"parts": {"region": {"nest": [0, 3]}}}) == [
        "expected parts [0, 3] in region 'nest': part 0 is in 'bin'"]
    assert check(report, {"events": {"order": ["release", "grasp", {"kind": "release", "part": 0}]}}) == [
        "events out of order: no release of part 0 after grasp at t = 2.260 s (event 3 of 3 in the order)"]
    assert check(report, {"events": {"order": [{"kind": "grasp", "part": 2}, {"kind": "grasp", "part": 1}]}}) \
        == ["events out of order: no grasp of part 1 after grasp of part 2 at t = 4.082 s (event 2 of 2 in the order)"]


def test_cycle_time_statistics():
    values = [1.0, 2.0, 3.0, 4.0, 10.0]
    assert percentile(values, 50) == 3.0 and percentile(values, 100) == 10.0
    assert percentile(values, 90) == pytest.approx(7.6)     # numpy.percentile's linear method
    r = Report(program="p", scene="s", seed=0, sim_time_s=20.0, wall_time_s=1.0, output="", cycle_times_s=values)
    assert check(r, {"cycle_time": {"median": {"max": 3.0}, "p90": {"max": 8.0}, "mean": {"min": 4.0}}}) == []
    assert check(r, {"cycle_time": {"p99.5": {"max": 9.0}, "min": {"min": 1.5}}}) == [
        "cycle time p99.5 was 9.880 s (over 5 cycles), expected at most 9 s",
        "cycle time min was 1.000 s (over 5 cycles), expected at least 1.5 s"]
    empty = Report(program="p", scene="s", seed=0, sim_time_s=20.0, wall_time_s=1.0, output="")
    assert check(empty, {"cycle_time": {"max": {"max": 2}}}) == [
        "cycle time max is undefined: the run measured no cycle"]


@pytest.mark.parametrize("expect, message", [
    ({"events": {"drop": 0}}, "unknown event kind 'drop' (did you mean 'dropped'?)"),
    ({"events": {"order": ["grasp", "relase"]}}, "events.order[1]: unknown event kind 'relase' (did you mean 'release'?)"),
    ({"parts": {"pose": {"id": 1, "positon": [0, 0, 0]}}}, "parts.pose[0]: unknown key 'positon' (did you mean 'position'?)"),
    ({"parts": {"pose": {"id": 1, "position": [0, 0]}}}, "parts.pose[0].position must be [x, y, z] in mm"),
    ({"parts": {"region": {"bin": []}}}, "parts.region.bin must be a non-empty list of part ids"),
    ({"cycle_time": {"medain": {"max": 1}}}, "unknown key(s) in [cycle_time]: medain (did you mean 'median'?)"),
    ({"cycle_time": {"p95": 2.0}}, "cycle_time.p95 must be written as bounds"),
    ({"progam": {}}, "unknown section(s) [progam]"),
])
def test_every_key_and_event_kind_is_validated(expect, message):
    with pytest.raises(ExpectError) as err:
        check(Report(program="p", scene="s", seed=0, sim_time_s=1.0, wall_time_s=1.0, output=""), expect)
    assert message in str(err.value)


def test_a_misspelt_event_kind_in_a_file_is_exit_2_before_running(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text("[events]\ndrop = 0\n")
    assert twin_main(["check", str(ROOT / "tests" / "data" / "report_ok.json"), "--expect", str(bad)]) == 2
    assert "unknown event kind 'drop' (did you mean 'dropped'?)" in capsys.readouterr().err
    # twin run reads the expectations first: no run is wasted on a typo.
    assert twin_main(["run", str(PICK_THREE), "--expect", str(bad), "--report", str(tmp_path / "r.json")]) == 2
    assert "unknown event kind 'drop'" in capsys.readouterr().err
    assert not (tmp_path / "r.json").exists()


def test_event_kinds_are_those_the_cell_emits():
    emitted = set()
    # ctx.event("grasp", ...) and the kinds parts.activate(..., kind="present") is given
    pattern = re.compile(r'\.event\("(\w+)"|activate\(.*kind="(\w+)"|def activate\(.*kind: str = "(\w+)"')
    for source in (ROOT / "twin" / "physics").rglob("*.py"):
        for found in pattern.findall(source.read_text()):
            emitted |= {k for k in found if k}
    assert emitted == set(EVENT_KINDS), "update twin.report.EVENT_KINDS and twin/schemas/expect.schema.json"
    schema_kinds = load_schema("expect")["$defs"]["event_kind"]["enum"]
    assert set(schema_kinds) == set(EVENT_KINDS)


def test_the_report_schema_accepts_real_reports_and_matches_the_format(pick_three):
    _, out = pick_three
    schema = load_schema("report")
    jsonschema.Draft202012Validator.check_schema(schema)
    for path in (out / "report.json", ROOT / "tests" / "data" / "report_ok.json"):
        jsonschema.validate(json.loads(path.read_text()), schema)
    fields = set(Report.__dataclass_fields__) | {"twin_report"}
    assert set(schema["properties"]) == fields, "keep twin/schemas/report.schema.json in step with twin/report.py"
    bad = json.loads((ROOT / "tests" / "data" / "report_invalid.json").read_text())
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate(bad, schema)


def test_the_expect_schema_accepts_the_shipped_files_and_rejects_typos():
    schema = load_schema("expect")
    jsonschema.Draft202012Validator.check_schema(schema)
    for path in [SCARA_EXPECT, PICK_THREE_EXPECT, *sorted((ROOT / "scenes").glob("*.expect.toml"))]:
        jsonschema.validate(load_expect(path), schema)
    for typo in ({"events": {"drop": 0}}, {"parts": {"droped": 0}}, {"cycle_time": {"medain": {"max": 1}}},
                 {"events": {"order": ["relase"]}}):
        with pytest.raises(jsonschema.ValidationError):
            jsonschema.validate(typo, schema)


def test_seeds_run_in_parallel_and_failures_are_summarised_by_seed(tmp_path, capsys):
    strict = tmp_path / "strict.toml"
    # The feeder's jitter moves the waiting part: only some seeds leave it within 0.5 mm.
    strict.write_text("[parts]\npose = { id = 3, position = [300.0, -180.0, 860.0], tolerance_mm = 0.5 }\n")
    code = twin_main(["run", str(PICK_THREE), "--seeds", "3", "--expect", str(strict),
                      "--report", str(tmp_path / "r.json")])
    err = capsys.readouterr().err
    reports = {s: Report.load(tmp_path / f"r-seed{s}.json") for s in range(3)}
    assert [r.seed for r in reports.values()] == [0, 1, 2]
    failing = [s for s, r in reports.items() if check(r, load_expect(strict))]
    assert err.splitlines()[0] == f"twin: 3 seeds: {3 - len(failing)} passed, {len(failing)} failed"
    for s in failing:
        assert re.search(rf"^  seed {s}: part 3 is \d+\.\d mm from", err, re.M), err
    assert code == (1 if failing else 0)
    assert failing, "pick a tolerance some seed misses, so the summary is exercised"


def test_the_pytest_example_passes_and_names_a_misplaced_part(tmp_path):
    def pytest_in(folder: Path) -> subprocess.CompletedProcess:
        return subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(folder)],
                              cwd=folder, capture_output=True, text=True)

    copy = tmp_path / "examples"
    shutil.copytree(EXAMPLES, copy, ignore=shutil.ignore_patterns("__pycache__"))
    good = pytest_in(copy)
    assert good.returncode == 0, good.stdout + good.stderr
    assert "2 passed" in good.stdout
    test = copy / "test_pick_three.py"
    test.write_text(test.read_text().replace("[300.0, -180.0, 860.0]", "[300.0, -170.0, 860.0]"))
    bad = pytest_in(copy)
    assert bad.returncode == 1
    assert re.search(r"part 3 is \d+\.\d mm from \(300\.0, -170\.0, 860\.0\) mm .* expected within 2 mm", bad.stdout)
