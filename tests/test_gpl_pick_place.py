"""The GPL pick-and-place project end to end: `twin run programs/gpl/pick_place` on
scenes/scara_pick.toml, checked with the eV+ demo's expectations
(scenes/scara_pick.expect.toml), plus small GPL projects that drive the robot
through the interpreter and the library."""

from __future__ import annotations

import statistics
from pathlib import Path

import pytest

from twin.check import main_check
from twin.runner import run_program

from conftest import ROOT, twin_run
from conftest import SCARA_EXPECT as EXPECT
from conftest import SCARA_SCENE as SCENE
from gpl_helpers import main_project

PROJECT = ROOT / "programs" / "gpl" / "pick_place"


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    return twin_run(PROJECT, tmp_path_factory.mktemp("gpl_pick_place"))


def test_project_ends_normally_with_the_demos_output(run):
    code, report, _ = run
    assert code == 0
    assert report["errors"] == []
    assert report["output"] == "All done. 100 parts processed\n"


def test_every_part_is_placed_like_the_evplus_demo(run):
    """The same outcome as programs/vplus/move_parts.pg (tests/test_demo_run.py): 100 parts
    in the bin, none dropped, the 101st waiting in the nest."""
    _, report, _ = run
    assert report["regions"]["bin"] == 100
    assert not [p for p in report["parts"] if p["dropped"]]
    assert [p["region"] for p in report["parts"] if p["region"] != "bin"] == ["nest"]
    assert not [e for e in report["events"] if e["kind"] in ("slip", "dropped")]
    assert statistics.median(report["cycle_times_s"]) < 3.0


def test_report_passes_twin_check_with_the_demos_expectations(run):
    _, _, report_path = run
    assert main_check([str(report_path), "--expect", str(EXPECT)]) == 0


# ------------------------------------------------------------ small projects
def _run(tmp_path: Path, body: str, max_sim_time: float = 30.0):
    result = run_program(main_project(tmp_path, body), scene=SCENE, max_sim_time=max_sim_time)
    return result.report


def test_motion_without_power_stops_the_thread_with_the_gpl_error(tmp_path):
    """Manual L1954: a motion needs high power; the uncaught error names the statement."""
    report = _run(tmp_path, """
        Dim here As New Location
        Dim pf As New Profile
        here.XYZ(300, 0, 300, 0, 180, 180)
        Move.Loc(here, pf)
""")
    assert len(report.errors) == 1
    error = report.errors[0]
    assert error["code"] == -1046
    assert error["line"] == 7  # Main.gpl: module, Sub, blank line, then the four statements


def test_try_catch_retries_a_motion_error(tmp_path):
    """The manual's retry pattern (L1719-1736, E23) on a twin error: an unreachable
    location raises -1033, the Catch block fixes the destination and jumps back."""
    report = _run(tmp_path, """
        Dim loc1 As New Location
        Dim profile1 As New Profile
        Dim exc As Exception
        Controller.PowerEnabled = True
        Robot.Attached = 1
        Robot.Home
        loc1.XYZ(900, 0, 250, 0, 180, 180)
        Try
retry:
            Move.Loc(loc1, profile1)
            Move.WaitForEOM
        Catch exc
            Console.WriteLine("Error " & CStr(exc.ErrorCode))
            loc1.X = loc1.X - 200
            GoTo retry
        End Try
        Console.WriteLine("At X = " & CStr(CInt(Robot.Where.X)))
""")
    assert report.errors == []
    assert report.output == "Error -1033\nError -1033\nAt X = 500\n"


def test_pallet_frame_drives_the_robot_through_a_grid(tmp_path):
    """A pallet RefFrame (L2048-2072) with a location on it: the robot visits the 2 x 2
    grid in row order, and Robot.Where follows."""
    report = _run(tmp_path, """
        Dim pallet As New RefFrame
        Dim slot As New Location
        Dim pf As New Profile
        Dim ii As Integer
        Controller.PowerEnabled = True
        Robot.Attached = 1
        Robot.Home
        pallet.Type = 1
        pallet.Loc.XYZ(300, -100, 250, 0, 180, 180)
        pallet.PalletMaxIndex(1) = 2
        pallet.PalletMaxIndex(2) = 2
        pallet.PalletPitch(1) = 40
        pallet.PalletPitch(2) = 30
        pf.InRange = 1
        slot.RefFrame = pallet
        For ii = 1 To 4
            Move.Loc(slot, pf)
            Move.WaitForEOM
            Console.WriteLine(CStr(CInt(Robot.Where.X)) & "," & CStr(CInt(Robot.Where.Y)))
            pallet.PalletNextPos
        Next ii
""")
    assert report.errors == []
    # Loc's rotation Ry(180) Rz(180) is diag(1, -1, -1): rows go along +X, columns along -Y.
    assert report.output.splitlines() == ["300,-100", "340,-100", "300,-130", "340,-130"]


def test_cycle_matches_the_evplus_demo_motion_for_motion():
    """The GPL project moves like move_parts.pg: the same points, approach heights, speeds
    and hand times, so the first put-downs come at the same simulated times."""
    vplus = run_program(ROOT / "programs" / "vplus" / "move_parts.pg", scene=SCENE, max_sim_time=8.0).report
    gpl = run_program(PROJECT, scene=SCENE, max_sim_time=8.0).report

    def times(report, kind):
        return [round(e["time"], 3) for e in report.events if e["kind"] == kind]

    assert len(times(gpl, "release")) >= 3
    assert times(gpl, "grasp") == times(vplus, "grasp")
    assert times(gpl, "release") == times(vplus, "release")
