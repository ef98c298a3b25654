"""The virtual robot controller: motion queue, continuous path, trajectory execution, hand.

Both languages drive the robot through this class.  It owns what the real
controller owns: the commanded destination, the arm configuration request, the
speed, acceleration and tolerance settings, TOOL and BASE, the hand valves, and
the servo references fed to the MuJoCo cell every physics step.

Forward processing and continuous path (V+ guide v17, "Motion Control
Instructions", "Continuous-Path Trajectories", "Robot Speed"; docs/motion.md):

* a motion instruction plans its motion, waits until the motion *begins*, and the
  program goes on (SIGNAL 1 after MOVE part.1 turns on just after the robot starts);
* the next motion instruction waits until the motion in progress enters its
  deceleration phase (CP on) or is over (CP off), then plans its own;
* with CP on, the new motion starts while the previous one decelerates, so that
  the end of the previous deceleration coincides with the end of the new
  acceleration (the overlap is the shorter of the two phases): the two
  trajectories are superposed in joint space.  The blend is confined to those
  phases, so the robot never leaves a segment before it has started to slow down
  for its end point;
* instructions that must see the robot stopped (BREAK, OPENI, CLOSEI, RELAXI,
  CPOFF, TOOL, BASE) wait until every motion is over and the joints have settled
  within the FINE tolerance ("*Time-out nulling errors*" when they never do).

The blocking methods are generators that yield wait conditions to the task
scheduler.  Locations are in the world frame of the program (mm, degrees); the
robot's flange is at ``BASE : location : INVERSE(TOOL)`` in the robot base frame.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ..errors import ProgramError
from .belt import BeltLocation, BeltMonitor
from .kinematics import KinematicsError, RobotKinematics
from .location import NULL, Location
from .tracking import BeltPath, Tracking
from .trajectory import Trajectory, plan_joint_move, plan_straight_move
from .watchdog import timed

NULLING_TIMEOUT = -1003  # V+ "*Time-out nulling errors*" (V+ guide v17 L5832)
COLLISION = -1020  # "*Collision detected*": twin-defined (the real controller does not see the cell)
# The belt reference of a step is the encoder reading of that step: the position servo with
# velocity feed-forward follows it within a few hundredths of a mm (measured: a lead of one
# step puts the tool 0.2 mm ahead of the part at 100 mm/s).
BELT_LEAD_STEPS = 0
TRACKING_FINE_MM = 0.1  # FINE while tracking a belt: the flange's distance from its moving target
# Conveyor tracking errors: the guides name them without codes; twin-chosen (docs/vplus.md).
BELT_WINDOW_VIOLATION = -1014
BELT_JOINT_MOTION = -1015
BELT_NOT_ENABLED = -1016
BELT_WINDOW_MESSAGE = "*Belt window violation*"
BELT_JOINT_MESSAGE = "*Illegal joint motion from/to belt*"
# BELT.MODE bits (docs/vplus.md): 2 an upstream destination is an error instead of a wait,
# 4 no look-ahead (a motion's destination is tested where it is when planned), 8 no window
# test while the tool tracks the belt (only when motions are planned).
BELT_MODE_UPSTREAM_ERROR = 2
BELT_MODE_NO_PREDICTION = 4
BELT_MODE_NO_TRACKING_TEST = 8
# BSTATUS bits (docs/vplus.md): tracking, destination upstream (waiting), downstream, violation.
BSTATUS_TRACKING, BSTATUS_UPSTREAM, BSTATUS_DOWNSTREAM, BSTATUS_VIOLATION = 1, 2, 4, 8
NULLING_TIMEOUT_S = 2.0  # how long the servos may take to settle after a move
BLEND_SLACK = 1.02  # blends may reach the joint limits within the planner's own tolerance
COARSE_FACTOR = 5.0  # COARSE tolerance / FINE tolerance (SPEC: "normally 2 to 10 times" FINE)
TRAJECTORY_CYCLE_S = 0.016  # V+ trajectory generator period (62.5 Hz, V+ guide v17 "Timing Considerations")
PLAN_CACHE = 64  # planned trajectories kept for reuse
DURATION_BISECTIONS = 12  # speed factor for DURATION to 1/4096: the last 0.1 % is a uniform stretch
MAX_DWELL_S = 1e12  # DELAY longer than this (30,000 years) waits this long: any run ends first
MM = 1000.0
MM_PER_INCH = 25.4
CONFIG_RIGHTY = 1  # CONFIG() bits: RIGHTY (else LEFTY); BELOW = 2 and FLIP = 4 never apply here
# INRANGE() bits besides a joint limit (joint n: 2^(n-1)); twin-defined (docs/motion.md).
INRANGE_TOO_CLOSE = 0x100
INRANGE_TOO_FAR = 0x200
INRANGE_ORIENTATION = 0x400
_OUT_OF_RANGE_BITS = {"too close to the J1 axis": INRANGE_TOO_CLOSE, "beyond the reach of the arm": INRANGE_TOO_FAR,
                      "no converged solution": INRANGE_TOO_FAR, "tool not vertical": INRANGE_ORIENTATION}


@dataclass
class MotionParameters:
    """What one motion is planned with, after the SPEED/ACCEL/DURATION/CP/SINGLE settings."""

    joint_speed: float  # fraction of each joint's maximum speed (program speed)
    cartesian_speed_m_s: float  # straight-line tool speed limit (program speed)
    time_scale: float  # 100 / monitor speed: the planned motion is slowed down by this
    accel: float  # fraction of the maximum acceleration while speeding up
    decel: float  # ... while slowing down
    duration_s: float  # minimum motion time (DURATION)
    cp: bool  # this motion may blend into the next one
    single: bool  # wrist within +/-180 deg (SINGLE)
    coarse: bool  # COARSE: the looser end-of-motion tolerance
    null: bool  # NULL: a stop waits for the position errors to be nulled
    overlap: bool  # OVERLAP: a multi-turn joint may not turn more than 180 deg to avoid a limit


@dataclass
class MotionSettings:
    """Motion settings as V+ keeps them (V+ guide v17, "Robot Speed", "Motion Modifiers").

    Settings given without ALWAYS apply to the next motion only (`next`); with ALWAYS
    they replace the permanent value.  The program speed sets the speed a motion is
    planned for, the accelerations staying as they are; the monitor speed then slows the
    whole planned motion down, path unchanged, every phase taking 100/monitor times as
    long (V+ Operating System Reference Guide, SPEED monitor command, "Details")."""

    monitor_speed: float = 50.0  # % ; 50 at controller start-up
    program_speed: float = 100.0  # % ; 100 when a program starts
    cartesian_speed_mm_s: float = 1000.0  # straight-line tool speed at 100 %
    absolute_speed_mm_s: float | None = None  # SPEED v MMPS|IPS ALWAYS: straight-line tool speed
    accel: float = 100.0  # ACCEL, % of the maximum acceleration
    decel: float = 100.0  # ACCEL's second argument, % of the maximum deceleration
    duration_s: float = 0.0  # DURATION ... ALWAYS
    cp: bool = True  # CPON / CPOFF ALWAYS
    single: bool = False  # SINGLE / MULTIPLE ALWAYS
    coarse: bool = False  # COARSE / FINE ALWAYS
    null: bool = True  # NULL / NONULL ALWAYS
    overlap: bool = False  # OVERLAP / NOOVERLAP ALWAYS (docs/motion.md: NOOVERLAP at start-up)
    payload: float = 0.0  # PAYLOAD, % of the maximum payload (recorded: see docs/motion.md)
    next: dict = field(default_factory=dict)  # next-motion-only values, same keys

    def take(self, consume: bool = True) -> MotionParameters:
        """The parameters of the motion about to be planned; next-motion values are used up
        unless `consume` is false."""
        once = self.next
        if consume:
            self.next = {}
        speed = min(max(once.get("program_speed", self.program_speed) / 100.0, 1e-3), 1.0)
        absolute = once.get("absolute_speed_mm_s", None if "program_speed" in once else self.absolute_speed_mm_s)
        # An absolute speed is reached only at monitor speed 100 (V+ guide v17, "Robot Speed").
        cartesian = absolute if absolute is not None else self.cartesian_speed_mm_s * speed
        return MotionParameters(
            joint_speed=speed,
            cartesian_speed_m_s=max(cartesian, 1e-3) / MM,
            time_scale=100.0 / min(max(self.monitor_speed, 0.1), 100.0),
            accel=self.accel / 100.0,
            decel=self.decel / 100.0,
            duration_s=once.get("duration_s", self.duration_s),
            cp=once.get("cp", self.cp),
            single=once.get("single", self.single),
            coarse=once.get("coarse", self.coarse),
            null=once.get("null", self.null),
            overlap=once.get("overlap", self.overlap),
        )

    def set(self, key: str, value, always: bool) -> None:
        if always:
            setattr(self, key, value)
            self.next.pop(key, None)
        else:
            self.next[key] = value


@dataclass(frozen=True)
class MotionRecord:
    """One motion as the controller executed it: for reports, tests and benchmarks."""

    start_s: float  # simulated time the motion began
    end_s: float  # simulated time its last reference was commanded (the destination, at rest)
    duration_s: float  # planned duration: toppra's, slowed by the monitor speed and DURATION
    overlap_s: float  # how long it ran blended with the motion before it
    straight: bool
    destination: Location


class _Motion:
    """One planned motion on the controller's timeline of physics steps.

    Sample k of the trajectory is commanded at step ``start + k``; ``end`` is the step of
    the last sample (the destination, at rest).  ``decel_from`` is the first step of the
    final deceleration, ``accel_steps`` the length of the acceleration phase."""

    def __init__(self, trajectory: Trajectory, dt: float, params: MotionParameters,
                 destination: Location, hand: str | None):
        _, self.q, self.qd = trajectory.sample(dt)
        self.dt = dt
        self.still = isinstance(trajectory, _Still)
        if self.still:  # DELAY: read-only views of one row, O(1) memory however long it lasts
            self.delta = self.qdd = self.qd
        else:
            self.delta = self.q - self.q[0]  # what this motion adds to the reference
            self.qdd = self._acceleration()
        self.last = len(self.q) - 1  # index of the last sample
        self.params = params
        self.destination = destination
        self.hand = hand
        self.accel_steps = int(round(trajectory.accel_time / dt))
        self.decel_steps = int(round(trajectory.decel_time / dt))
        self.start = 0
        self.started = False
        self.belt: BeltPath | None = None  # set for a motion to or from a belt

    @property
    def end(self) -> int:
        return self.start + self.last

    def brake(self, k: int, slack: int) -> None:
        """From sample k on, slow the playback down linearly to rest over the motion's
        deceleration time: the robot stops on the same path (unless it arrives first).  A
        motion within `slack` steps of its deceleration is left to finish."""
        last = len(self.q) - 1
        if self.still:  # standing still: the motion simply ends at sample k
            self.q, self.qd = self.q[:k + 1], self.qd[:k + 1]
            self.delta = self.qdd = self.qd
            self.last = len(self.q) - 1
            return
        steps = max(self.decel_steps, 1)
        if k >= last - self.decel_steps - slack:
            return
        t = np.arange(steps + 1, dtype=float)
        u = np.minimum(k + t - t * t / (2 * steps), last)  # fractional sample index
        rate = 1.0 - t / steps
        i = np.minimum(np.floor(u).astype(int), last - 1)
        w = (u - i)[:, None]
        q = (1 - w) * self.q[i] + w * self.q[i + 1]
        qd = ((1 - w) * self.qd[i] + w * self.qd[i + 1]) * rate[:, None]
        self.q = np.concatenate([self.q[:k], q])
        self.qd = np.concatenate([self.qd[:k], qd])
        self.delta = self.q - self.q[0]
        self.qdd = self._acceleration()
        self.last = len(self.q) - 1

    def _acceleration(self) -> np.ndarray:
        """Reference accelerations at the samples (for the servos' feed-forward); none at the
        last sample, where the motion is over."""
        qdd = np.zeros_like(self.qd) if len(self.qd) < 2 else np.gradient(self.qd, self.dt, axis=0)
        qdd[-1] = 0.0
        return qdd

    @property
    def decel_from(self) -> int:
        return self.end - self.decel_steps


class VirtualController:
    """One robot's motion controller, on a physical cell."""

    def __init__(self, cell, kinematics: RobotKinematics, settings: MotionSettings | None = None):
        self.cell = cell
        self.kin = kinematics
        self.settings = settings or MotionSettings()
        self.dt = cell.timestep
        self.lookahead = max(1, int(round(TRAJECTORY_CYCLE_S / self.dt)))
        self.step = 0  # index of the next physics step to command
        self.belts = BeltMonitor(cell, self.dt)
        self._belt_lead = BELT_LEAD_STEPS * self.dt
        self.tracking: Tracking | None = None  # the belt location the tool follows
        self._qd_tracking = np.zeros(len(cell.robot_qpos()))  # its joint speeds, last step
        self.belt_status = 0  # BSTATUS bits
        self.fault: ProgramError | None = None  # an error the robot raised by itself (window violation)
        self.q_command = np.array(cell.robot_qpos(), dtype=float)
        self._anchor = self.q_command.copy()  # reference before the motions on the timeline
        self._motions: list[_Motion] = []  # started or about to start, in time order
        self._q_planned = self.q_command.copy()  # joints at the end of the last planned motion
        self.tool = NULL
        self.base = NULL
        self._destination = self._location_of(self.q_command)
        self._righty_request: bool | None = None
        self._hand_request: str | None = None
        self.hand_state = "open"  # the valves as last driven: HAND() (the jaws start open)
        self.prismatic = np.array([cell.model.joint(n).type == 2 for n in cell.robot_joint_names])
        # FINE tolerance per joint, in joint units (rad or m).
        self.fine = np.where(self.prismatic, 2e-5, 1e-4)
        self.history: list[MotionRecord] = []
        self._plans: dict[tuple, Trajectory] = {}
        self._last_params: MotionParameters | None = None  # of the last motion launched
        self._t0 = cell.time  # simulated time of step 0
        # Told of each motion planned (its joint samples, straight or not): the recording draws
        # the planned tool-tip path (twin/program_trace.py).  None: nobody listens.
        self.on_plan: Callable[[np.ndarray, bool], None] | None = None

    # ------------------------------------------------------------ locations
    def _flange_matrix_m(self, location: Location) -> np.ndarray:
        """Flange pose in the robot base frame (metres) for a program location."""
        T = (self.base * location * self.tool.inverse()).matrix()
        T[:3, 3] /= MM
        return T

    def _tip_matrix_m(self, location: Location) -> np.ndarray:
        """Tool-tip pose in the robot base frame (metres)."""
        T = (self.base * location).matrix()
        T[:3, 3] /= MM
        return T

    def _location_of(self, q: np.ndarray) -> Location:
        """Program location of the tool tip for joints q: INVERSE(BASE) : FK(q) : TOOL."""
        T = self.kin.fk(q).copy()
        T[:3, 3] *= MM
        return self.base.inverse() * Location.from_matrix(T) * self.tool

    def _tool_m(self) -> np.ndarray:
        T = self.tool.matrix()
        T[:3, 3] /= MM
        return T

    def destination(self) -> Location | BeltLocation:
        """DEST: where the robot was last told to go (a belt location while it tracks one)."""
        return self._destination

    def here(self) -> Location:
        """HERE: where the robot is now, from the measured joint positions."""
        return self._location_of(self.cell.robot_qpos())

    def joints(self) -> np.ndarray:
        """#PHERE: measured joints (SI)."""
        return self.cell.robot_qpos()

    def destination_joints(self) -> np.ndarray:
        """#PDEST: the joints the robot was last told to go to (SI)."""
        return self._q_planned.copy()

    def location_of_joints(self, values) -> Location:
        """The location a precision point (joint values, degrees and mm) puts the tool tip at."""
        return self._location_of(self.from_user_joints(values))

    def to_user_joints(self, q: np.ndarray) -> tuple[float, ...]:
        """Joint values as V+ shows them: degrees for revolute joints, mm for prismatic."""
        return tuple(float(v * MM if p else math.degrees(v)) for v, p in zip(q, self.prismatic))

    def from_user_joints(self, values) -> np.ndarray:
        values = [float(v) for v in values]
        if len(values) != self.kin.dof:
            raise ProgramError(f"*Invalid argument* precision point has {len(values)} joints, "
                               f"the robot {self.kin.dof}", -407)
        return np.array([v / MM if p else math.radians(v) for v, p in zip(values, self.prismatic)])

    # ------------------------------------------------------------ settings
    def set_speed(self, value: float, always: bool = False, monitor: bool = False, units: str | None = None):
        """SPEED v [MMPS|IPS] [ALWAYS] / SPEED v MONITOR."""
        if monitor:
            self.settings.monitor_speed = value
        elif units is not None:
            mm_s = value * (MM_PER_INCH if units == "IPS" else 1.0)
            self.settings.set("absolute_speed_mm_s", mm_s, always)
        else:
            self.settings.set("program_speed", value, always)
            if always:
                self.settings.absolute_speed_mm_s = None

    def speed(self, select: int = 1) -> float:
        """SPEED(select) (V+ Language Reference, SPEED function; docs/motion.md): 1 the monitor
        speed, 2 the permanent program speed (SPEED ... ALWAYS), 3 the program speed the next
        motion will get (a SPEED without ALWAYS included)."""
        if select == 1:
            return self.settings.monitor_speed
        if select == 2:
            return self.settings.program_speed
        if select == 3:
            return self.settings.next.get("program_speed", self.settings.program_speed)
        raise ProgramError(f"*Invalid argument* SPEED({select})", -407)

    def configuration(self, select: int = 0) -> int:
        """CONFIG(select): the arm configuration bits (1 RIGHTY, 2 BELOW, 4 FLIP) of the robot now
        (0), of the destination of the last motion (1) or of the next motion (2, after
        LEFTY/RIGHTY).  A SCARA has only the RIGHTY bit to show, a Cartesian robot none."""
        if select not in (0, 1, 2):
            raise ProgramError(f"*Invalid argument* CONFIG({select})", -407)
        if self.kin.scara is None:
            return 0
        righty = self._righty_request if select == 2 else None
        if righty is None:
            righty = self.kin.is_righty(self.cell.robot_qpos() if select == 0 else self._q_planned)
        return CONFIG_RIGHTY if righty else 0

    def configuration_of(self, values) -> int:
        """SOLVE.FLAGS: the CONFIG bits of a precision point (joint values, degrees and mm)."""
        if self.kin.scara is None:
            return 0
        return CONFIG_RIGHTY if self.kin.is_righty(self.from_user_joints(values)) else 0

    def solve_angles(self, target: Location, seed, flags: int) -> tuple[tuple[float, ...], int]:
        """SOLVE.ANGLES: the joint values (degrees, mm) and their CONFIG bits that put the tool
        tip at `target` (TOOL and BASE applied), nearest the `seed` joint values, in the
        configuration the CONFIG bits `flags` ask for.  Raises KinematicsError."""
        righty = None if self.kin.scara is None else bool(int(flags) & CONFIG_RIGHTY)
        q = self.kin.ik(self._flange_matrix_m(target), self.from_user_joints(seed), righty=righty)
        values = self.to_user_joints(q)
        return values, self.configuration_of(values)

    def inrange(self, target) -> int:
        """INRANGE(location): 0 when the next joint motion could reach `target` (a Location or
        a precision point's joint values) from the last destination in the requested
        configuration; otherwise the reasons as bits: joint n's limit 2^(n-1), too close to
        the J1 axis, beyond reach, a tool orientation the robot cannot take (INRANGE_*)."""
        try:
            if isinstance(target, Location):
                single = self.settings.take(consume=False).single
                self.kin.ik(self._flange_matrix_m(target), self._q_planned, righty=self._righty_request, single=single)
            else:
                self.kin.check_limits(self.from_user_joints(target))
        except KinematicsError as err:
            if err.joint is not None:
                return 1 << (err.joint - 1)
            return _OUT_OF_RANGE_BITS.get(getattr(err, "detail", ""), INRANGE_TOO_FAR)
        return 0

    def set_accel(self, accel: float | None, decel: float | None) -> None:
        """ACCEL acc, dec: percentages of the maximum, at most 100 (the SPEC maximum)."""
        if accel is not None:
            self.settings.accel = min(max(float(accel), 1.0), 100.0)
        if decel is not None:
            self.settings.decel = min(max(float(decel), 1.0), 100.0)

    def set_duration(self, seconds: float, always: bool = False) -> None:
        self.settings.set("duration_s", max(float(seconds), 0.0), always)

    def set_modifier(self, key: str, value, always: bool = False) -> None:
        """SINGLE/MULTIPLE ("single"), COARSE/FINE ("coarse"), NULL/NONULL ("null"),
        OVERLAP/NOOVERLAP ("overlap"), CPON/CPOFF ("cp"): the next motion, or every motion
        with ALWAYS; PAYLOAD ("payload", always)."""
        self.settings.set(key, value, always)

    def request_configuration(self, righty: bool) -> None:
        """LEFTY / RIGHTY for the next motion (a SCARA's only configuration choice)."""
        self._righty_request = righty

    # ------------------------------------------------------------ state
    @property
    def moving(self) -> bool:
        return bool(self._motions)

    def _motion_done(self) -> bool:
        return not self._motions

    def stopped(self, tolerance: np.ndarray | None = None) -> bool:
        """Every motion is over and every joint has settled within `tolerance` (FINE)."""
        if self._motions:
            return False
        tolerance = self.fine if tolerance is None else tolerance
        if self.tracking is not None:
            return self._on_the_part(float(np.max(tolerance / self.fine)))
        return bool(np.all(np.abs(self.cell.robot_qpos() - self.q_command) <= tolerance))

    def _on_the_part(self, looser: float) -> bool:
        """Nulled while tracking: the flange within TRACKING_FINE_MM (times `looser` for
        COARSE) of where the servos are taking it, one step ahead of the last reference.
        The wrist is left out: its counter-rotation lags by what its joint damping costs
        (docs/motion.md), which does not move the tool tip."""
        target = self.kin.fk(self.q_command + self._qd_tracking * self.dt)[:3, 3]
        error = np.linalg.norm(self.kin.fk(self.cell.robot_qpos())[:3, 3] - target) * MM
        return bool(error <= TRACKING_FINE_MM * looser)

    # ------------------------------------------------------------ motion
    def move(self, target, straight: bool, cp: bool = True):
        """Plan and start a motion to `target` (a Location, or joint values in V+ units for a
        precision point), after the motion in progress has reached its blend point.
        `cp` is the state of the CP switch."""
        if isinstance(target, BeltLocation) or self.tracking is not None or self._belt_motion() is not None:
            # No blending into or out of a belt motion: the next one waits for it to end.
            if self._motions:
                yield self._motion_done
            if isinstance(target, BeltLocation) or self.tracking is not None:
                yield from self._belt_move(target, straight)
                return
        yield from self._wait_for_queue(cp)
        params = self.settings.take()
        righty, self._righty_request = self._righty_request, None
        q0 = self._q_planned
        try:
            if isinstance(target, Location):
                if straight:
                    tip, tool = self._tip_matrix_m(target), self._tool_m()
                    trajectory = self._as_run(
                        ("S", q0.tobytes(), tip.tobytes(), tool.tobytes(), righty, params.cartesian_speed_m_s,
                         params.accel, params.decel),
                        lambda f: plan_straight_move(self.kin, q0, tip, self.kin.max_velocity,
                                                     self.kin.max_acceleration, params.cartesian_speed_m_s * f,
                                                     righty=righty, accel=params.accel, decel=params.decel,
                                                     tool=tool),
                        params)
                else:
                    q1 = self.kin.ik(self._flange_matrix_m(target), q0, righty=righty, single=params.single)
                    if params.overlap:
                        self._check_overlap(q0, q1)
                    trajectory = self._joint_trajectory(q0, q1, params)
                destination = target
            else:
                q1 = self.from_user_joints(target)
                self.kin.check_limits(q1)
                trajectory = self._joint_trajectory(q0, q1, params)
                destination = self._location_of(q1)
        except KinematicsError as err:
            raise ProgramError(err.message, err.code) from None
        yield from self._launch(trajectory, params, destination, cp, straight and isinstance(target, Location))

    # ------------------------------------------------------------ belts
    @property
    def following_belt(self) -> bool:
        """The tool is on a belt location, following it (not on its way there or off it)."""
        return self.tracking is not None and self._belt_motion() is None

    def _belt_motion(self) -> _Motion | None:
        return next((m for m in self._motions if m.belt is not None), None)

    def _belt_move(self, target, straight: bool):
        """A straight-line motion to or from a belt location (module doc of tracking.py).
        The window is tested first: a destination not yet in the window is waited for
        (an error with BELT.MODE bit 2); one past it, now or by the time the motion would
        get there, is a window violation."""
        if not straight or not isinstance(target, (Location, BeltLocation)):
            raise ProgramError(BELT_JOINT_MESSAGE, BELT_JOINT_MOTION)
        if isinstance(target, BeltLocation):
            if not (yield from self._await_window(target, 0.0)):
                return
        params = self.settings.take()
        start = self.tracking
        q0 = self.q_command.copy()
        tip, tool = self._tip_matrix_m(_world(target)), self._tool_m()
        try:
            trajectory = plan_straight_move(self.kin, q0, tip, self.kin.max_velocity, self.kin.max_acceleration,
                                            params.cartesian_speed_m_s, accel=params.accel, decel=params.decel,
                                            tool=tool)
        except KinematicsError as err:
            raise ProgramError(err.message, err.code) from None
        trajectory = trajectory.stretched(max(trajectory.duration * params.time_scale, params.duration_s,
                                              TRAJECTORY_CYCLE_S))
        if isinstance(target, BeltLocation):
            ahead = 0.0 if target.belt.mode & BELT_MODE_NO_PREDICTION else trajectory.duration
            if not (yield from self._await_window(target, ahead)):
                return
        self.tracking = None
        self._anchor = q0
        self._q_planned = q0
        motion = _Motion(trajectory, self.dt, params, target, self._hand_request)
        motion.belt = BeltPath(self.kin, motion.q, self.dt, self.base, None if start is None else start.where,
                               target if isinstance(target, BeltLocation) else None)
        self._hand_request = None
        yield from self._launch_motion(motion, trajectory, params, target, cp=False, straight=True)

    def _await_window(self, target: BeltLocation, ahead_s: float):
        """True when `target` may be moved to; False after a violation handled by the program's
        own routine.  Waits while it is upstream (BELT.MODE bit 2: an error instead)."""
        state = target.window_state(ahead_s)
        if state == "upstream":
            if target.belt.mode & BELT_MODE_UPSTREAM_ERROR:
                return self._violation(target, state, raising=True)
            self.belt_status |= BSTATUS_UPSTREAM
            yield lambda: target.window_state(ahead_s) != "upstream"
            self.belt_status &= ~BSTATUS_UPSTREAM
            state = target.window_state(ahead_s)
        if state == "downstream":
            return self._violation(target, state, raising=True)
        return True

    def _violation(self, where: BeltLocation, state: str, raising: bool) -> bool:
        """A window violation: the robot stops; the belt's own routine is told (V+ WINDOW's
        program), or else it is an error, raised here or (`raising` false, found by the
        servo loop) left in `fault` for the simulation to give the running programs."""
        self.belt_status |= BSTATUS_VIOLATION | (BSTATUS_DOWNSTREAM if state == "downstream" else BSTATUS_UPSTREAM)
        self._stop_tracking()
        if where.belt.on_violation is not None:
            where.belt.on_violation(state)
            return False
        error = ProgramError(f"{BELT_WINDOW_MESSAGE} {where.belt.name or 'belt'}: destination {state} of the window",
                             BELT_WINDOW_VIOLATION)
        if raising:
            raise error
        self.fault = error
        return False

    def take_fault(self) -> ProgramError | None:
        fault, self.fault = self.fault, None
        return fault

    def bstatus(self) -> int:
        """BSTATUS: the tracking bits now (the violation bit is cleared by reading it)."""
        tracking = BSTATUS_TRACKING if self.tracking is not None or self._belt_motion() is not None else 0
        value = self.belt_status | tracking
        self.belt_status &= ~BSTATUS_VIOLATION
        return value

    def _stop_tracking(self) -> None:
        """The tool stops following its belt: it holds where it is now commanded."""
        if self.tracking is None and self._belt_motion() is None:
            return
        self.tracking = None
        self._motions = []
        self._anchor = self.q_command.copy()
        self._q_planned = self.q_command.copy()
        self._destination = self._location_of(self.q_command)
        self.cell.set_servo(self.q_command, np.zeros_like(self.q_command))

    def _check_overlap(self, q0: np.ndarray, q1: np.ndarray) -> None:
        """OVERLAP: a multi-turn joint (range over 360 deg) that would turn more than 180 deg,
        which MULTIPLE does only to keep clear of a limit, is that joint's limit-stop error."""
        multi_turn = self.kin.revolute & (self.kin.upper - self.kin.lower > 2 * math.pi)
        over = np.nonzero(multi_turn & (np.abs(q1 - q0) > math.pi + 1e-9))[0]
        if len(over):
            raise KinematicsError.joint_limit(int(over[0]) + 1)

    def ready_joints(self) -> tuple[float, ...]:
        """READY's destination: the robot's READY joints (the model's `ready` numeric), V+ units."""
        return self.to_user_joints(self.kin.ready)

    def drive(self, joint: int, change: float, speed: float, cp: bool = True):
        """DRIVE joint, change, speed: joint `joint` (1-based) by `change` (deg or mm) at
        `speed` % of normal speed (times the monitor speed), from the last destination."""
        if not 1 <= joint <= self.kin.dof:
            raise ProgramError(f"*Invalid argument* DRIVE joint {joint}", -407)
        yield from self._wait_for_queue(cp)
        self.settings.next["program_speed"] = float(speed)
        params = self.settings.take()
        q1 = self._q_planned.copy()
        j = joint - 1
        q1[j] += change / MM if self.prismatic[j] else math.radians(change)
        try:
            self.kin.check_limits(q1)
        except KinematicsError as err:
            raise ProgramError(err.message, err.code) from None
        trajectory = self._joint_trajectory(self._q_planned, q1, params)
        yield from self._launch(trajectory, params, self._location_of(q1), cp)

    def _joint_trajectory(self, q0, q1, params: MotionParameters) -> Trajectory:
        return self._as_run(
            ("J", q0.tobytes(), q1.tobytes(), params.joint_speed, params.accel, params.decel),
            lambda f: plan_joint_move(q0, q1, self.kin.max_velocity * params.joint_speed * f,
                                      self.kin.max_acceleration, accel=params.accel, decel=params.decel),
            params)

    def _as_run(self, key: tuple, plan, params: MotionParameters) -> Trajectory:
        """The motion as it will run.  `plan(f)` plans it at f times the program speed.  The
        monitor speed slows the planned motion down uniformly (see MotionSettings).  A motion
        that would take less than DURATION is replanned at the lower speed that makes it last
        that long, accelerations unchanged, as a lower SPEED would be ("the motion is
        slowed", V+ Language Reference, DURATION): its acceleration and deceleration stay
        short, and so do its blends with its neighbours.  Every motion lasts at least one
        trajectory cycle, the minimum motion time (V+ guide v17 L6548-6553; a motion that
        goes nowhere stays empty)."""
        trajectory = self._cached(key, lambda: plan(1.0))
        planned_duration = params.duration_s / params.time_scale
        if 0.0 < trajectory.duration < planned_duration:
            trajectory = self._cached(key + (planned_duration,), lambda: _slowed_down(plan, planned_duration))
        return trajectory.stretched(max(trajectory.duration * params.time_scale, params.duration_s, TRAJECTORY_CYCLE_S))

    def _cached(self, key: tuple, plan) -> Trajectory:
        """A cyclic program asks for the same motions, from the same joints, over and over:
        planning is deterministic, so a plan is computed once (most recent PLAN_CACHE kept)."""
        trajectory = self._plans.pop(key, None)
        if trajectory is None:
            trajectory = plan()
            if len(self._plans) >= PLAN_CACHE:
                self._plans.pop(next(iter(self._plans)))
        self._plans[key] = trajectory
        return trajectory

    def aligned(self) -> Location:
        """ALIGN's destination: the last destination with its tool Z turned onto the nearest
        world axis (the smallest rotation that does it)."""
        loc = self._destination
        R = loc.rotation()
        z = R[:, 2]
        axis = np.zeros(3)
        k = int(np.argmax(np.abs(z)))
        axis[k] = math.copysign(1.0, z[k])
        v = np.cross(z, axis)
        c = float(z @ axis)
        if np.linalg.norm(v) < 1e-12:
            return loc
        vx = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
        turn = np.eye(3) + vx + vx @ vx / (1.0 + c)
        T = loc.matrix()
        T[:3, :3] = turn @ R
        return Location.from_matrix(T)

    def dwell(self, seconds: float):
        """DELAY: a motion that stands still for `seconds` (the robot stops before it)."""
        yield from self._wait_for_queue(cp=False)
        trajectory = _Still(self._q_planned, max(float(seconds), self.dt))
        # Standing still leaves the next-motion settings (SPEED without ALWAYS...) to the next
        # real motion.
        yield from self._launch(trajectory, self.settings.take(consume=False), self._destination, cp=False)

    def _wait_for_queue(self, cp: bool):
        """Wait until the last motion on the timeline is in its deceleration (blend possible)
        or, without continuous path, over."""
        if not self._motions:
            return
        last = self._motions[-1]
        if cp and last.params.cp:
            yield lambda: self.step + self.lookahead >= last.decel_from or not self._motions
        else:
            yield self._motion_done

    def _launch(self, trajectory, params: MotionParameters, destination: Location, cp: bool,
                straight: bool = False):
        """Put a planned motion on the timeline and wait until it begins."""
        motion = _Motion(trajectory, self.dt, params, destination, self._hand_request)
        self._hand_request = None
        yield from self._launch_motion(motion, trajectory, params, destination, cp, straight)

    def _launch_motion(self, motion: _Motion, trajectory, params: MotionParameters, destination, cp: bool,
                       straight: bool):
        start = self.step
        if self._motions:
            last = self._motions[-1]
            overlap = 0
            if cp and last.params.cp:
                longest = min(last.decel_steps, motion.accel_steps, max(last.end - self.step, 0))
                overlap = self._blend_steps(last, motion, longest)
            start = max(start, last.end - overlap)
        motion.start = start
        self._last_params = params
        overlap_s = (self._motions[-1].end - start) * self.dt if self._motions else 0.0
        self.history.append(MotionRecord(self._t0 + start * self.dt, self._t0 + motion.end * self.dt,
                                         trajectory.duration, max(overlap_s, 0.0), straight, destination))
        self._motions.append(motion)
        if self.on_plan is not None and not motion.still and motion.belt is None:
            self.on_plan(motion.q, straight)
        self._q_planned = motion.q[-1].copy()
        self._destination = destination
        if start > self.step:
            yield lambda: motion.started or motion not in self._motions

    def _blend_steps(self, last: _Motion, new: _Motion, longest: int) -> int:
        """The longest overlap, up to `longest` steps, for which the sum of the two motions
        stays within every joint's speed and acceleration limits (those the motions were
        planned with, slowed by the monitor speed like the motions themselves): the path
        is rounded only as much as the accelerations allow (V+ Operating System Reference,
        SPEED monitor command).  A joint that reverses between the two motions allows none."""
        scale = new.params.time_scale
        vmax = self.kin.max_velocity / scale * BLEND_SLACK
        amax = self.kin.max_acceleration / (scale * scale) * BLEND_SLACK

        def within(o: int) -> bool:
            qd = last.qd[last.last - o:] + new.qd[:o + 1]
            qdd = last.qdd[last.last - o:] + new.qdd[:o + 1]
            return bool(np.all(np.abs(qd) <= vmax) and np.all(np.abs(qdd) <= amax))

        lo, hi = 0, longest  # within(0) holds: one motion at rest, the other starting
        while lo < hi:
            mid = (lo + hi + 1) // 2
            if within(mid):
                lo = mid
            else:
                hi = mid - 1
        return lo

    def wait_stopped(self):
        """BREAK: wait for every motion to finish and, unless the last motion was NONULL, the
        joints to settle within its tolerance (FINE, or COARSE: COARSE_FACTOR times looser)."""
        if self._motions:
            yield self._motion_done
        last = self._last_params
        if last is not None and not last.null:
            return
        tolerance = self.fine * (COARSE_FACTOR if last is not None and last.coarse else 1.0)
        if not self.stopped(tolerance):
            deadline = self.cell.time + NULLING_TIMEOUT_S
            cell = self.cell
            yield timed(lambda: self.stopped(tolerance) or cell.time >= deadline)
            if not self.stopped(tolerance):
                raise ProgramError("*Time-out nulling errors*", NULLING_TIMEOUT)

    def set_tool(self, tool: Location):
        """TOOL t: waits for the robot to stop, then locations refer to the new tool tip."""
        yield from self._set_frame("tool", tool)

    def set_base(self, base: Location):
        """BASE: waits for the robot to stop, then the world frame is `base` in the robot frame."""
        yield from self._set_frame("base", base)

    def _set_frame(self, which: str, value: Location):
        """TOOL and BASE break continuous path; DEST is then the robot's destination seen
        through the new frame."""
        yield from self.wait_stopped()
        setattr(self, which, value)
        self._destination = self._location_of(self._q_planned)

    def stop(self) -> None:
        """A program error or BRAKE: the robot decelerates to a stop on its path.  Motions not yet
        begun are dropped; one already in its final deceleration (as a motion is when the
        next one fails to plan) goes on to its destination; one at speed slows down along
        its path over its own deceleration time.  A robot on a belt stops following it."""
        if self.tracking is not None or self._belt_motion() is not None:
            self._stop_tracking()
            return
        self._motions = [m for m in self._motions if m.started]
        for m in self._motions:
            m.brake(self.step - m.start, self.lookahead)
        self._q_planned = self._anchor + sum((m.delta[-1] for m in self._motions), np.zeros_like(self._anchor))
        self._destination = self._location_of(self._q_planned)

    def halt(self) -> None:
        """Stop at once where the robot is (a crash): every motion dropped, the servos hold
        the measured position."""
        q = self.cell.robot_qpos()
        self._motions = []
        self.tracking = None
        self._anchor = q.copy()
        self._q_planned = q.copy()
        self.q_command = q.copy()
        self._destination = self._location_of(q)
        self.cell.set_servo(q, np.zeros_like(q))

    def servo_step(self) -> None:
        """Feed this physics step's references to the servos: the superposition of the
        motions on the timeline (two only while they blend), moved with the belt when the
        motion goes to or from one or the tool tracks one."""
        self.belts.sample()
        motions = self._motions
        n = self.step
        self.step = n + 1
        if not motions:
            if self.tracking is not None:
                self._track()
            return
        belt, k_belt, active = None, 0, []
        for m in motions:
            k = n - m.start
            if k < 0:
                continue
            self._start(m)
            k = min(k, m.last)
            if m.belt is not None:
                belt, k_belt = m, k
            active.append((m, k))
        q, qd, qdd = self._superpose(active)
        if belt is not None:
            q, qd = self._belt_reference(belt, k_belt, q, qd)
            if q is None:
                return
        elif self.tracking is not None:  # DELAY while tracking: the tool stays on the part
            self._track()
            qd = None
        if qd is not None:
            self.q_command = q
            self.cell.set_servo(q, qd, qdd)
        self._retire(n)

    def _start(self, motion: _Motion) -> None:
        """A motion's first step: its hand action (OPENI/CLOSEI...) happens now."""
        if not motion.started:
            motion.started = True
            if motion.hand is not None:
                self.hand(motion.hand)

    def _superpose(self, active: list) -> tuple:
        """The references of the motions on the timeline, each at its index (a step or the
        rows of a chunk): positions from the anchor plus each motion's offset, velocities and
        accelerations summed; (anchor, None, None) when no motion is active."""
        q, qd, qdd = self._anchor, None, None
        for m, i in active:
            if qd is None:
                q, qd, qdd = q + m.delta[i], m.qd[i], m.qdd[i]
            else:
                q, qd, qdd = q + m.delta[i], qd + m.qd[i], qdd + m.qdd[i]
        return q, qd, qdd

    def _retire(self, last: int) -> None:
        """Drop the motions that ended by step `last`, their final offsets into the anchor."""
        motions = self._motions
        while motions and motions[0].end <= last:
            done = motions.pop(0)
            self._anchor = self._anchor + done.delta[-1]
            if done.belt is not None:
                self._arrived(done)
        if not motions and self.tracking is None:
            self.q_command = self._anchor.copy()

    def servo_chunk(self, limit: int) -> tuple[int, "Callable[[int], None] | None"]:
        """Command the next physics steps in one go, up to `limit` of them: returns how many,
        and the function the cell calls before each of those steps (0-based) to feed its
        servo references, or None when they do not change over the steps (standing still),
        so MuJoCo steps them in one call.  The references are those `servo_step` gives,
        computed for the whole chunk with numpy; the inertia feed-forward uses the mass
        matrix at the chunk's start (docs/performance.md).  A chunk ends where a motion
        begins (its hand action happens at that step).  Motions on or to a belt, tracking
        and encoders to sample are fed one step at a time by `servo_step`."""
        motions = self._motions
        if self.tracking is not None or self.belts.encoders or any(m.belt is not None for m in motions):
            self.servo_step()
            return 1, None
        n = self.step
        k = min([limit] + [m.start - n for m in motions if m.start > n])
        for m in motions:
            if m.start == n:
                self._start(m)
        active = [m for m in motions if m.start <= n]
        self.step = n + k
        last = n + k - 1
        feed = None
        if active and not all(m.still for m in active):
            indexed = []
            for m in active:
                a, b = n - m.start, last - m.start + 1
                indexed.append((m, slice(a, b) if b <= m.last + 1 else np.minimum(np.arange(a, b), m.last)))
            q, qd, qdd = self._superpose(indexed)
            self.q_command = q[-1]
            feed = self.cell.servo_feed(q, qd, qdd)
        elif active:  # standing still on the timeline (DELAY): one reference for the chunk
            q = self._anchor + sum((m.delta[0] for m in active), np.zeros_like(self._anchor))
            self.q_command = q
            self.cell.set_servo(q, np.zeros_like(q), np.zeros_like(q))
        self._retire(last)
        return k, feed

    def _belt_reference(self, motion: _Motion, k: int, q, qd):
        """The planned reference of a belt motion moved with its belts; a window violation
        of its destination stops it (None)."""
        end = motion.belt.end
        if end is not None and not end.belt.mode & BELT_MODE_NO_TRACKING_TEST and \
                end.window_state() == "downstream":
            self._violation(end, "downstream", raising=False)
            return None, None
        try:
            return motion.belt.reference(k, q, qd, self.q_command, self._belt_lead)
        except KinematicsError as err:
            self._stop_tracking()
            self.fault = ProgramError(err.message, err.code)
            return None, None

    def _arrived(self, motion: _Motion) -> None:
        """A belt motion is over: the tool tracks its destination, or it is off the belt."""
        end = motion.belt.end
        if end is None:
            self.tracking = None
            return
        self.tracking = Tracking(self.kin, end, self._flange_matrix_m(end.instantaneous()), self.base)
        self._destination = end

    def _track(self) -> None:
        """No motion: the tool follows its belt location; a window violation stops it."""
        where = self.tracking.where
        if not where.belt.mode & BELT_MODE_NO_TRACKING_TEST and where.window_state() == "downstream":
            self._violation(where, "downstream", raising=False)
            return
        try:
            q, qd = self.tracking.reference(self.q_command, self._belt_lead)
        except KinematicsError as err:
            self._stop_tracking()
            self.fault = ProgramError(err.message, err.code)
            return
        # Joint accelerations change as the arm turns while the tool runs straight: fed forward.
        qdd = (qd - self._qd_tracking) / self.dt
        self.q_command = q
        self._qd_tracking = qd
        self.cell.set_servo(q, qd, qdd)

    # ------------------------------------------------------------ hand
    def hand_at_next_motion(self, state: str) -> None:
        self._hand_request = state

    def hand(self, state: str) -> None:
        """Drive the gripper valves: 'open', 'close' or 'relax'."""
        self.hand_state = state
        self.cell.set_gripper(closed=(state == "close"))


def _slowed_down(plan, seconds: float) -> Trajectory:
    """plan(f) for the speed factor f in (0, 1] at which the motion takes just under
    `seconds` (bisection: a slower motion takes longer); the caller stretches the rest."""
    slow, fast = 0.0, 1.0
    for _ in range(DURATION_BISECTIONS):
        middle = 0.5 * (slow + fast)
        if plan(middle).duration >= seconds:
            slow = middle
        else:
            fast = middle
    return plan(fast)


class _Still(Trajectory):
    """DELAY: standing still at q for `seconds` (at most MAX_DWELL_S: longer than any run)."""

    def __init__(self, q: np.ndarray, seconds: float):
        q = np.array(q, dtype=float)
        z = np.zeros(1)
        seconds = min(float(seconds), MAX_DWELL_S)
        super().__init__(seconds, q, q.copy(), np.array([0.0, seconds]), z, z, np.zeros(1))

    def sample(self, dt: float) -> tuple[None, np.ndarray, np.ndarray]:
        """The samples as read-only broadcast views of one row: a DELAY of a day costs no
        more memory than one of a millisecond."""
        n = int(math.ceil(self.duration / dt - 1e-9)) + 1
        shape = (n, len(self.q_start))
        return None, np.broadcast_to(self.q_start, shape), np.broadcast_to(np.zeros(shape[1]), shape)


def _world(target) -> Location:
    """A motion's destination as a location now (a belt location where its belt is now)."""
    return target.instantaneous() if isinstance(target, BeltLocation) else target
