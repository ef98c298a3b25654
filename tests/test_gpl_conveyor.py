"""GPL conveyor tracking (User Manual ch. 12, "Conveyor Reference Frame", "Latch Class")
on the SCARA demo cell given a belt along the robot's +Y (tests/belt_helpers.py): a
photo-eye latch sets the conveyor RefFrame's offset, a Location on that frame moves
with the belt, and Move.Loc follows it."""

from __future__ import annotations

import io

import numpy as np
import pytest
from belt_helpers import ClockConveyor, ClockEncoder, on_cell
from test_motion_controller import SCARA
from test_vplus_conveyor import _Rows

from twin.controller.location import Location
from twin.language.gpl.runtime import GplSystem
from twin.language.vplus.runtime import Console
from twin.simulation import Simulation

SPEED = 100.0  # mm/s
COUNTS_PER_MM = 20.0
LATCH_S = 0.3
# The belt's top face: centre at robot (300, 0, 100) mm (the base is 750 mm above the
# world origin), X along the robot's +Y.
FRAME_WORLD = np.array([[0.0, -1.0, 0.0, 0.300],
                        [1.0, 0.0, 0.0, 0.0],
                        [0.0, 0.0, 1.0, 0.850],
                        [0.0, 0.0, 0.0, 1.0]])
NOMINAL = Location(300.0, 0.0, 100.0, 90.0, 0.0, 0.0)  # the same frame, robot frame, mm

SETUP = """
        Dim belt As New RefFrame
        Dim part As New Location
        Dim pf As New Profile
        Dim lt As Latch
        Controller.PowerEnabled = True
        Robot.Attached = 1
        Robot.Home
        belt.Type = 2
        belt.ConveyorRobot = 2
        While Latch.Count(2) = 0
            Thread.Sleep(10)
        End While
        lt = Latch.Result(2)
        belt.ConveyorOffset = lt.Angle(1)
        part.RefFrame = belt
        part.XYZ(-150, 0, 130, 0, 180, 0)
        pf.Straight = True
"""


def run_gpl_belt(body: str, max_time: float = 10.0):
    sim = Simulation(SCARA)
    encoder = ClockEncoder(sim.cell, 1, COUNTS_PER_MM, SPEED, latch_times=(LATCH_S,))
    on_cell(sim.cell, {"infeed": ClockConveyor(FRAME_WORLD, encoder)})
    probe = _Rows(sim)
    sim.recorder = probe
    console = Console(stdin=io.StringIO(""), echo=None)
    system = GplSystem(sim.controller, sim.io, sim.clock, sim.scheduler, console)
    system.load_text("Module Test\n    Public Sub Main()\n" + SETUP + body + "    End Sub\nEnd Module\n", "Test.gpl")
    thread = system.start("Main")
    sim.scheduler.add(thread)
    outcome = sim.run(max_sim_time=max_time)
    return sim, outcome, probe.rows, console.output


def _part_flange(travel_mm: float) -> np.ndarray:
    """Where the part's flange target is after the belt moved `travel_mm` since the latch."""
    return (NOMINAL * Location(travel_mm - 150.0, 0.0, 130.0, 0.0, 180.0, 0.0)).position()


def test_move_loc_to_a_location_on_a_conveyor_frame_follows_the_belt():
    sim, outcome, rows, out = run_gpl_belt("""
        Move.Loc(part, pf)
        Move.WaitForEOM
        Thread.Sleep(1500)
        Console.WriteLine(CStr(Robot.Where.Y - part.Pos.Y))
""")
    assert outcome.errors == []
    assert abs(float(out.strip())) < 0.5  # Robot.Where is on the part, which moves
    errors = [np.linalg.norm(sim.kinematics.fk(q)[:3, 3] * 1e3 - _part_flange(SPEED * (t - LATCH_S)))
              for t, q, following in rows if following]
    assert len(errors) > 80 and max(errors) < 0.5


def test_conveyor_frame_members_and_conveyor_limit():
    _, outcome, _, out = run_gpl_belt("""
        Console.WriteLine(CStr(belt.Type) & " " & CStr(belt.ConveyorRobot) & " " & CStr(belt.ConveyorOffset))
        Console.WriteLine(CStr(CInt(belt.PosWrtRef.X)) & " " & CStr(CInt(belt.PosWrtRef.Yaw + belt.PosWrtRef.Roll)))
        Console.WriteLine(CStr(CInt(part.ConveyorLimit(0))) & " " & CStr(CInt(part.ConveyorLimit(1))))
""")
    assert outcome.errors == []
    lines = out.splitlines()
    assert lines[0] == f"2 2 {LATCH_S * SPEED:g}"  # offset: the belt position (mm) at the latch
    assert lines[1] == "300 90"
    downstream, upstream = (int(v) for v in lines[2].split())
    assert downstream > 0 and upstream > 0  # the part is within the reachable stretch
    # The two distances add up to the reachable stretch's length, about the Cobra's reach each way.
    assert 900 < downstream + upstream < 1200


def test_latch_queue_members():
    _, outcome, _, out = run_gpl_belt("""
        Console.WriteLine(CStr(Latch.Count(2)) & " " & CStr(lt.Signal) & " " & CStr(lt.Timestamp))
        Console.WriteLine(CStr(Latch.Count(1)))
        If Latch.Result(2) Is Nothing Then
            Console.WriteLine("empty")
        End If
""")
    assert outcome.errors == []
    assert out.splitlines() == [f"0 1001 {LATCH_S:g}", "0", "empty"]


def test_a_part_carried_past_the_conveyor_limit_is_an_error():
    _, outcome, _, _ = run_gpl_belt("""
        Move.Loc(part, pf)
        Move.WaitForEOM
        Thread.Sleep(20000)
""", max_time=30.0)
    (error,) = outcome.errors
    assert error["code"] == -1053


def test_a_joint_motion_to_a_conveyor_location_is_an_error():
    _, outcome, _, _ = run_gpl_belt("""
        pf.Straight = False
        Move.Loc(part, pf)
""")
    assert outcome.errors[0]["code"] == -1011


def test_conveyor_robot_must_be_a_belt():
    sim, outcome, _, _ = run_gpl_belt("""
        belt.ConveyorRobot = 5
""")
    assert outcome.errors[0]["code"] == -1000
