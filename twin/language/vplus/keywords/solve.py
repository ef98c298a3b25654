"""Kinematics and robot-state keywords: SOLVE.ANGLES, SOLVE.TRANS, SOLVE.FLAGS, HAND,
STATE, HOUR.METER and CALIBRATE (V+ guide v17 L6781, L6859, L6871, L7044-7052, L7059;
eV+ guide L2756, L2849-2851).  The guides only list them; the forms follow the V+
Language Reference and the twin's choices are in docs/motion.md, "Kinematics keywords".

    SOLVE.ANGLES o.jts[], o.flags, error = trans, i.jts[], i.flags
    SOLVE.TRANS trans[, error] = i.jts[]
"""

from __future__ import annotations

from ....controller.kinematics import KinematicsError
from .. import messages as msg
from ..values import fail
from . import Any, Loc, function, instruction
from .locations import location_arg

HAND_VALUES = {"open": 1.0, "close": 0.0, "relax": -1.0}
STATE_PROGRAM_CONTROL = 7  # STATE(1): the robot is under program control
STATE_NO_MOTION, STATE_MOVING, STATE_STOPPED = 0, 1, 2  # STATE(2)
STATE_COMPUTER_CONTROL = 5  # STATE(3): the last of the manual control modes, computer control
STATE_NO_CONDITION = range(4, 10)  # STATE(4..9): bit flags and modes of hardware the cell lacks


def _joints_from(rt, ref) -> list[float]:
    """The robot's joint values from an array, starting at the given element (0 for a[])."""
    if not isinstance(ref, tuple) or not isinstance(ref[0], dict):
        raise fail(msg.WRONG_TYPE, "an array of joint values expected")
    array, start = ref[0], ref[1] or 0
    values = []
    for i in range(start, start + rt.robot.kin.dof):
        if array.get(i) is None:
            raise fail(msg.UNDEFINED_VALUE, f"joint array element [{i}]")
        values.append(float(array[i]))
    return values


@instruction("SOLVE.ANGLES", targets=True, array_values=(1,), writes_back=True)
def _solve_angles(rt, trans: Loc, seed: Any, in_flags, out_joints: Any, out_flags: Any, error: Any):
    """o.jts[] gets the joints that put the tool tip at `trans` nearest i.jts[], in the
    configuration i.flags asks for (CONFIG bits), o.flags their bits and error 0; a
    location the robot cannot reach leaves o.jts[] and o.flags as they were and sets
    error to the V+ error code a MOVE there would stop with (-610 out of range, -1021
    joint limit)."""
    seed = _joints_from(rt, seed)
    if not isinstance(out_joints, tuple) or not isinstance(out_joints[0], dict):
        raise fail(msg.WRONG_TYPE, "SOLVE.ANGLES needs an array")
    try:
        joints, flags = rt.robot.solve_angles(location_arg(trans), seed, int(in_flags or 0))
    except KinematicsError as err:
        return None, None, float(err.code)
    array, start = out_joints[0], out_joints[1] or 0
    for i, value in enumerate(joints):
        array[start + i] = value
    return None, float(flags), 0.0


@instruction("SOLVE.TRANS", targets=True, array_values=(0,), writes_back=True)
def _solve_trans(rt, joints: Any, trans: Any, error: Any = None):
    """trans gets the tool-tip location (TOOL and BASE applied) of the joints in i.jts[];
    error, if given, 0 (forward kinematics always has an answer)."""
    return rt.robot.location_of_joints(_joints_from(rt, joints)), 0.0


@function("SOLVE.FLAGS")
def _solve_flags(rt, joints: Any):
    """SOLVE.FLAGS(jts[]): the CONFIG bits (1 RIGHTY) of the joints in the array."""
    return float(rt.robot.configuration_of(_joints_from(rt, joints)))


@function("HAND")
def _hand(rt, select=1):
    """HAND(): the pneumatic hand as last driven: 1 open, 0 closed, -1 relaxed."""
    if int(select or 1) != 1:
        raise fail(msg.ILLEGAL_VALUE, f"HAND({select})")
    return HAND_VALUES[rt.robot.hand_state]


@function("STATE")
def _state(rt, select):
    """STATE(1): 7, the robot is under program control; STATE(2): 0 before the first
    motion, 1 while a motion runs, 2 stopped at its planned location; STATE(3): 5, computer
    control (no manual control mode: there is no pendant); STATE(4) to STATE(9): 0, none of
    the front-panel, hardware or mode conditions they report exists in the twin's cell
    (docs/vplus.md, "STATE(select)")."""
    select = int(select)
    if select == 1:
        return float(STATE_PROGRAM_CONTROL)
    if select == 2:
        robot = rt.robot
        if robot.moving:
            return float(STATE_MOVING)
        return float(STATE_STOPPED if robot.history else STATE_NO_MOTION)
    if select == 3:
        return float(STATE_COMPUTER_CONTROL)
    if select in STATE_NO_CONDITION:
        return 0.0
    raise fail(msg.ILLEGAL_VALUE, f"STATE({select})")


@function("HOUR.METER")
def _hour_meter(rt):
    """HOUR.METER: hours the robot has been powered: the cell's simulated time."""
    return rt.robot.cell.time / 3600.0


@instruction("CALIBRATE")
def _calibrate(rt, *mode):
    """CALIBRATE: the twin's robot is always calibrated; nothing to do."""
