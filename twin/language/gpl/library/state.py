"""What the controller keeps for GPL: power, homing, which thread has the robot
attached, base and tool offsets, the last profile; also its other per-run
state (analog channels, thread events, NVRAM files).

The twin has one robot (number 1) driven by the shared VirtualController.
This state lives beside that controller (one per controller object), so every
GPL thread of a run sees the same robot, as on the real controller.

Start state (digest §15 item 13): a scene starts with high power off and the
robot not homed, as a real controller after restart; a program must set
``Controller.PowerEnabled = True``, call ``Robot.Home`` and attach the robot
(``Robot.Attached = 1``) before it moves.  Homing is instantaneous in the twin
(the model's encoders are absolute).
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ....controller.kinematics import KinematicsError
from ....controller.location import NULL, Location
from ....errors import ProgramError
from . import codes

MM = 1000.0
GPL_RIGHTY, GPL_LEFTY = 0x01, 0x02  # Location.Config bits (manual Table 4-4, L658)


@dataclass
class RobotState:
    power: bool = False
    homed: bool = False
    attached_by: Any = None  # thread handle holding the robot
    selected: int = 1
    base: Location = NULL  # Robot.Base: robot base in the world (GPL "world" = robot frame + Base)
    tool: Location = NULL  # Robot.Tool: tool tip in the flange frame
    payload: float | None = None  # Robot.Payload; None: not set since restart (DataID 16071)
    last_profile: Any = None
    last_in_range: float = 0.0
    source: Location | None = None
    source_q: np.ndarray | None = None  # joints at the start of the last motion
    dest_q: np.ndarray | None = None
    messages: list[str] = field(default_factory=list)  # Controller.SystemMessage log
    analog: dict[int, float] = field(default_factory=dict)  # Signal.AIO channels
    events: dict = field(default_factory=dict)  # pending Thread events by thread handle
    threads: dict = field(default_factory=dict)  # Thread object by thread handle
    nvram: dict = field(default_factory=dict)  # /NVRAM files: name -> NvramFile
    pdb: Any = None  # the parameter database (pdb.Database), made at first use


_STATES: "weakref.WeakKeyDictionary[Any, RobotState]" = weakref.WeakKeyDictionary()


def robot_state(rt) -> RobotState:
    """The GPL robot state of rt's controller (created at first use)."""
    state = _STATES.get(rt.robot)
    if state is None:
        state = _STATES[rt.robot] = RobotState()
    return state


def check_robot(number) -> None:
    if int(number) != 1:
        raise codes.fail(codes.INVALID_ROBOT, str(number))


# ------------------------------------------------------------ joints in GPL units
def revolute(rt) -> np.ndarray:
    return rt.robot.kin.revolute


def axis_count(rt) -> int:
    """The robot's highest GPL axis number (a PF400 on a rail: 6, its rail; axis 5, the
    servo gripper, is not one of the twin's joints and reads 0)."""
    return max(rt.robot.kin.axis_numbers)


def joint_of_axis(rt, axis: int) -> int | None:
    """Index in the joint vector of GPL axis `axis` (1-based), None when no joint is."""
    numbers = rt.robot.kin.axis_numbers
    return numbers.index(axis) if axis in numbers else None


def to_gpl_angles(rt, q: np.ndarray) -> list[float]:
    """Joint vector (rad, m) as GPL axis values (degrees, mm), axis 1 first."""
    values = [0.0] * axis_count(rt)
    for v, r, axis in zip(q, revolute(rt), rt.robot.kin.axis_numbers):
        values[axis - 1] = float(np.degrees(v)) if r else float(v * MM)
    return values


def from_gpl_angles(rt, values: list[float]) -> np.ndarray:
    """GPL axis values (degrees, mm; axis 1 first) as a joint vector (rad, m); missing axes are 0."""
    values = list(values) + [0.0] * axis_count(rt)
    return np.array([np.radians(values[axis - 1]) if r else values[axis - 1] / MM
                     for r, axis in zip(revolute(rt), rt.robot.kin.axis_numbers)])


# ------------------------------------------------------------ world <-> flange
def flange_pose(rt, q: np.ndarray) -> Location:
    """Flange pose (mm, deg) in the robot base frame for joints q."""
    T = rt.robot.kin.fk(q).copy()
    T[:3, 3] *= MM
    return Location.from_matrix(T)


def tool_pose(rt, q: np.ndarray) -> Location:
    """Robot.Where for joints q: Base * flange * Tool."""
    state = robot_state(rt)
    return state.base * flange_pose(rt, q) * state.tool


def flange_target(rt, total: Location) -> Location:
    """The flange pose (robot base frame) that puts the tool tip at `total`."""
    state = robot_state(rt)
    return state.base.inverse() * total * state.tool.inverse()


def matrix_m(pose: Location) -> np.ndarray:
    """4x4 matrix of a pose, translation in metres (what the kinematics takes)."""
    T = pose.matrix()
    T[:3, 3] /= MM
    return T


def config_of(rt, q: np.ndarray) -> int:
    """The Config bits of the arm configuration at joints q (Table 4-4): GPL_Righty or
    GPL_Lefty for a SCARA arm, none for a robot without an elbow configuration."""
    if rt.robot.kin.scara is None:
        return 0
    return GPL_RIGHTY if rt.robot.kin.is_righty(q) else GPL_LEFTY


def righty_of(config: int) -> bool | None:
    """The arm configuration a Location's Config bits ask for (None: keep the present one)."""
    if config & GPL_RIGHTY:
        return True
    if config & GPL_LEFTY:
        return False
    return None


def solve_joints(rt, total: Location, config: int) -> np.ndarray:
    """Joint vector (rad, m) putting the tool tip at `total`, from the present joints."""
    robot = rt.robot
    try:
        return robot.kin.ik(matrix_m(flange_target(rt, total)), robot.q_command, righty=righty_of(config))
    except KinematicsError as err:
        raise codes.from_controller(ProgramError(err.message, err.code)) from None
