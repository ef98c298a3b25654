"""The HERE instruction on the cell: HERE loc, HERE #p and HERE frame:loc
(V+ guide v17, "Relative Transformations", L6140-6154, and L6283-6289)."""

from __future__ import annotations

import pytest

from test_motion_controller import run_on_cell
from twin.controller.location import Location


def test_here_frame_loc_records_the_location_relative_to_the_frame():
    """The guide's example, with loc_a lowered into the Cobra's reach: after
    MOVE loc_a:TRANS(-50, 20, 30), HERE loc_a:loc_b gives loc_b = -50, 20, 30, 0, 0, 0
    and SET loc_c = loc_a:loc_b is where the robot is."""
    text = """.PROGRAM rel()
    MOVE loc_a:TRANS(-50, 20, 30)
    BREAK
    HERE loc_a:loc_b
    BREAK
    SET loc_c = loc_a:loc_b
    HERE now
    HERE #joints
.END
"""
    loc_a = Location(300.0, 50.0, 280.0, 0.0, 180.0, 0.0)
    sim, task, outcome, _ = run_on_cell(text, locations={"loc_a": loc_a})
    assert outcome.errors == []
    g = task.globals
    assert g["loc_b"].components() == pytest.approx((-50, 20, 30, 0, 0, 0), abs=0.05)
    assert g["loc_c"].position() == pytest.approx((350, 70, 250), abs=0.05)
    assert g["now"].position() == pytest.approx(g["loc_c"].position(), abs=0.05)
    # HERE #p records joint values (degrees, mm); the servos settle on after the program ends.
    assert g["#joints"] == pytest.approx(sim.controller.to_user_joints(sim.cell.robot_qpos()), abs=0.01)


def test_here_frame_chain_compounds_the_frames():
    """HERE a:b:c records c relative to a:b (L6287)."""
    text = """.PROGRAM chain()
    SET b = TRANS(10, 0, 0)
    MOVE a:b:TRANS(0, 0, 20)
    BREAK
    HERE a:b:c
.END
"""
    a = Location(320.0, 0.0, 280.0, 0.0, 180.0, 0.0)
    _, task, outcome, _ = run_on_cell(text, locations={"a": a})
    assert outcome.errors == []
    assert task.globals["c"].components() == pytest.approx((0, 0, 20, 0, 0, 0), abs=0.05)
