"""Vision-guided programs on scenes/scara_vision.toml: the V+ program and the GPL project
place every plate in order in the tray within 1 mm and 1 degree of its cell, put wrong and
upside-down parts in the reject bin, and run their not-found branch when a part is hidden
from the camera; the GPL manual's Vision Procedure Example runs unchanged.
(bench/vision.py runs the 20 seeded layouts.)"""

from __future__ import annotations

import math
import shutil

import pytest

from conftest import ROOT
from twin.runner import run_program
from twin.vision.check import check_vision_run

SCENE = ROOT / "scenes" / "scara_vision.toml"
CALIBRATION = ROOT / "scenes" / "scara_vision.top.calib.json"
VPLUS = ROOT / "programs" / "vplus" / "vision_pick.pg"
GPL = ROOT / "programs" / "gpl" / "vision_pick"


@pytest.mark.parametrize("program, seed", [(VPLUS, 1), (GPL, 3)], ids=["vplus", "gpl"])
def test_plates_in_order_in_the_tray_and_wrong_parts_rejected(program, seed):
    result = run_program(program, scene=SCENE, seed=seed)
    report = result.report
    assert report.errors == []
    outcome = check_vision_run(result)
    assert outcome.failures == [], outcome.failures
    assert outcome.plates >= 1 and outcome.worst_mm < 1.0 and outcome.worst_deg < 1.0
    assert report.counts["located"] == outcome.plates
    assert report.counts["rejected"] == outcome.wrong
    assert report.counts["not_found"] == 0
    assert f"Placed {outcome.plates} parts, rejected {outcome.wrong}" in report.output


def _hidden_scene(tmp_path):
    """The cell with one of the job's five parts on a second mat, out of the camera's view."""
    text = SCENE.read_text().replace("count = 5\n", "count = 4\n", 1)
    text += """
[[scatter]]
name = "hidden"
parts = ["plate"]
count = 1
area = [300.0, 20.0, 300.1, 20.1]
mat = [270.0, -10.0, 330.0, 50.0]
mat_height = 100.0
"""
    scene = tmp_path / "hidden.toml"
    scene.write_text(text)
    shutil.copy(CALIBRATION, tmp_path / CALIBRATION.name)
    return scene


@pytest.mark.parametrize("program", [VPLUS, GPL], ids=["vplus", "gpl"])
def test_a_part_hidden_from_the_camera_runs_the_not_found_branch(program, tmp_path):
    result = run_program(program, scene=_hidden_scene(tmp_path))
    report = result.report
    assert report.errors == []
    assert "Part 5 not found" in report.output
    assert report.counts["not_found"] == 1
    hidden = [p for p in report.parts if p["region"] == "hidden"]
    assert len(hidden) == 1 and not hidden[0]["picked"]


def test_vision_results_match_the_parts_on_the_mat():
    """The server's results against the scattered parts' poses (ground truth, read here only)."""
    from twin.simulation import Simulation

    sim = Simulation(SCENE)
    sim.cell.step(200)
    run = sim.vision.run("Main")
    layout = next(c for c in sim.cell.components if c.section == "scatter").layout
    plates = [p for p in layout if p["type"] == "plate" and not p["upside_down"]]
    found = [i for i in run.results["inspect"] if i.passed]
    assert len(found) == len(plates)
    for p in plates:
        f = min(found, key=lambda i: math.hypot(i.x - p["x"], i.y - p["y"]))
        assert math.hypot(f.x - p["x"], f.y - p["y"]) < 0.5
        assert abs((f.angle - p["yaw"] + 180) % 360 - 180) < 0.5
    assert run.ready_at == pytest.approx(sim.cell.time + sim.vision.time_s)
    sim.vision.close()


# The procedure of the example, its beginning as the digest rebuilds it; a start procedure
# powers the robot, attaches and homes it first, as a cell's start-up does.
MANUAL_EXAMPLE = """\
Module VisionExample
    Public Sub Main()
        Controller.PowerEnabled = True
        Robot.Attached = 1
        Robot.Home
        Thread.Sleep(200)  ' the parts are on the mat
        VisionProcedure()
    End Sub

    Public Sub VisionProcedure()
        Dim vis As New Vision
        Dim vResult As VisResult
        Move.Loc(safe, vsProfile)
        vis.Process("Main")
        If vis.ResultCount("part1") < 1 Then
            GoTo done
        End If
        vResult = vis.Result("part1", 1) ' Get results
        ' Create a reference frame object and set it
        ' equal to the returned vision location
        Dim vsRefFrame As New RefFrame
        vsRefFrame.Loc.PosWrtRef = vResult.Loc
        ' Pickup point is relative to new frame
        vsRelPoint.RefFrame = vsRefFrame
        Move.Approach(vsRelPoint, vsProfile)
        Move.Loc(vsRelPoint, vsProfile)
        Move.Approach(vsRelPoint, vsProfile)
        ' Move back to safe location
        Move.Loc(safe, vsProfile)
done:
    End Sub
End Module
"""
LOCATIONS = """\
Module Locations
    Public safe As Location
    Public vsRelPoint As Location
    Public vsProfile As Profile
    Public Sub Init()
        safe = New Location
        safe.XYZ(150, 350, 300, 0, 180, 180)
        vsRelPoint = New Location
        vsRelPoint.XYZ(0, 0, 107.5, 90, 180, 180)
        vsRelPoint.ZClearance = 50
        vsProfile = New Profile
        vsProfile.Speed = 50
    End Sub
End Module
"""


def test_the_manual_vision_procedure_example_runs_unchanged(tmp_path):
    """GPL manual L3187-3220 (its first lines, lost in the seed, as the digest rebuilds
    them): the robot goes to the part the camera found, relative to a frame made from the
    vision location, and back to safe."""
    folder = tmp_path / "vision_example"
    folder.mkdir()
    (folder / "Project.gpr").write_text('ProjectBegin\nProjectName="vision_example"\nProjectStart="Main"\n'
                                        'ProjectSource="Example.gpl"\nProjectSource="Locations.gpo"\nProjectEnd\n')
    (folder / "Example.gpl").write_text(MANUAL_EXAMPLE)
    (folder / "Locations.gpo").write_text(LOCATIONS)
    result = run_program(folder, scene=SCENE)
    assert result.report.errors == []
    sim = result.simulation
    first = sim.vision.runs[0].results["part1"][0]
    destinations = [m.destination for m in sim.controller.history]
    at_part = [d for d in destinations if math.hypot(d.x - first.x, d.y - first.y) < 1e-3]
    # Approach (50 mm above), the grip 107.5 mm above the part's top face (vsRelPoint), approach.
    assert [round(d.z - first.z, 1) for d in at_part] == [157.5, 107.5, 157.5]
    assert math.hypot(destinations[-1].x - 150, destinations[-1].y - 350) < 1e-6  # back at safe


def test_pictures_and_found_poses_are_recorded_at_their_times(tmp_path):
    from test_recorder import read_rrd, timed

    path = tmp_path / "vision.rrd"
    result = run_program(VPLUS, scene=SCENE, rrd_path=path)
    rrd = read_rrd(path)
    taken = [run.image.time for run in result.simulation.vision.runs]
    images = timed(rrd["/vision/top"])
    assert [t * 1e-9 for t in images["sim_time"]] == pytest.approx(taken, abs=1e-9)
    found = timed(rrd["/vision/top/found"])
    assert len(found["sim_time"]) == len(taken)
    assert any(label.startswith("inspect ") and label.endswith(" pass") for label in found["Points2D:labels"][0])
    residual = timed(rrd["/vision/top/calibration_residual_mm"])["Scalars:scalars"]
    assert 0 < residual[0][0] < 0.2
