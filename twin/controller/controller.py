"""The virtual robot controller: motion queue, trajectory execution, hand.

Both languages drive the robot through this class.  It owns what the real
controller owns: the commanded destination, the arm configuration request,
the speed settings, the hand valves, and the servo references fed to the
MuJoCo cell every physics step.

Forward processing (V+ guide v17, "Robot Motion"): a motion instruction
starts the move and the program goes on at once; the next motion instruction
waits until the move in progress is done.  Instructions that must see the
robot stopped (BREAK, OPENI, CLOSEI) wait until the joints have settled
within the FINE tolerance, and report "*Time-out nulling errors*" when they
never do.  The blocking methods are generators that yield wait conditions to
the task scheduler.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ProgramError
from .kinematics import KinematicsError, RobotKinematics
from .location import Location
from .trajectory import Trajectory, plan_joint_move, plan_straight_move

NULLING_TIMEOUT = -1003  # V+ "*Time-out nulling errors*" (V+ guide v17 L5832)
NULLING_TIMEOUT_S = 2.0  # how long the servos may take to settle after a move
MM = 1000.0


@dataclass
class MotionSettings:
    """Speed settings as V+ keeps them (V+ guide v17, "Speed, Acceleration")."""

    monitor_speed: float = 50.0  # % ; 50 at controller start-up
    program_speed: float = 100.0  # % ; 100 when a program starts
    next_speed: float | None = None  # SPEED without ALWAYS: the next motion only
    cartesian_speed_mm_s: float = 1000.0  # straight-line tool speed at 100 %
    accel: float = 100.0  # % of the maximum acceleration
    decel: float = 100.0  # % of the maximum deceleration

    def take(self) -> float:
        """Effective speed fraction for the motion about to start."""
        program = self.next_speed if self.next_speed is not None else self.program_speed
        self.next_speed = None
        return max(program * self.monitor_speed / 1e4, 1e-3)


class _Segment:
    """A trajectory sampled at the physics step, played back one step at a time."""

    def __init__(self, trajectory: Trajectory | None, dt: float, hold: np.ndarray, dwell_s: float = 0.0):
        if trajectory is not None and trajectory.duration > 0:
            _, self.q, self.qd = trajectory.sample(dt)
        else:
            steps = max(int(round(dwell_s / dt)), 1)
            self.q = np.repeat(hold[None, :], steps, axis=0)
            self.qd = np.zeros_like(self.q)
        self.k = 0

    @property
    def done(self) -> bool:
        return self.k >= len(self.q)


class VirtualController:
    """One robot's motion controller, on a physical cell."""

    def __init__(self, cell, kinematics: RobotKinematics, settings: MotionSettings | None = None):
        self.cell = cell
        self.kin = kinematics
        self.settings = settings or MotionSettings()
        self.dt = cell.timestep
        self.q_command = np.array(cell.robot_qpos(), dtype=float)
        self._destination = self._location_of(self.q_command)
        self._segment: _Segment | None = None
        self._righty_request: bool | None = None
        self._hand_request: str | None = None
        self._segment_end_time = cell.time
        # FINE tolerance per joint, in joint units (rad or m).
        self.fine = np.where(self._is_prismatic(), 2e-5, 1e-4)
        self.moves = 0

    def _is_prismatic(self) -> np.ndarray:
        names = self.kin.joint_names
        return np.array([self.cell.model.joint(n).type == 2 for n in names])

    # ------------------------------------------------------------ locations
    def _location_of(self, q: np.ndarray) -> Location:
        T = self.kin.fk(q).copy()
        T[:3, 3] *= MM
        return Location.from_matrix(T)

    @staticmethod
    def _matrix_m(location: Location) -> np.ndarray:
        T = location.matrix().copy()
        T[:3, 3] /= MM
        return T

    def destination(self) -> Location:
        """DEST: where the robot was last told to go."""
        return self._destination

    def here(self) -> Location:
        """HERE: where the robot is now, from the measured joint positions."""
        return self._location_of(self.cell.robot_qpos())

    def joints(self) -> np.ndarray:
        return self.cell.robot_qpos()

    # ------------------------------------------------------------ settings
    def set_speed(self, value: float, always: bool = False, monitor: bool = False, units: str | None = None):
        if monitor:
            self.settings.monitor_speed = value
        elif always:
            self.settings.program_speed = value
        else:
            self.settings.next_speed = value

    def speed(self, select: int = 1) -> float:
        return self.settings.monitor_speed if select == 0 else self.settings.program_speed

    def set_accel(self, accel: float | None, decel: float | None) -> None:
        """Acceleration and deceleration, percent of the maximum (1 to 100)."""
        if accel is not None:
            self.settings.accel = min(max(float(accel), 1.0), 100.0)
        if decel is not None:
            self.settings.decel = min(max(float(decel), 1.0), 100.0)

    def request_configuration(self, righty: bool) -> None:
        self._righty_request = righty

    # ------------------------------------------------------------ motion
    @property
    def moving(self) -> bool:
        return self._segment is not None

    def _motion_done(self) -> bool:
        return self._segment is None

    def stopped(self) -> bool:
        """The motion is over and every joint has settled within FINE."""
        if self._segment is not None:
            return False
        return bool(np.all(np.abs(self.cell.robot_qpos() - self.q_command) <= self.fine))

    def move(self, target: Location, straight: bool, cp: bool = True):
        """Start a motion to `target` once the motion in progress is done.  `cp`: the motion
        may blend into the next one (this controller stops at the end of every motion)."""
        if self._segment is not None:
            yield self._motion_done
        speed = self.settings.take()
        q0 = self.q_command
        # One acceleration limit for the whole motion (toppra's bounds are symmetric).
        amax = self.kin.max_acceleration * min(self.settings.accel, self.settings.decel) / 100.0
        try:
            if straight:
                trajectory = plan_straight_move(
                    self.kin, q0, self._matrix_m(target), self.kin.max_velocity, amax,
                    self.settings.cartesian_speed_mm_s * speed / MM,
                )
            else:
                q1 = self.kin.ik(self._matrix_m(target), q0, righty=self._righty_request)
                self._righty_request = None
                trajectory = plan_joint_move(q0, q1, self.kin.max_velocity * speed, amax)
        except KinematicsError as err:
            raise ProgramError(err.message, err.code) from None
        self._start(_Segment(trajectory, self.dt, q0))
        self._destination = target

    def dwell(self, seconds: float):
        """DELAY: a motion that stands still for `seconds`."""
        if self._segment is not None:
            yield self._motion_done
        self._start(_Segment(None, self.dt, self.q_command, dwell_s=seconds))

    def _start(self, segment: _Segment) -> None:
        if self._hand_request is not None:
            self.hand(self._hand_request)
            self._hand_request = None
        self._segment = segment
        self.moves += 1

    def wait_stopped(self):
        """BREAK: wait for the motion to finish and the joints to settle."""
        if self._segment is not None:
            yield self._motion_done
        if not self.stopped():
            deadline = self.cell.time + NULLING_TIMEOUT_S
            cell = self.cell
            yield lambda: self.stopped() or cell.time >= deadline
            if not self.stopped():
                raise ProgramError("*Time-out nulling errors*", NULLING_TIMEOUT)

    def stop(self) -> None:
        """Stop at once (program error, abort): hold the present command."""
        self._segment = None

    def servo_step(self) -> None:
        """Feed this physics step's references to the servos."""
        segment = self._segment
        if segment is None:
            return
        k = segment.k
        self.q_command = segment.q[k]
        self.cell.set_servo(self.q_command, segment.qd[k])
        segment.k = k + 1
        if segment.done:
            self.cell.set_servo(self.q_command, np.zeros_like(self.q_command))
            self._segment = None

    # ------------------------------------------------------------ hand
    def hand_at_next_motion(self, state: str) -> None:
        self._hand_request = state

    def hand(self, state: str) -> None:
        """Drive the gripper valves: 'open', 'close' or 'relax'."""
        self.cell.set_gripper(closed=(state == "close"))
