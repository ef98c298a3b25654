"""SOLVE.ANGLES, SOLVE.TRANS, SOLVE.FLAGS, HAND, STATE, HOUR.METER and CALIBRATE on the
SCARA cell (twin/language/vplus/keywords/solve.py; docs/motion.md, "Kinematics keywords").

The guides list these keywords only (V+ guide v17 L6781, L6859, L6871, L7044-7052, L7059;
eV+ guide L2756, L2849-2851); the forms are the V+ Language Reference's."""

from __future__ import annotations

import numpy as np
import pytest

from test_motion_controller import _program, run_on_cell
from twin.language.vplus.messages import LOCATION_OUT_OF_RANGE


def _run(*lines):
    sim, task, outcome, _ = run_on_cell(_program(*lines))
    assert outcome.errors == []
    return sim, task.globals


def _joints(array) -> list[float]:
    return [array[i] for i in range(len(array))]


SOLVE = ("DECOMPOSE j[] = #PHERE", "j[0] = j[0]+10", "j[1] = j[1]+15",
         "SOLVE.TRANS t1, e1 = j[]",
         "f0 = SOLVE.FLAGS(j[])",
         "SOLVE.ANGLES k[], f, e2 = t1, j[], f0",
         "SOLVE.TRANS t2 = k[]")


def test_solve_trans_and_solve_angles_round_trip():
    """SOLVE.TRANS (L7051: "the transformation equivalent to a given set of joint
    positions") and SOLVE.ANGLES (L7044: "the robot joint positions ... equivalent to a
    specified transformation") undo each other: the joints come back, and their
    transformation agrees within 0.01 mm; SOLVE.FLAGS (L7048) gives CONFIG's bits."""
    sim, g = _run(*SOLVE)
    assert g["e1"] == 0.0 and g["e2"] == 0.0
    assert np.allclose(_joints(g["k[]"]), _joints(g["j[]"]), atol=1e-6)
    assert np.linalg.norm(g["t2"].position() - g["t1"].position()) < 0.01
    assert g["f0"] == g["f"] == 1.0  # RIGHTY, as the robot starts
    expected = sim.controller.location_of_joints(_joints(g["j[]"]))
    assert np.linalg.norm(g["t1"].position() - expected.position()) < 0.01


def test_solve_angles_takes_the_configuration_the_flags_ask_for():
    """i.flags 0 asks for LEFTY: other joints, the same transformation (L7044-7048)."""
    _, g = _run(*SOLVE, "SOLVE.ANGLES m[], g, e3 = t1, j[], 0", "SOLVE.TRANS t3 = m[]",
                "f3 = SOLVE.FLAGS(m[])")
    assert g["e3"] == 0.0 and g["g"] == g["f3"] == 0.0
    assert not np.allclose(_joints(g["m[]"]), _joints(g["j[]"]), atol=1.0)
    assert np.linalg.norm(g["t3"].position() - g["t1"].position()) < 0.01


def test_solve_angles_out_of_reach_sets_the_error_and_leaves_the_outputs():
    """A transformation the arm cannot reach: error is the code a motion there would stop
    with, *Location out of range* (-610); o.jts[] and o.flags are not written."""
    _, g = _run(*SOLVE, "SET far = SHIFT(t1 BY 5000, 0, 0)", "n[0] = 7", "h = 3",
                "SOLVE.ANGLES n[], h, e4 = far, j[], 1")
    assert g["e4"] == float(LOCATION_OUT_OF_RANGE) == -610.0
    assert dict(g["n[]"]) == {0: 7.0} and g["h"] == 3.0


def test_hand_state_hour_meter_and_calibrate():
    """HAND (L6400, L6859: "the current state of the gripper"), STATE (L7059: "information
    about the robot system state"), HOUR.METER (L6871) and CALIBRATE (L6781: the twin's
    robot is always calibrated, so a no-op)."""
    sim, g = _run("a = HAND()", "s1 = STATE(1)", "s2 = STATE(2)", "CALIBRATE",
                  "MOVE start", "s3 = STATE(2)", "BREAK", "s4 = STATE(2)",
                  "CLOSEI", "b = HAND(1)", "RELAXI", "c = HAND()", "hm = HOUR.METER")
    assert (g["a"], g["b"], g["c"]) == (1.0, 0.0, -1.0)
    assert (g["s1"], g["s2"], g["s3"], g["s4"]) == (7.0, 0.0, 1.0, 2.0)
    assert 0.0 < g["hm"] <= sim.controller.cell.time / 3600.0


def test_solve_angles_needs_its_arrays():
    """o.jts and i.jts are arrays (Reference: "Real-valued array"): a plain value is
    refused when the program is loaded."""
    with pytest.raises(Exception, match="needs an array"):
        run_on_cell(_program("SOLVE.ANGLES k[], f, e = HERE, 5, 0"))
