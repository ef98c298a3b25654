"""Time-optimal trajectories (toppra) for V+ joint and straight-line motions.

All toppra use lives in this module (its README warns Python support may go).
A path is a cubic spline through joint waypoints, parametrised by s in [0, 1];
toppra (Seidel solver, `N_GRID_*` grid points, constant-acceleration
parametrizer) gives the time-optimal s(t) within the joint velocity and
acceleration limits.  `Trajectory` keeps only numpy/scipy data: the
piecewise-constant path acceleration that `ParametrizeConstAccel` uses, and the
spline, so sampling a whole move is a few vectorised numpy calls.

* `plan_joint_move` (MOVE, APPRO, DEPART): straight line in joint space.
* `plan_straight_move` (MOVES, APPROS, DEPARTS): the flange origin on the
  straight line from fk(q0) to T1, orientation by slerp, sampled into joint
  waypoints with `RobotKinematics.ik` (each seeded by the previous one, the
  arm configuration held), the spacing refined until the spline's flange path
  stays within `LINE_TOLERANCE` of the line.  The TCP speed limit is a toppra
  velocity limit on an extra path coordinate equal to the distance travelled.
"""

from __future__ import annotations

import functools
import importlib
import importlib.util
import logging
import math
import sys
import types
from dataclasses import dataclass, field
from types import SimpleNamespace
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from .kinematics import STRAIGHT_LINE_CONFIG, KinematicsError, RobotKinematics

if TYPE_CHECKING:
    from scipy.interpolate import PPoly

# toppra grid points (cosine spacing, see `_grid`), each costing about 10 us of toppra's
# Python loop, chosen by measurement against a 400-point grid over 200 random Cobra
# motions (`bench/planning.py --grid-error`, docs/performance.md): every motion within
# 0.5 % of its duration there.
N_GRID_JOINT = 8  # joint-space line, refined once at the profile's corners: at most 0.13 % longer
REFINE_CELLS = 4  # that refinement: each cell at a corner cut into this many
END_FRACTIONS = np.array([1e-4, 1e-3, 5e-3])  # grid points this near either end, see `_grid`
N_GRID_STRAIGHT = 80  # straight line: at most 0.33 % longer, 0.08 % on average
LINE_TOLERANCE = 0.05e-3  # m: target deviation of a straight-line motion (the contract is 0.1 mm)
WAYPOINT_SPACING = 0.010  # m: first try of the straight-line waypoint spacing
WAYPOINT_ANGLE = math.radians(5.0)  # rad: same, for the orientation
MAX_REFINEMENTS = 5
CART_ACCEL_UNLIMITED = 1e3  # m/s^2 on the distance coordinate: no Cartesian acceleration limit
PHASE_TOLERANCE = 1e-3  # path accelerations within this fraction of the largest count as zero
KEPT_SAMPLES = 5000  # a plan keeps its samples when fewer (10 s at 2 ms: 0.5 MB for four joints)


@dataclass
class Trajectory:
    """A planned motion: joint positions and velocities as functions of time (SI).

    `duration` is 0 for a motion that goes nowhere."""

    duration: float
    q_start: np.ndarray
    q_end: np.ndarray
    _t: np.ndarray = field(repr=False)  # knot times (m + 1)
    _s: np.ndarray = field(repr=False)  # path parameter at the knots
    _v: np.ndarray = field(repr=False)  # ds/dt at the knots
    _a: np.ndarray = field(repr=False)  # d2s/dt2 on each segment (m), constant
    _path: PPoly | _Line | None = field(default=None, repr=False)  # s -> q
    _dpath: PPoly | _Line | None = field(default=None, repr=False)  # s -> dq/ds
    # A cyclic program runs the same (cached) plans over and over: the last `stretched` and
    # `sample` of this plan, kept (a fifth of the demo's time in the interpreter went there).
    _last_stretch: tuple = field(default=(None, None), init=False, repr=False, compare=False)
    _last_sample: tuple = field(default=(None, None), init=False, repr=False, compare=False)

    @classmethod
    def still(cls, q: np.ndarray) -> "Trajectory":
        q = np.array(q, dtype=float)
        z = np.zeros(1)
        return cls(0.0, q, q.copy(), z, z, z, np.zeros(0))

    def _eval(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        n = len(times)
        if self.duration <= 0.0 or self._path is None:
            return np.repeat(self.q_start[None, :], n, axis=0), np.zeros((n, len(self.q_start)))
        t = np.clip(times, 0.0, self.duration)
        i = np.clip(np.searchsorted(self._t, t, side="right") - 1, 0, len(self._a) - 1)
        tau = t - self._t[i]
        s = np.clip(self._s[i] + self._v[i] * tau + 0.5 * self._a[i] * tau * tau, 0.0, self._s[-1])
        sd = np.maximum(self._v[i] + self._a[i] * tau, 0.0)
        q = self._path(s)
        qd = self._dpath(s) * sd[:, None]
        end = t >= self.duration
        q[end] = self.q_end
        qd[end] = 0.0
        return q, qd

    def sample(self, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Times k*dt (k = 0, 1, ...) before the end, then the end itself; q and qd (n x dof)
        there.  The last sample is exactly `q_end` at rest."""
        if dt <= 0:
            raise ValueError("dt must be positive")
        last_dt, samples = self._last_sample
        if last_dt == dt:
            return samples
        k = int(math.ceil(self.duration / dt - 1e-9))
        times = np.arange(k + 1, dtype=float) * dt
        times[-1] = self.duration
        q, qd = self._eval(times)
        if k < KEPT_SAMPLES:  # kept for the next run of this plan, unless it is a long crawl
            for array in (times, q, qd):
                array.flags.writeable = False  # shared by every run of this plan
            self._last_sample = (dt, (times, q, qd))
        return times, q, qd

    def at(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """q, qd at time t (clamped to [0, duration])."""
        q, qd = self._eval(np.array([float(t)]))
        return q[0], qd[0]

    # ------------------------------------------------------------ phases
    def _phases(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Start, length and sign of the path acceleration of each segment that lasts
        (see `_accel_signs`)."""
        keep, sign = _accel_signs(self._t, self._a)
        return self._t[:-1][keep], np.diff(self._t)[keep], sign

    @functools.cached_property
    def accel_time(self) -> float:
        """Length of the acceleration phase: from the start until the path speed stops rising."""
        if self.duration <= 0.0 or len(self._a) == 0:
            return 0.0
        start, _, sign = self._phases()
        falling = np.flatnonzero(sign <= 0)
        return float(start[falling[0]]) if len(falling) else self.duration

    @functools.cached_property
    def decel_time(self) -> float:
        """Length of the final deceleration phase: from the last moment the path speed was not
        falling until the end (V+ guide v17 "Robot Speed": accelerate, travel, decelerate)."""
        if self.duration <= 0.0 or len(self._a) == 0:
            return 0.0
        start, length, sign = self._phases()
        not_falling = np.flatnonzero(sign >= 0)
        if not len(not_falling):
            return self.duration
        i = not_falling[-1]
        return self.duration - float(start[i] + length[i])

    def stretched(self, duration: float) -> "Trajectory":
        """The same path slowed down uniformly to take `duration` seconds (monitor speed,
        DURATION); a motion that already takes that long is returned unchanged."""
        if self.duration <= 0.0 or duration <= self.duration:
            return self
        last_duration, slower = self._last_stretch
        if last_duration != duration:
            f = duration / self.duration
            slower = Trajectory(duration, self.q_start, self.q_end, self._t * f, self._s, self._v / f,
                                self._a / (f * f), self._path, self._dpath)
            self._last_stretch = (duration, slower)
        return slower


# ---------------------------------------------------------------- toppra
@functools.cache
def _libs() -> SimpleNamespace:
    """toppra and scipy's PPoly, imported by the first plan: with the scipy and
    matplotlib modules toppra pulls in they are most of the package's import time, which a
    run that never moves the robot (or a `twin check`) need not pay."""
    _defer_pyplot()
    import toppra
    import toppra.algorithm
    import toppra.constraint
    import toppra.solverwrapper
    from scipy.interpolate import PPoly

    # toppra logs a path it cannot time as warnings on stderr; the planner times it again
    # on a stretched parameter or raises the controller's own error (`_solve`), so only
    # toppra's fatal messages (a grid that is not increasing: a bug of ours) are let through.
    logging.getLogger("toppra").setLevel(logging.CRITICAL)
    # Every toppra instance asks which optional solver packages are installed, searching
    # sys.path for each (a tenth of a MOVE's planning, more on a busy disk); the answer
    # cannot change while the process runs, so it is asked once.
    if not hasattr(toppra.solverwrapper.available_solvers, "cache_info"):
        toppra.solverwrapper.available_solvers = functools.cache(toppra.solverwrapper.available_solvers)
    return SimpleNamespace(toppra=toppra, algorithm=toppra.algorithm, constraint=toppra.constraint, PPoly=PPoly)


class _DeferredPyplot(types.ModuleType):
    """Stands in for matplotlib.pyplot until something uses it, then imports the real
    module in its place.  toppra imports pyplot at import time for plotting helpers that
    a plan never calls; pyplot (figures, backends, artists) is about 0.45 s of the 1.4 s
    toppra import that every run moving the robot pays.  (The standard library's
    `LazyLoader` does not serve: the import system's own look at `__spec__` loads it.)"""

    def __getattr__(self, name: str):
        if name.startswith("__"):
            raise AttributeError(name)
        if sys.modules.get(self.__name__) is self:
            del sys.modules[self.__name__]
        return getattr(importlib.import_module(self.__name__), name)


def _defer_pyplot() -> None:
    """matplotlib.pyplot is imported only when used (`_DeferredPyplot`); nothing is done
    when it is imported already or matplotlib is not installed."""
    if "matplotlib.pyplot" not in sys.modules and importlib.util.find_spec("matplotlib") is not None:
        sys.modules["matplotlib.pyplot"] = _DeferredPyplot("matplotlib.pyplot")


@functools.lru_cache(maxsize=512)
def _constraints(vmax: tuple[float, ...], abounds: tuple[tuple[float, float], ...]):
    """The toppra joint velocity and acceleration constraints for these limits.  They hold
    only the limits (the path is given at each solve), and building them costs about a
    fifth of a MOVE's planning (toppra validates and formats the limit arrays), while a
    program's moves reuse a few dozen sets (ACCEL settings x the joints' directions)."""
    constraint = _libs().constraint
    vmax_a = np.array(vmax)
    vel = constraint.JointVelocityConstraint(np.column_stack([-vmax_a, vmax_a]))
    acc = constraint.JointAccelerationConstraint(
        np.array(abounds), discretization_scheme=constraint.DiscretizationType.Interpolation
    )
    return vel, acc


def accel_bounds(dq: np.ndarray, amax: np.ndarray, accel: float = 1.0, decel: float = 1.0) -> np.ndarray:
    """Per-joint (lower, upper) acceleration bounds for ACCEL accel, decel (fractions of the
    maximum): a joint moving by `dq` speeds up in the direction of dq and slows down against
    it; a joint that ends where it started gets the smaller of the two both ways."""
    dq = np.asarray(dq, dtype=float)
    amax = np.asarray(amax, dtype=float)
    up = np.where(dq > 0, accel, np.where(dq < 0, decel, min(accel, decel))) * amax
    down = np.where(dq > 0, decel, np.where(dq < 0, accel, min(accel, decel))) * amax
    return np.column_stack([-down, up])


@functools.cache
def _grid(n: int) -> np.ndarray:
    """toppra grid on the path parameter's [0, 1]: `n` points closer together near both
    ends, where a motion speeds up and slows down (a short acceleration phase spread over
    a few uniform cells comes out slow), and `END_FRACTIONS` of the way from either end
    (the acceleration phase of a slow motion, DURATION or a low SPEED, is that short:
    inside a single cell it would be spread over the whole cell, at less than the allowed
    acceleration).  A straight line's waypoints need no grid points of their own (the
    durations do not change)."""
    u = np.concatenate([0.5 * (1.0 - np.cos(np.linspace(0.0, math.pi, n))), END_FRACTIONS, 1.0 - END_FRACTIONS])
    grid = np.unique(u)
    grid.flags.writeable = False  # shared by every plan
    return grid


def _accel_signs(t: np.ndarray, a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Which segments of a toppra profile last (grid points toppra places a hair apart give
    segments of no duration and meaningless accelerations), and the sign of the path
    acceleration (+1, 0, -1) on each of those."""
    keep = np.diff(t) > 1e-7
    kept = a[keep]
    tol = PHASE_TOLERANCE * float(np.max(np.abs(kept), initial=0.0))
    return keep, np.where(kept > tol, 1, np.where(kept < -tol, -1, 0))


def _solve(path, grid: np.ndarray, vel, acc):
    out = _toppra(path, grid, vel, acc)
    if out is None:
        # toppra bounds the squared path speed and acceleration (its MAXX, MAXU: 1e4), and
        # a motion of a fraction of a millimetre moves the joints so little along s in
        # [0, 1] that its sets of reachable speeds cannot be computed (about one straight
        # line in ten of 0.05 mm, one in a hundred of 1 mm: a part arriving under a waiting
        # tool).  The same path with s stretched to [0, rate], where its fastest coordinate
        # changes by one per unit of s, is the same motion in better numbers.
        rate = float(np.max(np.abs(path(grid, 1)), initial=0.0))
        if 0.0 < rate < 1.0:
            out = _toppra(_Stretched(path, rate), grid * rate, vel, acc)
            if out is not None:
                return out._ts, out._ss / rate, out._velocities / rate, out._us / rate
        raise KinematicsError.out_of_range("no feasible time parametrisation")
    return out._ts, out._ss, out._velocities, out._us


def _toppra(path, grid: np.ndarray, vel, acc):
    """toppra's time-optimal rest-to-rest parametrisation of `path` on `grid` (None: failed)."""
    return _libs().algorithm.TOPPRA([vel, acc], path, gridpoints=grid, solver_wrapper="seidel",
                                    parametrizer="ParametrizeConstAccel").compute_trajectory(0.0, 0.0)


class _Stretched:
    """A toppra geometric path with its parameter stretched `k` times: s' = k s."""

    def __init__(self, path, k: float):
        self.path, self.k = path, k
        self.dof = path.dof
        self.path_interval = np.asarray(path.path_interval, dtype=float) * k

    def __call__(self, s, order: int = 0) -> np.ndarray:
        return self.path(np.asarray(s, dtype=float) / self.k, order) / self.k ** order


def _parametrize(path, grid: np.ndarray, vmax: np.ndarray, abounds: np.ndarray, refine: bool = False):
    """Time-optimal rest-to-rest s(t) along the toppra `path`: (t, s, v, a).  `abounds` is
    (dof, 2): lower and upper joint acceleration.

    With `refine`, a second toppra pass on `grid` with the cells on either side of each
    change of the path acceleration's sign (where speeding up, cruising and slowing down
    meet) cut into `REFINE_CELLS`: on a joint-space line (constant limits along the path)
    the profile's corners fall inside cells, and a coarse cell around a corner is all that
    makes the motion slower than the time-optimal one."""
    vel, acc = _constraints(tuple(map(float, vmax)), tuple(map(tuple, np.asarray(abounds, float).tolist())))
    t, s, v, a = _solve(path, grid, vel, acc)
    if not refine:
        return t, s, v, a
    keep, sign = _accel_signs(t, a)
    cells = np.flatnonzero(keep)
    corners = np.flatnonzero(np.diff(sign) != 0)
    cut = np.unique(np.concatenate([cells[corners], cells[corners + 1]]))
    if not len(cut):
        return t, s, v, a
    pieces = np.linspace(0.0, 1.0, REFINE_CELLS + 1)[1:-1]
    inside = (grid[cut, None] + (grid[cut + 1] - grid[cut])[:, None] * pieces).ravel()
    return _solve(path, np.sort(np.concatenate([grid, inside])), vel, acc)


def _trajectory(timing, q_path, q0: np.ndarray, q1: np.ndarray) -> Trajectory:
    """A Trajectory from toppra's (t, s, v, a) and the joint path s -> q."""
    t, s, v, a = (np.asarray(x, float) for x in timing)
    return Trajectory(float(t[-1]), np.array(q0, dtype=float), np.array(q1, dtype=float), t, s, v, a,
                      q_path, q_path.derivative())


class _Line:
    """The joint-space line q0 + s (q1 - q0), s in [0, 1], or its `order`-th derivative:
    a geometric path for toppra (the interface of toppra's AbstractGeometricPath:
    `path(s, order)`, `dof`, `path_interval`; toppra's SplineInterpolator through the two
    end points is the same line, and building it was a sixth of a MOVE's planning) and
    for sampling (scipy's PPoly interface: `path(s)`, `path.derivative()`)."""

    path_interval = np.array([0.0, 1.0])

    def __init__(self, q0, q1, order: int = 0):
        self.q0 = np.asarray(q0, float)
        self.dq = np.asarray(q1, float) - self.q0
        self.order = order

    @property
    def dof(self) -> int:
        return len(self.q0)

    def __call__(self, s, order: int = 0) -> np.ndarray:
        s = np.asarray(s, dtype=float)
        order += self.order
        if order == 0:
            return self.q0 + s[..., None] * self.dq
        return np.broadcast_to(self.dq if order == 1 else np.zeros_like(self.dq), s.shape + self.dq.shape).copy()

    def derivative(self) -> "_Line":
        return _Line(self.q0, self.q0 + self.dq, self.order + 1)


# ---------------------------------------------------------------- analytic check
def joint_move_time(q0, q1, vmax, amax) -> float:
    """Time of the time-optimal rest-to-rest straight line in joint space (trapezoid or
    triangle on the path parameter, the slowest joint deciding): the analytic answer that
    `plan_joint_move` approximates."""
    dq = np.abs(np.asarray(q1, float) - np.asarray(q0, float))
    moving = dq > 0
    if not moving.any():
        return 0.0
    v = float(np.min(np.asarray(vmax, float)[moving] / dq[moving]))  # ds/dt limit, s in [0, 1]
    a = float(np.min(np.asarray(amax, float)[moving] / dq[moving]))
    if v * v / a >= 1.0:
        return 2.0 * math.sqrt(1.0 / a)
    return 1.0 / v + v / a


# ---------------------------------------------------------------- planners
def plan_joint_move(q0, q1, vmax, amax, accel: float = 1.0, decel: float = 1.0) -> Trajectory:
    """MOVE / APPRO / DEPART / DRIVE: straight line from q0 to q1 in joint space, rest to rest,
    time-optimal within the per-joint |qd| <= vmax and |qdd| <= amax (speeding up within
    accel * amax, slowing down within decel * amax: see `accel_bounds`)."""
    q0 = np.array(q0, dtype=float)
    q1 = np.array(q1, dtype=float)
    if np.max(np.abs(q1 - q0), initial=0.0) < 1e-12:
        return Trajectory.still(q0)
    vmax = np.asarray(vmax, float)
    amax = np.asarray(amax, float)
    path = _Line(q0, q1)
    timing = _parametrize(path, _grid(N_GRID_JOINT), vmax,
                          accel_bounds(q1 - q0, amax, accel, decel), refine=True)
    return _trajectory(timing, path, q0, q1)


def _segment_clear_of_hole(kin: RobotKinematics, P0: np.ndarray, P1: np.ndarray, righty: bool) -> None:
    """A SCARA cannot put its J4 axis nearer the J1 axis than the elbow allows: |L1 - L2|
    geometrically, more where the J2 range stops the elbow folding.  A straight line must
    not cross that disc (its end points can both lie outside it)."""
    s = kin.scara
    elbow = s.elbow_joint
    # The elbow angles the joint range allows in this configuration (a range may hold
    # the folded arm, as the PF400's J3 does, 12 to 348 deg): the most folded one.
    g = s.elbow(np.linspace(kin.lower[elbow], kin.upper[elbow], 721))
    if np.any(np.abs(np.diff(g)) > math.pi):  # the wrapped angle jumps: the range passes the fold
        fold = math.pi
    else:
        g = g[g >= 0.0] if righty else -g[g < 0.0]
        fold = float(g.max()) if len(g) else 0.0
    r_min = math.sqrt(max(s.l1 ** 2 + s.l2 ** 2 + 2 * s.l1 * s.l2 * math.cos(fold), 0.0))
    a, b = P0[:2] - s.p1, P1[:2] - s.p1
    d = b - a
    dd = float(d @ d)
    u = 0.0 if dd == 0.0 else min(1.0, max(0.0, -float(a @ d) / dd))
    if np.linalg.norm(a + u * d) < r_min - 1e-9:
        if r_min > abs(s.l1 - s.l2) + 1e-9:
            raise KinematicsError.joint_limit(elbow + 1)
        raise KinematicsError.out_of_range("straight line passes too close to the J1 axis")


def _distance_to_segment(P: np.ndarray, p0: np.ndarray, p1: np.ndarray) -> np.ndarray:
    d = p1 - p0
    dd = float(d @ d)
    if dd == 0.0:
        return np.linalg.norm(P - p0, axis=1)
    u = np.clip((P - p0) @ d / dd, 0.0, 1.0)
    return np.linalg.norm(P - (p0 + u[:, None] * d), axis=1)


def _tip_positions(kin: RobotKinematics, Q: np.ndarray, tool: np.ndarray) -> np.ndarray:
    """Tool-tip positions (n x 3, m) for joint vectors Q."""
    if not np.any(tool[:3, 3]):
        return kin.fk_positions(Q)
    return np.array([(kin.fk(q) @ tool)[:3, 3] for q in Q])


def plan_straight_move(kin: RobotKinematics, q0, T1, vmax, amax, cart_speed_max, righty=None,
                       accel: float = 1.0, decel: float = 1.0, tool: np.ndarray | None = None) -> Trajectory:
    """MOVES / APPROS / DEPARTS / ALIGN: the tool tip on the straight line from its pose at q0
    to T1 (the tool-tip pose, metres, base frame), orientation by slerp, arm configuration
    held.  `tool` is the TOOL transformation (flange -> tip, metres; None: the flange).

    Limits: joint |qd| <= vmax, speeding up within accel * amax and slowing down within
    decel * amax, and the tip's linear speed <= cart_speed_max (m/s).  Raises
    KinematicsError: -1022 when `righty` asks for a configuration change, -610 when the
    line leaves the workspace, -1021 when a joint would pass its limit on the way (J2 for a
    line passing closer to the J1 axis than the elbow can fold)."""
    q0 = np.array(q0, dtype=float)
    tool = np.eye(4) if tool is None else np.asarray(tool, dtype=float)
    untool = np.linalg.inv(tool)
    T1 = np.asarray(T1, dtype=float)
    vmax = np.asarray(vmax, float)
    amax = np.asarray(amax, float)
    config = kin.is_righty(q0)
    if righty is not None and kin.scara is not None and bool(righty) != config:
        raise KinematicsError(STRAIGHT_LINE_CONFIG, "*Straight-line motion can't alter configuration*")
    T0 = kin.fk(q0) @ tool
    p0, p1 = T0[:3, 3].copy(), T1[:3, 3].copy()
    R0 = T0[:3, :3].copy()
    length = float(np.linalg.norm(p1 - p0))
    rotvec = pin.log3(R0.T @ T1[:3, :3])
    if kin.arm_dof == 4:  # only the rotation about the vertical can be followed; a tilt is an error in ik
        rotvec = np.array([0.0, 0.0, rotvec[2]]) if kin._tilt_ok(T1[:3, :3] @ untool[:3, :3]) else rotvec
    angle = float(np.linalg.norm(rotvec))
    # The end point first: an unreachable target is reported as such.
    kin.ik(T1 @ untool, q0, righty=config)
    if length < 1e-9 and angle < 1e-9:
        return Trajectory.still(q0)
    if kin.scara is not None:
        s = kin.scara
        rail = kin.rail_offset(q0)  # the line is the arm's, from where the rail holds it
        _segment_clear_of_hole(kin, (T0 @ untool @ s.M4f_inv)[:3, 3] - rail, (T1 @ untool @ s.M4f_inv)[:3, 3] - rail,
                               config)

    n = max(2, int(math.ceil(length / WAYPOINT_SPACING)), int(math.ceil(angle / WAYPOINT_ANGLE))) + 1
    spline = _libs().toppra.SplineInterpolator
    for attempt in range(MAX_REFINEMENTS + 1):
        ss = np.linspace(0.0, 1.0, n)
        T = np.empty((n - 1, 4, 4))
        T[:] = np.eye(4)
        T[:, :3, :3] = R0 @ np.array([pin.exp3(u * rotvec) for u in ss[1:]])
        T[:, :3, 3] = p0 + ss[1:, None] * (p1 - p0)
        T[-1] = T1
        Q = np.vstack([q0, kin.ik_path(T @ untool, q0, righty=config)])
        # Extra path coordinate: distance travelled (m), limited to cart_speed_max.
        W = np.column_stack([Q, length * ss])
        path = spline(ss, W)
        # Deviation of the spline's tip path from the line, between the waypoints.
        probe = np.concatenate([(ss[:-1] + ss[1:]) / 2, ss[:-1] + (ss[1:] - ss[:-1]) / 4,
                                ss[:-1] + 3 * (ss[1:] - ss[:-1]) / 4])
        deviation = float(np.max(_distance_to_segment(_tip_positions(kin, path(probe)[:, :kin.dof], tool), p0, p1)))
        if deviation <= LINE_TOLERANCE:
            break
        n = 2 * n - 1
    else:
        raise KinematicsError.out_of_range(f"straight line not followed (deviation {deviation * 1e3:.3f} mm)")
    v_all = np.append(vmax, cart_speed_max if length > 0 else 1.0)
    a_all = np.append(amax, CART_ACCEL_UNLIMITED)
    timing = _parametrize(path, _grid(N_GRID_STRAIGHT), v_all, accel_bounds(W[-1] - W[0], a_all, accel, decel))
    # The joint columns of the same spline (its coefficients, not a second fit).
    q_path = _libs().PPoly.construct_fast(path.cspl.c[..., :kin.dof], path.cspl.x)
    return _trajectory(timing, q_path, q0, Q[-1])
