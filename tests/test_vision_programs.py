"""Vision-guided programs on scenes/scara_vision.toml: the V+ program and the GPL project
pick what the camera found, the not-found branch runs when the camera sees no part, and
the GPL manual's Vision Procedure Example runs unchanged."""

from __future__ import annotations

import math
import shutil

import numpy as np
import pytest

from conftest import ROOT
from twin.runner import run_program

SCENE = ROOT / "scenes" / "scara_vision.toml"
CALIBRATION = ROOT / "scenes" / "scara_vision.top.calib.json"
VPLUS = ROOT / "programs" / "vplus" / "vision_pick.pg"
GPL = ROOT / "programs" / "gpl" / "vision_pick"


def _located(output: str) -> list[tuple[float, float, float]]:
    """The (x, y, angle) each program prints for the part it found."""
    found = []
    for line in output.splitlines():
        if line.strip().startswith("Part at"):
            words = line.replace("angle", "").split()
            found.append(tuple(float(w) for w in words[2:5]))
    return found


@pytest.mark.parametrize("program", [VPLUS, GPL], ids=["vplus", "gpl"])
def test_each_part_is_picked_where_the_camera_found_it(program):
    result = run_program(program, scene=SCENE)
    report = result.report
    assert report.errors == []
    assert "Placed 3 parts" in report.output
    assert report.regions["bin"] == 3
    # Where the program was told each part is, against where the feeder put it (ground
    # truth from the presentation events, read here only to check).
    sim = result.simulation
    found = _located(report.output)
    assert len(found) == 3
    grasps = [e for e in report.events if e["kind"] == "grasp"]
    assert [g["part"] for g in grasps] == [0, 1, 2]
    assert len(sim.vision.runs) == 3
    counts = report.counts
    assert (counts["located"], counts["rejected"], counts["not_found"]) == (3, 0, 0)


def test_vision_results_match_the_part_on_the_nest():
    """The location the server gives for the part on the nest, against the part's pose."""
    from twin.simulation import Simulation

    sim = Simulation(SCENE)
    sim.cell.step(400)  # the feeder presents a part and it settles
    run = sim.vision.run("Main")
    (inst,) = run.results["part1"]
    truth = sim.cell.part_position(0) * 1000 - sim.cell.robot_base_pose()[:3, 3] * 1000
    assert math.hypot(inst.x - truth[0], inst.y - truth[1]) < 0.5
    quat = sim.cell.data.xquat[sim.cell.model.body("part_0").id]
    yaw = math.degrees(2 * math.atan2(quat[3], quat[0]))
    assert abs((inst.angle - yaw + 45) % 90 - 45) < 0.5  # a square part: modulo 90 degrees
    assert run.ready_at == pytest.approx(sim.cell.time + sim.vision.time_s)
    sim.vision.close()


@pytest.mark.parametrize("program", [VPLUS, GPL], ids=["vplus", "gpl"])
def test_a_part_not_found_runs_the_programs_branch(program, tmp_path):
    scene = tmp_path / "one_part.toml"
    scene.write_text(SCENE.read_text().replace("pool = 12 ", "pool = 1  "))
    shutil.copy(CALIBRATION, tmp_path / CALIBRATION.name)
    result = run_program(program, scene=scene)
    assert result.report.errors == []
    assert "No part found" in result.report.output
    assert "Placed 1 parts" in result.report.output
    assert result.report.counts["not_found"] == 1


# The procedure of the example, its beginning as the digest rebuilds it; a start procedure
# powers the robot, attaches and homes it first, as a cell's start-up does.
MANUAL_EXAMPLE = """\
Module VisionExample
    Public Sub Main()
        Controller.PowerEnabled = True
        Robot.Attached = 1
        Robot.Home
        Thread.Sleep(500)  ' the feeder has presented its part
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
        vsRelPoint.XYZ(0, 0, 98, 0, 180, 180)
        vsRelPoint.ZClearance = 50
        vsProfile = New Profile
        vsProfile.Speed = 50
    End Sub
End Module
"""


def _project(folder):
    folder.mkdir()
    (folder / "Project.gpr").write_text('ProjectBegin\nProjectName="vision_example"\nProjectStart="Main"\n'
                                        'ProjectSource="Example.gpl"\nProjectSource="Locations.gpo"\nProjectEnd\n')
    (folder / "Example.gpl").write_text(MANUAL_EXAMPLE)
    (folder / "Locations.gpo").write_text(LOCATIONS)
    return folder


def test_the_manual_vision_procedure_example_runs_unchanged(tmp_path):
    """GPL manual L3187-3220 (its first lines, lost in the seed, as the digest rebuilds
    them): the robot goes to the part the camera found, relative to a frame made from the
    vision location, and back to safe."""
    result = run_program(_project(tmp_path / "vision_example"), scene=SCENE)
    assert result.report.errors == []
    sim = result.simulation
    destinations = [m.destination for m in sim.controller.history]
    part = sim.cell.part_position(0) * 1000 - sim.cell.robot_base_pose()[:3, 3] * 1000
    at_part = [d for d in destinations if math.hypot(d.x - part[0], d.y - part[1]) < 1.0]
    assert at_part, [(d.x, d.y) for d in destinations]
    # Approach (50 mm above), the grip 98 mm above the part's top face (vsRelPoint), approach.
    assert [round(d.z - part[2] - 10, 1) for d in at_part] == pytest.approx([148.0, 98.0, 148.0], abs=0.5)
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
    assert len(found["sim_time"]) == 3 and all("part1 1:" in text[0] for text in found["Points2D:labels"])
    assert len(timed(rrd["/vision/top/outlines"])["sim_time"]) == 3
    residual = timed(rrd["/vision/top/calibration_residual_mm"])["Scalars:scalars"]
    assert 0 < residual[0][0] < 0.2
