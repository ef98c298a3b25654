"""The whole pipeline on the demo cell: move.parts from the eV+ guide, unchanged.

V+ program -> interpreter -> virtual controller (IK, toppra) -> MuJoCo cell -> report ->
twin check. One full 100-part run (about 7 s of wall time) is shared by the tests here.
"""

from __future__ import annotations

import statistics

import pytest

from twin.check import main_check
from twin.cli import main as twin_main
from twin.runner import run_program

from conftest import ROOT, twin_run
from conftest import SCARA_EXPECT as EXPECT
from conftest import SCARA_SCENE as SCENE

PROGRAM = ROOT / "programs" / "vplus" / "move_parts.pg"


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    return twin_run(PROGRAM, tmp_path_factory.mktemp("demo"))


def test_program_ends_normally_with_the_manuals_output(demo):
    code, report, _ = demo
    assert code == 0
    assert report["errors"] == []
    assert report["output"] == "All done. 100 parts processed\n"


def test_every_part_lands_in_the_bin_and_none_is_dropped(demo):
    _, report, _ = demo
    assert report["regions"]["bin"] == 100
    assert not [p for p in report["parts"] if p["dropped"]]
    # The feeder presents the 101st part when the 100th leaves the nest; it stays there.
    assert [p["region"] for p in report["parts"] if p["region"] != "bin"] == ["nest"]
    assert not [e for e in report["events"] if e["kind"] in ("slip", "dropped")]


def test_cycle_time_is_that_of_a_cobra_class_scara(demo):
    _, report, _ = demo
    cycles = report["cycle_times_s"]
    assert len(cycles) == 99
    # Monitor speed 50 % (the controller's start-up value), HAND.TIME 0.16 s twice a cycle.
    assert 1.0 < statistics.median(cycles) < 3.0
    assert max(cycles) - min(cycles) < 0.05  # the same motion every cycle


def test_check_passes_and_fails_when_an_expectation_is_false(demo, tmp_path, capsys):
    _, _, report_path = demo
    assert main_check([str(report_path), "--expect", str(EXPECT)]) == 0
    wrong = tmp_path / "wrong.toml"
    wrong.write_text(EXPECT.read_text().replace("bin = 100", "bin = 99"))
    assert main_check([str(report_path), "--expect", str(wrong)]) == 1
    assert "bin" in capsys.readouterr().out


SHORT = """.PROGRAM three()
    PARAMETER HAND.TIME = 0.16
    OPEN
    MOVE start
    FOR i = 1 TO 3
        APPRO pick, 25.4
        MOVES pick
        CLOSEI
        DEPARTS 25.4
        APPRO place, 50.8
        MOVES place
        OPENI
        DEPARTS 50.8
    END
    TYPE /I0, i-1, " parts"
.END
"""


def test_same_program_and_seed_give_the_same_result_bit_for_bit(tmp_path):
    program = tmp_path / "three.pg"
    program.write_text(SHORT)
    a = run_program(program, scene=SCENE).report
    b = run_program(program, scene=SCENE).report
    assert a.output == "3 parts\n"
    assert a.parts == b.parts and a.events == b.events and a.sim_time_s == b.sim_time_s
    assert a.regions["bin"] == 3


def test_unreachable_location_stops_the_program_with_the_v_plus_error(tmp_path, capsys):
    program = tmp_path / "far.pg"
    program.write_text(".PROGRAM far()\n    MOVE TRANS(900, 0, 200, 0, 180, 0)\n.END\n")
    code = twin_main(["run", str(program), "--scene", str(SCENE)])
    assert code == 1
    err = capsys.readouterr().err
    assert "*Location out of range*" in err
    assert "far.pg:2" in err
