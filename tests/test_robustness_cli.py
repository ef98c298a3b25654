"""Command-line corpus: every wrong file or argument is refused before anything is
simulated, with one line saying which and why and exit status 2; nothing the run reads is
overwritten; outputs replace only regular files; an internal error says it is one, where,
and how to report it, with exit status 3 (docs/robustness.md, "Command line")."""

from __future__ import annotations

import json
import os
import stat
import subprocess
import sys

import pytest

from conftest import SCARA_SCENE
from robustness_helpers import gpl_main, gpl_project, run_cli, vplus_file
from twin.outputs import OutputError
from twin.report import Report

PROGRAM = ".PROGRAM hello()\n    TYPE \"hello\"\n.END"


@pytest.fixture
def files(tmp_path):
    """A V+ program, a copy of the demo scene, a FIFO, a folder and a good report."""
    program = vplus_file(tmp_path, PROGRAM)
    scene = tmp_path / "cell.toml"
    scene.write_text(SCARA_SCENE.read_text())
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    folder = tmp_path / "folder"
    folder.mkdir()
    report = tmp_path / "good.json"
    assert run_cli_status(["run", program, "--report", report]) == 0
    return {"program": program, "scene": scene, "fifo": fifo, "folder": folder, "report": report,
            "tmp": tmp_path}


def run_cli_status(argv) -> int:
    from twin.cli import main

    return main([str(a) for a in argv])


# (id, arguments after `twin run PROGRAM` with {names} from `files`, text expected on stderr)
RUN_ARGUMENTS = [
    ("seed-negative", ["--seed", "-1"], "-1 is negative"),
    ("seed-not-a-number", ["--seed", "abc"], "'abc' is not an integer"),
    ("seed-fraction", ["--seed", "1.5"], "'1.5' is not an integer"),
    ("seed-empty", ["--seed", ""], "is not an integer"),
    ("max-sim-time-nan", ["--max-sim-time", "nan"], "nan is not a finite number of seconds > 0"),
    ("max-sim-time-inf", ["--max-sim-time", "inf"], "inf is not a finite number"),
    ("max-sim-time-negative", ["--max-sim-time", "-1"], "-1 is not a finite number of seconds > 0"),
    ("max-sim-time-zero", ["--max-sim-time", "0"], "0 is not a finite number of seconds > 0"),
    ("max-sim-time-word", ["--max-sim-time", "long"], "'long' is not a number of seconds"),
    ("max-wall-time-zero", ["--max-wall-time", "0"], "0 is not a finite number"),
    ("max-wall-time-nan", ["--max-wall-time", "nan"], "nan is not a finite number"),
    ("max-wall-time-negative", ["--max-wall-time", "-5"], "-5 is not a finite number"),
    ("no-progress-negative", ["--no-progress-limit", "-1"], "-1 is not a finite number"),
    ("no-progress-nan", ["--no-progress-limit", "nan"], "nan is not a finite number"),
    ("no-progress-inf", ["--no-progress-limit", "inf"], "inf is not a finite number"),
    ("unknown-option", ["--speed", "3"], "unrecognized arguments: --speed 3"),
    ("scene-folder", ["--scene", "{folder}"], "is a folder, not a file"),
    ("scene-missing", ["--scene", "{tmp}/nope.toml"], "nope.toml: no such file"),
    ("scene-fifo", ["--scene", "{fifo}"], "is a FIFO, not a file"),
    ("scene-device", ["--scene", "/dev/null"], "is a device, not a file"),
    ("report-is-the-program", ["--report", "{program}"], "is the input file"),
    ("report-is-the-scene", ["--scene", "{scene}", "--report", "{scene}"], "is the input file"),
    ("report-missing-folder", ["--report", "{tmp}/missing/r.json"], "does not exist"),
    ("report-device", ["--report", "/dev/full"], "is a device; an output must be a regular file"),
    ("report-null-device", ["--report", "/dev/null"], "is a device"),
    ("report-folder", ["--report", "{folder}"], "is a folder; an output must be a regular file"),
    ("report-trailing-slash", ["--report", "{tmp}/new/"], "names a folder, not a file"),
    ("report-fifo", ["--report", "{fifo}"], "is a FIFO; an output must be a regular file"),
    ("report-dot", ["--report", "{tmp}/.."], "names a folder"),
    ("rrd-is-the-program", ["--rrd", "{program}"], "is the input file"),
    ("rrd-missing-folder", ["--rrd", "{tmp}/missing/r.rrd"], "does not exist"),
    ("rrd-device", ["--rrd", "/dev/full"], "is a device"),
    ("rrd-same-as-report", ["--report", "{tmp}/x.out", "--rrd", "{tmp}/x.out"], "is also the report"),
    ("main-unknown", ["--main", "nosuch"], "--main nosuch: "),
]


@pytest.mark.parametrize("extra, expected", [c[1:] for c in RUN_ARGUMENTS], ids=[c[0] for c in RUN_ARGUMENTS])
def test_wrong_run_argument_exits_2_before_the_run(files, capsys, extra, expected):
    before = files["program"].read_bytes(), files["scene"].read_bytes()
    argv = [a.format(**files) for a in extra]
    result = run_cli(capsys, "run", files["program"], *argv)
    assert result.status == 2, result.err
    assert expected in result.err, result.err
    assert "Traceback" not in result.err and "twin: 0." not in result.err  # nothing was simulated
    assert (files["program"].read_bytes(), files["scene"].read_bytes()) == before
    assert stat.S_ISCHR(os.stat("/dev/full").st_mode) and stat.S_ISCHR(os.stat("/dev/null").st_mode)
    assert stat.S_ISFIFO(os.stat(files["fifo"]).st_mode)


PROGRAM_ARGUMENTS = [
    ("missing", "{tmp}/nope.pg", "no such file or folder"),
    ("folder-without-project", "{folder}", "a folder without Project.gpr is not a GPL project"),
    ("fifo", "{fifo}", "is a FIFO, not a file"),
    ("device", "/dev/null", "is a device, not a file"),
]


@pytest.mark.parametrize("program, expected", [c[1:] for c in PROGRAM_ARGUMENTS],
                         ids=[c[0] for c in PROGRAM_ARGUMENTS])
def test_wrong_program_argument_exits_2(files, capsys, program, expected):
    result = run_cli(capsys, "run", program.format(**files))
    assert result.status == 2 and expected in result.err, result.err


def test_report_may_not_replace_a_gpl_source(tmp_path, capsys):
    project = gpl_project(tmp_path, gpl_main('        Console.WriteLine("x")'))
    source = (project / "Main.gpl").read_text()
    result = run_cli(capsys, "run", project, "--report", project / "Main.gpl")
    assert result.status == 2 and "is the input file" in result.err
    assert (project / "Main.gpl").read_text() == source


def test_gpl_main_unknown_exits_2(tmp_path, capsys):
    project = gpl_project(tmp_path, gpl_main('        Console.WriteLine("x")'))
    result = run_cli(capsys, "run", project, "--main", "Nope")
    assert result.status == 2 and "--main Nope: Start procedure not found" in result.err


BROKEN_SCENES = [
    ("not-toml", "[robot\nx = 1\n", "Expected ']'"),
    ("missing-sections", '[robot]\nmodel = "x"\n', "missing (required)"),
    ("binary", "\x00\x01\x02", ""),
    ("not-utf8", "[robot]\nmodel = \"\xff\"\n", "not UTF-8 text"),
    ("empty", "", "robot: missing (required)"),
]


@pytest.mark.parametrize("text, expected", [c[1:] for c in BROKEN_SCENES], ids=[c[0] for c in BROKEN_SCENES])
def test_broken_scene_exits_2(files, capsys, text, expected):
    scene = files["tmp"] / "broken.toml"
    scene.write_bytes(text.encode("latin-1"))
    result = run_cli(capsys, "run", files["program"], "--scene", scene)
    assert result.status == 2, result.err
    assert str(scene) in result.err and expected in result.err
    assert "Traceback" not in result.err


# (id, text of the demo scene to replace, its replacement, what the message says)
WRONG_SCENE_VALUES = [
    ("speed-nan", "speed = 200.0 ", "speed = nan ", "conveyor[0].speed: expected a finite number"),
    ("speed-inf", "speed = 200.0 ", "speed = inf ", "conveyor[0].speed: expected a finite number"),
    ("zero-direction", "direction = [0.0, 1.0]", "direction = [0.0, 0.0]", "must not be the zero vector"),
    ("misspelt-section", "[conveyor]", "[convayor]", "did you mean conveyor?"),
    ("negative-pool", "pool = 120 ", "pool = -3 ", "feeder[0].pool"),
    ("zero-timestep", "timestep = 0.002 ", "timestep = 0 ", "physics.timestep"),
    ("mass-word", "mass = 0.05 ", 'mass = "heavy" ', "part[0].mass: expected a number"),
    ("missing-model", 'model = "models/robots/cobra_s600.xml"', 'model = "models/robots/nope.xml"', "not found"),
    ("broken-model", 'model = "models/robots/cobra_s600.xml"', 'model = "{broken}"', "XML parse error"),
    ("model-is-a-device", 'model = "models/robots/cobra_s600.xml"', 'model = "/dev/null"', "/dev/null"),
    ("unknown-home", 'home = "start" ', 'home = "nowhere" ', "robot.home: location 'nowhere'"),
    ("short-size", "size = [30.0, 30.0, 20.0]", "size = [30.0, 30.0]", "part[0].size"),
    ("long-location", "start = [", "start = [9000.0, ", "locations.start"),
]


@pytest.mark.parametrize("old, new, expected", [c[1:] for c in WRONG_SCENE_VALUES],
                         ids=[c[0] for c in WRONG_SCENE_VALUES])
def test_scene_with_a_wrong_value_exits_2_naming_the_key(files, capsys, old, new, expected):
    broken = files["tmp"] / "broken.xml"
    broken.write_text("<mujoco><bad")
    text = SCARA_SCENE.read_text()
    assert old in text
    scene = files["tmp"] / "wrong.toml"
    scene.write_text(text.replace(old, new.format(broken=broken), 1))
    result = run_cli(capsys, "run", files["program"], "--scene", scene)
    assert result.status == 2, result.err
    assert str(scene) in result.err and expected in result.err, result.err
    assert "Traceback" not in result.err


def test_scene_no_progress_limit_must_not_be_negative(files, capsys):
    scene = files["tmp"] / "limit.toml"
    scene.write_text(SCARA_SCENE.read_text() + "\n[controller]\nno_progress_s = -1\n")
    result = run_cli(capsys, "run", files["program"], "--scene", scene)
    assert result.status == 2 and "controller.no_progress_s" in result.err


def test_scene_with_a_wrong_value_type_exits_2(files, capsys):
    scene = files["tmp"] / "pool.toml"
    scene.write_text(SCARA_SCENE.read_text().replace("pool = 120", 'pool = "many"'))
    result = run_cli(capsys, "run", files["program"], "--scene", scene)
    assert result.status == 2 and str(scene) in result.err and "Traceback" not in result.err


def test_good_run_still_exits_0_and_writes_the_report(files, capsys):
    report = files["tmp"] / "again.json"
    result = run_cli(capsys, "run", files["program"], "--report", report, "--seed", "0",
                     "--max-sim-time", "20", "--max-wall-time", "60", "--no-progress-limit", "0")
    assert result.status == 0, result.err
    assert json.loads(report.read_text())["output"] == "hello\n"


def test_report_replaces_an_older_report(files, capsys):
    report = files["tmp"] / "old.json"
    report.write_text("old")
    assert run_cli(capsys, "run", files["program"], "--report", report).status == 0
    assert json.loads(report.read_text())["output"] == "hello\n"
    assert [p.name for p in files["tmp"].iterdir() if p.name.endswith(".tmp")] == []


def test_report_and_recording_get_the_mode_of_an_ordinary_file(files, capsys):
    report, rrd = files["tmp"] / "mode.json", files["tmp"] / "mode.rrd"
    previous = os.umask(0o022)
    try:
        assert run_cli(capsys, "run", files["program"], "--report", report, "--rrd", rrd).status == 0
    finally:
        os.umask(previous)
    assert stat.S_IMODE(report.stat().st_mode) == 0o644
    assert stat.S_IMODE(rrd.stat().st_mode) == 0o644


def test_report_write_refuses_anything_but_a_regular_file(files):
    report = Report.load(files["report"])
    with pytest.raises(OutputError):
        report.write(files["fifo"])
    with pytest.raises(OutputError):
        report.write(files["folder"])
    assert stat.S_ISFIFO(os.stat(files["fifo"]).st_mode) and files["folder"].is_dir()


def test_recording_is_renamed_into_place(files, capsys):
    rrd = files["tmp"] / "run.rrd"
    assert run_cli(capsys, "run", files["program"], "--rrd", rrd).status == 0
    assert rrd.stat().st_size > 0
    assert [p.name for p in files["tmp"].iterdir() if p.name.endswith(".tmp")] == []


def test_command_line_without_a_command_exits_2(capsys):
    assert run_cli(capsys).status == 2
    assert run_cli(capsys, "run").status == 2
    assert run_cli(capsys, "fly").status == 2


def test_help_exits_0(capsys):
    result = run_cli(capsys, "run", "--help")
    assert result.status == 0 and "--max-wall-time" in result.out and "--no-progress-limit" in result.out


def test_internal_error_is_reported_as_one_with_exit_3(files, capsys, monkeypatch):
    """A bug in twin (here: the runner breaks) is not the user's error: exit 3, the words
    'internal error', where it happened, how to report it, and no traceback on screen."""
    import twin.runner

    def broken(*args, **kwargs):
        raise RuntimeError("a bug")

    monkeypatch.setattr(twin.runner, "run_program", broken)
    result = run_cli(capsys, "run", files["program"])
    assert result.status == 3
    assert "twin: internal error: RuntimeError: a bug" in result.err
    assert "where: " in result.err and "test_robustness_cli.py" in result.err
    assert "Please report it" in result.err and "Traceback" not in result.err
    trace = result.err.split("the full trace is in ")[1].split(".txt")[0] + ".txt"
    assert "RuntimeError: a bug" in open(trace).read()
    os.unlink(trace)


# ------------------------------------------------------------------ twin check
BROKEN_EXPECTATIONS = [
    ("not-toml", "[regions\n", "not valid TOML"),
    ("binary", "\x00\xff\x00", "not UTF-8 text"),
    ("unknown-key", "[regions]\nbin = 3\n[nonsense]\nx = 1\n", "nonsense"),
    ("wrong-type", '[regions]\nbin = "many"\n', "twin check: error:"),
]


@pytest.mark.parametrize("text, expected", [c[1:] for c in BROKEN_EXPECTATIONS],
                         ids=[c[0] for c in BROKEN_EXPECTATIONS])
def test_broken_expectation_file_exits_2(files, capsys, text, expected):
    expect = files["tmp"] / "e.toml"
    expect.write_bytes(text.encode("latin-1"))
    result = run_cli(capsys, "check", files["report"], "--expect", expect)
    assert result.status == 2, result.err + result.out
    assert expected in result.err and "Traceback" not in result.err


CHECK_FILES = [
    ("report-missing", ["{tmp}/none.json", "--expect", "{expect}"], "no such file"),
    ("report-folder", ["{folder}", "--expect", "{expect}"], "is a folder, not a file"),
    ("report-fifo", ["{fifo}", "--expect", "{expect}"], "is a FIFO, not a file"),
    ("report-not-json", ["{program}", "--expect", "{expect}"], "twin check: error:"),
    ("expect-missing", ["{report}", "--expect", "{tmp}/none.toml"], "no such file"),
    ("expect-folder", ["{report}", "--expect", "{folder}"], "is a folder, not a file"),
    ("expect-device", ["{report}", "--expect", "/dev/zero"], "is a device, not a file"),
    ("junit-missing-folder", ["{report}", "--expect", "{expect}", "--junit", "{tmp}/no/j.xml"], "does not exist"),
    ("junit-is-the-report", ["{report}", "--expect", "{expect}", "--junit", "{report}"], "is the input file"),
    ("junit-device", ["{report}", "--expect", "{expect}", "--junit", "/dev/full"], "is a device"),
    ("no-expect", ["{report}"], "--expect"),
]


@pytest.mark.parametrize("argv, expected", [c[1:] for c in CHECK_FILES], ids=[c[0] for c in CHECK_FILES])
def test_wrong_check_file_exits_2(files, capsys, argv, expected):
    expect = files["tmp"] / "ok.toml"
    expect.write_text("[regions]\n")
    before = files["report"].read_bytes()
    result = run_cli(capsys, "check", *[a.format(expect=expect, **files) for a in argv])
    assert result.status == 2, result.err + result.out
    assert expected in result.err, result.err
    assert files["report"].read_bytes() == before


# ------------------------------------------------------------------ end to end, in a real process
def _twin(*argv, timeout=60):
    return subprocess.run([sys.executable, "-m", "twin.cli", *map(str, argv)], capture_output=True,
                          text=True, timeout=timeout, env={**os.environ, "MUJOCO_GL": "egl"})


def test_subprocess_wrong_arguments_exit_2(files):
    done = _twin("run", files["program"], "--seed", "-1")
    assert done.returncode == 2 and "Traceback" not in done.stderr
    done = _twin("run", files["program"], "--report", "/dev/full")
    assert done.returncode == 2 and "is a device" in done.stderr
    assert stat.S_ISCHR(os.stat("/dev/full").st_mode)


def test_subprocess_deadlock_exits_1_with_the_report(files):
    program = vplus_file(files["tmp"], ".PROGRAM w()\n    WAIT SIG(1001)\n.END", name="w.pg")
    report = files["tmp"] / "w.json"
    done = _twin("run", program, "--report", report)
    assert done.returncode == 1 and "*Deadlock*" in done.stderr and "WAIT SIG(1001)" in done.stderr
    assert json.loads(report.read_text())["errors"][0]["code"] == -1030
