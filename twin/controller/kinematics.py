"""Robot kinematics on pinocchio, built from the robot's MJCF.

`RobotKinematics` works in SI (m, rad) and in the robot base frame.  Forward
kinematics and Jacobians come from pinocchio.  Inverse kinematics:

* SCARA (detected from the model: two revolute arm joints, a prismatic one and a
  revolute wrist, all axes vertical, in either of the two orders robots use:
  revolute, revolute, prismatic, revolute as on the Cobra, or prismatic first, a
  vertical column carrying the arm, as on the PreciseFlex PF400): closed form for
  the requested arm configuration, with the link lengths and offsets read from
  the pinocchio model's joint placements, then a Newton refinement on the
  pinocchio model (normally zero or one step).
* any other chain (e.g. a Cartesian X/Y/Z/theta gantry): damped least squares
  on the pinocchio model from the seed.

A linear rail under the robot's base (`LinearRail`, from the scene) is an extra axis:
the last joint of the joint vector, not part of the arm's chain.  Cartesian poses
include it (the base frame is the robot's frame with the rail at 0), inverse
kinematics keeps it where the seed has it (the arm alone reaches the pose), and its
Jacobian column is zero: Cartesian motion never moves the rail, joint motion does.

A robot with 4 joints controls x, y, z and the rotation about the vertical; the
flange's orientation can only turn about the vertical from its home orientation
(the Cobra's flange points down, the PF400's horizontally): a target tilted by
more than `TILT_TOLERANCE` is out of range.

V+ errors raised as `KinematicsError` (code, text):

* -610 ``*Location out of range*``: the location cannot be reached (too far,
  too close to the J1 axis, tool not vertical).  Code and text as the project's
  table `twin/language/vplus/messages.py` (LOCATION_OUT_OF_RANGE, "(LRG)": the
  numbered list is not in the seeds).
* -1021 ``*Joint N limit stop*``: the location is reachable geometrically, but
  in the requested configuration joint N would be outside its range.  The V+
  guide uses "limit stop" (v17 L6958-6959, OVERLAP) but prints no message for
  it: code and text are twin-defined (next free after twin's -1020).
* -1022 ``*Straight-line motion can't alter configuration*`` (raised by the
  trajectory planner): text as we remember it from the V+ reference; the code is
  twin-defined.  Neither is in the seeds.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

LOCATION_OUT_OF_RANGE = -610  # "*Location out of range*" (messages.py, "(LRG)")
JOINT_LIMIT = -1021  # "*Joint N limit stop*" (twin-defined code and text)
STRAIGHT_LINE_CONFIG = -1022  # "*Straight-line motion can't alter configuration*" (twin-defined code)

TILT_TOLERANCE = 1e-4  # rad: a 4-axis robot cannot tilt its tool
POSITION_TOLERANCE = 1e-6  # m: IK must land this close
LANDED = 1e-10  # m and rad: `_refine` stops this close to the pose, and a closed form this close needs no refining
LIMIT_EPS = 1e-9  # joint units: slack on the joint limits


@dataclass(frozen=True)
class LinearRail:
    """A rail the robot's base rides on (SI units): its travel `direction` in the robot base
    frame, its range, 100 % speed and acceleration, and its axis number in GPL."""

    direction: tuple[float, float, float]
    lower: float
    upper: float
    max_velocity: float
    max_acceleration: float
    axis_number: int
    name: str = "rail"


class KinematicsError(Exception):
    """A V+ robot error: `.code` (int) and `.message` (the *text*)."""

    def __init__(self, code: int, message: str, joint: int | None = None):
        super().__init__(message)
        self.code = code
        self.message = message
        self.joint = joint  # 1-based joint number for joint-limit errors

    @classmethod
    def out_of_range(cls, detail: str = "") -> "KinematicsError":
        err = cls(LOCATION_OUT_OF_RANGE, "*Location out of range*")
        err.detail = detail
        return err

    @classmethod
    def joint_limit(cls, joint: int) -> "KinematicsError":
        return cls(JOINT_LIMIT, f"*Joint {joint} limit stop*", joint=joint)


def _wrap(a):
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


def _branch_nearest(value: float, seed: float, lo: float, hi: float, within: bool = True) -> float:
    """`value + 2 pi k` nearest `seed`; with `within`, among those inside [lo, hi] when any is."""
    two_pi = 2 * math.pi
    nearest = value + two_pi * round((seed - value) / two_pi)
    if not within or lo - LIMIT_EPS <= nearest <= hi + LIMIT_EPS:
        return nearest
    k_lo = math.ceil((lo - LIMIT_EPS - value) / two_pi)
    k_hi = math.floor((hi + LIMIT_EPS - value) / two_pi)
    inside = [value + two_pi * k for k in range(k_lo, k_hi + 1)]
    return min(inside, key=lambda c: abs(c - seed)) if inside else nearest


def _read_numeric(path: Path) -> tuple[str, dict[str, np.ndarray]]:
    root = ET.parse(path).getroot()
    model = root.get("model", "")
    out = {}
    for node in root.iter("numeric"):
        name, data = node.get("name"), node.get("data")
        if name and data:
            out[name] = np.array([float(v) for v in data.split()])
    return model, out


SCARA_LAYOUTS = {"RRPR": (0, 1, 2, 3), "PRRR": (1, 2, 0, 3)}  # joint kinds -> (shoulder, elbow, slide, wrist)


def _joint_kinds(model: pin.Model) -> str:
    """'R' or 'P' per joint of a 4-joint chain whose axes are all vertical, else ''."""
    data = model.createData()
    q0 = pin.neutral(model)
    pin.computeJointJacobians(model, data, q0)
    J = pin.getJointJacobian(model, data, 4, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
    ez = np.array([0.0, 0.0, 1.0])
    kinds = ""
    for i in range(4):
        lin, ang = J[:3, i], J[3:, i]
        if abs(abs(ang @ ez) - 1) < 1e-9:
            kinds += "R"
        elif np.linalg.norm(ang) < 1e-12 and abs(abs(lin @ ez) - 1) < 1e-9:
            kinds += "P"
        else:
            return ""
    return kinds


class _Scara:
    """Closed-form geometry of a SCARA, read from a pinocchio model at q = 0.  The joint
    indices (`shoulder`, `elbow_joint`, `slide`, `wrist`) follow the robot's layout."""

    def __init__(self, kin: "RobotKinematics"):
        model, data = kin.model, kin.model.createData()
        self.shoulder, self.elbow_joint, self.slide, self.wrist = SCARA_LAYOUTS[_joint_kinds(model)]
        q0 = pin.neutral(model)
        pin.forwardKinematics(model, data, q0)
        pin.updateFramePlacements(model, data)
        pin.computeJointJacobians(model, data, q0)
        J = pin.getJointJacobian(model, data, 4, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        # World direction of each joint axis at q = 0 (angular part for hinges, linear for the slide).
        self.s1, self.s2, self.s4 = (float(np.sign(J[5, i])) for i in (self.shoulder, self.elbow_joint, self.wrist))
        self.a3 = float(J[2, self.slide])  # dz of the wrist origin per unit of the slide
        o = [data.oMi[i].translation.copy() for i in range(5)]  # joint origins, o[i] of joint i (1-based)
        shoulder, elbow, wrist = (o[i + 1] for i in (self.shoulder, self.elbow_joint, self.wrist))
        self.p1 = shoulder[:2]
        d12, d24 = elbow[:2] - shoulder[:2], wrist[:2] - elbow[:2]
        self.l1, self.l2 = float(np.hypot(*d12)), float(np.hypot(*d24))
        self.alpha1 = math.atan2(d12[1], d12[0])  # world angle of link 1 at q = 0
        self.beta = math.atan2(d24[1], d24[0])  # world angle of link 2 at q = 0
        self.z4 = float(wrist[2])
        self.R4 = data.oMi[4].rotation.copy()
        self.M4f_inv = (data.oMi[4].inverse() * data.oMf[kin.frame_id]).inverse().homogeneous
        self.flange_in_j4 = (data.oMi[4].inverse() * data.oMf[kin.frame_id]).translation.copy()

    def elbow(self, q2) -> np.ndarray:
        """Angle from link 1 to link 2 (world, seen from above)."""
        return _wrap(self.beta - self.alpha1 + self.s2 * np.asarray(q2))

    def closed_form(self, T: np.ndarray, righty: bool) -> tuple[np.ndarray, ...]:
        """Closed-form IK of flange poses T (n x 4 x 4) in the arm configuration `righty`:
        shoulder, elbow and slide joints, the yaw psi of J4's frame from its home
        orientation, and the elbow cosine c (|c| > 1: out of reach), each an n-array.  The
        shoulder and elbow are on their principal turn (see `RobotKinematics._scara_branches`)."""
        T4 = T @ self.M4f_inv
        P = T4[:, :3, 3]
        Rrel = T4[:, :3, :3] @ self.R4.T
        psi = np.arctan2(Rrel[:, 1, 0], Rrel[:, 0, 0])
        dx, dy = P[:, 0] - self.p1[0], P[:, 1] - self.p1[1]
        c = (dx * dx + dy * dy - self.l1 ** 2 - self.l2 ** 2) / (2 * self.l1 * self.l2)
        gamma = np.arccos(np.clip(c, -1.0, 1.0))
        if not righty:
            gamma = -gamma
        theta1 = np.arctan2(dy, dx) - np.arctan2(self.l2 * np.sin(gamma), self.l1 + self.l2 * np.cos(gamma))
        q1 = self.s1 * (theta1 - self.alpha1)
        q2 = self.s2 * (gamma - (self.beta - self.alpha1))
        q3 = (P[:, 2] - self.z4) / self.a3
        return q1, q2, q3, psi, c

    @staticmethod
    def valid(model: pin.Model) -> bool:
        return model.nq == 4 and model.nv == 4 and _joint_kinds(model) in SCARA_LAYOUTS

    def joints(self, shoulder, elbow, slide, wrist) -> np.ndarray:
        """The joint vector in the robot's order."""
        q = np.empty(4)
        q[[self.shoulder, self.elbow_joint, self.slide, self.wrist]] = shoulder, elbow, slide, wrist
        return q


class RobotKinematics:
    """Kinematics of one robot (SI units, robot base frame)."""

    def __init__(self, model: pin.Model, flange_frame: str, max_velocity, max_acceleration, name: str = "",
                 ready=None, payload_kg=None, rail: LinearRail | None = None,
                 controller_figures: dict[str, np.ndarray] | None = None):
        self.model = model  # the arm's chain (pinocchio); a rail is not in it
        self.data = model.createData()
        self.name = name
        if not model.existFrame(flange_frame):
            raise ValueError(f"no frame {flange_frame!r} in the model")
        self.frame_id = model.getFrameId(flange_frame)
        n = self.arm_dof = model.nv
        self.rail = rail
        self.rail_direction = np.zeros(3) if rail is None else np.asarray(rail.direction, dtype=float)
        self.joint_names: list[str] = [model.names[i] for i in range(1, model.njoints)]
        self.lower = np.array(model.lowerPositionLimit, dtype=float)
        self.upper = np.array(model.upperPositionLimit, dtype=float)
        self.max_velocity = np.asarray(max_velocity, dtype=float)
        self.max_acceleration = np.asarray(max_acceleration, dtype=float)
        self.revolute = np.array([model.joints[i].shortname().startswith(("JointModelR", "JointModelRevolute"))
                                  for i in range(1, model.njoints)])
        # GPL axis numbers of the joints: 1 .. n for the arm, the rail's own (PreciseFlex: 6).
        self.axis_numbers: tuple[int, ...] = tuple(range(1, n + 1))
        neutral = pin.neutral(model)
        if rail is not None:
            self.joint_names.append(rail.name)
            self.lower = np.append(self.lower, rail.lower)
            self.upper = np.append(self.upper, rail.upper)
            self.revolute = np.append(self.revolute, False)
            self.axis_numbers += (rail.axis_number,)
            neutral = np.append(neutral, 0.0)
            if ready is not None and len(ready) == n:
                ready = np.append(ready, 0.0)
        # READY: the joints of the robot's READY location (V+ READY), the neutral pose unless given.
        self.ready = np.clip(neutral if ready is None else np.asarray(ready, dtype=float), self.lower, self.upper)
        self.payload_kg = None if payload_kg is None else tuple(float(v) for v in payload_kg)  # rated, maximum
        # Figures a controller reports about the robot that the planner does not use (the GPL
        # parameter database's robot type, servo gripper axis, Cartesian references), by name.
        self.controller_figures: dict[str, np.ndarray] = dict(controller_figures or {})
        if self.max_velocity.shape != (n,) or self.max_acceleration.shape != (n,):
            raise ValueError("max_velocity/max_acceleration need one value per joint")
        if rail is not None:
            self.max_velocity = np.append(self.max_velocity, rail.max_velocity)
            self.max_acceleration = np.append(self.max_acceleration, rail.max_acceleration)
        self.scara = _Scara(self) if _Scara.valid(model) else None
        # Task rows of the 6-D frame velocity (LOCAL_WORLD_ALIGNED): x, y, z, wz for 4 joints.
        self._rows = np.array([0, 1, 2, 5]) if n == 4 else np.arange(6)
        self._home_rotation = self._arm_fk(pin.neutral(model))[:3, :3].copy()

    @classmethod
    def from_mjcf(cls, path: str | Path, flange_site: str = "flange",
                  rail: LinearRail | None = None) -> "RobotKinematics":
        """Pinocchio model from the MJCF (robot = first top-level body); joint speed and
        acceleration limits from the `<numeric>` entries `<model>/max_velocity` and
        `<model>/max_acceleration` (pinocchio does not read them); the READY joints from
        `<model>/ready` and the rated and maximum payload (kg) from `<model>/payload`;
        `<model>/gpl_*` entries as `controller_figures` (without the prefix);
        `rail`: the linear rail the scene mounts the robot on, if any."""
        path = Path(path)
        model = pin.buildModelFromMJCF(str(path))
        name, numeric = _read_numeric(path)
        try:
            vmax = numeric[f"{name}/max_velocity"]
            amax = numeric[f"{name}/max_acceleration"]
        except KeyError as missing:
            raise ValueError(f"{path}: no <numeric name={missing}> (joint limits for the planner)") from None
        prefix = f"{name}/gpl_"
        figures = {key[len(prefix):]: value for key, value in numeric.items() if key.startswith(prefix)}
        return cls(model, flange_site, vmax, amax, name, ready=numeric.get(f"{name}/ready"),
                   payload_kg=numeric.get(f"{name}/payload"), rail=rail, controller_figures=figures)

    # ------------------------------------------------------------ forward
    @property
    def dof(self) -> int:
        return len(self.lower)

    def _arm_fk(self, q_arm: np.ndarray) -> np.ndarray:
        pin.forwardKinematics(self.model, self.data, np.asarray(q_arm, dtype=float))
        return pin.updateFramePlacement(self.model, self.data, self.frame_id).homogeneous

    def rail_offset(self, q: np.ndarray) -> np.ndarray:
        """Where the rail has carried the arm (m, base frame) at joints q; zero without a rail."""
        if self.rail is None:
            return np.zeros(3)
        return self.rail_direction * float(q[self.arm_dof])

    def fk(self, q: np.ndarray) -> np.ndarray:
        """4x4 flange pose in the robot base frame, translation in metres."""
        q = np.asarray(q, dtype=float)
        T = self._arm_fk(q[: self.arm_dof])
        if self.rail is not None:
            T = T.copy()
            T[:3, 3] += self.rail_offset(q)
        return T

    def fk_positions(self, Q: np.ndarray) -> np.ndarray:
        """Flange positions (n x 3, m) for joint vectors Q (n x dof); vectorised for a SCARA."""
        Q = np.atleast_2d(np.asarray(Q, dtype=float))
        s = self.scara
        if s is None:
            return np.array([self.fk(q)[:3, 3] for q in Q])
        q1, q2, q3, q4 = Q[:, s.shoulder], Q[:, s.elbow_joint], Q[:, s.slide], Q[:, s.wrist]
        t1 = s.alpha1 + s.s1 * q1
        t2 = s.beta + s.s1 * q1 + s.s2 * q2
        psi = s.s1 * q1 + s.s2 * q2 + s.s4 * q4
        out = np.empty((len(Q), 3))
        # Flange offset from the J4 origin, turned with the J4 frame about the vertical.
        r = s.R4 @ s.flange_in_j4
        c, si = np.cos(psi), np.sin(psi)
        out[:, 0] = s.p1[0] + s.l1 * np.cos(t1) + s.l2 * np.cos(t2) + c * r[0] - si * r[1]
        out[:, 1] = s.p1[1] + s.l1 * np.sin(t1) + s.l2 * np.sin(t2) + si * r[0] + c * r[1]
        out[:, 2] = s.z4 + s.a3 * q3 + r[2]
        if self.rail is not None:
            out += np.outer(Q[:, self.arm_dof], self.rail_direction)
        return out

    def jacobian(self, q: np.ndarray) -> np.ndarray:
        """6 x dof Jacobian of the flange: rows vx, vy, vz (flange origin) and wx, wy, wz,
        all in the base frame axes (pinocchio LOCAL_WORLD_ALIGNED).  A rail's column is
        zero: what solves Cartesian velocities with it leaves the rail still."""
        q = np.asarray(q, dtype=float)
        J = pin.computeFrameJacobian(self.model, self.data, q[: self.arm_dof], self.frame_id,
                                     pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        if self.rail is not None:
            J = np.hstack([J, np.zeros((6, 1))])
        return J

    def translation_rates(self, q: np.ndarray, velocity_m_s: np.ndarray) -> np.ndarray:
        """Joint speeds that move the flange at `velocity_m_s` (base frame) without turning
        it: the Jacobian's task rows solved, in the least-squares sense where they are not
        square or singular (a stretched arm).  The rows a four-axis arm cannot move in (tilt)
        are zero, so this is the least-squares answer of the whole Jacobian, for a quarter
        of its cost (belt tracking asks every servo step)."""
        J = self.jacobian(q)[self._rows]
        twist = np.zeros(6)
        twist[:3] = velocity_m_s
        twist = twist[self._rows]
        if J.shape[0] == J.shape[1]:
            try:
                return np.linalg.solve(J, twist)
            except np.linalg.LinAlgError:
                pass
        return np.linalg.lstsq(J, twist, rcond=None)[0]

    def is_righty(self, q: np.ndarray) -> bool:
        """SCARA arm configuration: RIGHTY when the elbow turns link 2 counter-clockwise
        from link 1 seen from above (for the Cobra model: J2 > 0, for the PF400: J3 below
        180 deg; the stretched arm counts as RIGHTY).  Robots without an elbow
        configuration report True."""
        if self.scara is None:
            return True
        return bool(self.scara.elbow(q[self.scara.elbow_joint]) >= 0.0)

    def within_limits(self, q: np.ndarray) -> bool:
        return bool(np.all(q >= self.lower - LIMIT_EPS) and np.all(q <= self.upper + LIMIT_EPS))

    def check_limits(self, q: np.ndarray) -> None:
        bad = np.nonzero((q < self.lower - LIMIT_EPS) | (q > self.upper + LIMIT_EPS))[0]
        if len(bad):
            raise KinematicsError.joint_limit(int(bad[0]) + 1)

    # ------------------------------------------------------------ inverse
    def _tilt_ok(self, R: np.ndarray) -> bool:
        """For 4 joints the flange may only turn about the vertical from its home orientation."""
        if self.model.nv != 4:
            return True
        return float((R @ self._home_rotation.T)[2, 2]) >= math.cos(TILT_TOLERANCE)

    def ik(self, T: np.ndarray, q_seed: np.ndarray, righty: bool | None = None, *,
           continuous: bool = False, single: bool = False) -> np.ndarray:
        """Joint vector (SI) putting the flange at `T` (4x4, metres, base frame).

        `righty`: the SCARA arm configuration (None keeps the seed's).  Revolute joints
        that can turn more than one way (J4 multi-turn, J1 if its range allows) take the
        solution nearest the seed within the limits (V+ MULTIPLE); with `single` (V+
        SINGLE) the wrist, the last joint, is kept within +/-180 deg.  With `continuous`
        (straight-line motion), the nearest solution is taken and a joint limit is an error.
        Raises KinematicsError (-610 out of range, -1021 joint limit)."""
        T = np.asarray(T, dtype=float)
        q_seed = np.asarray(q_seed, dtype=float)
        if not self._tilt_ok(T[:3, :3]):
            raise KinematicsError.out_of_range("tool not vertical")
        n = self.arm_dof
        if self.rail is not None:  # the arm reaches the pose from where the rail is
            T = T.copy()
            T[:3, 3] -= self.rail_offset(q_seed)
        if self.scara is not None:
            q = self._scara_ik(T, q_seed, self.is_righty(q_seed) if righty is None else righty, continuous)
            if not self._lands(T, q):
                q = self._refine(T, q)
        else:
            q = self._refine(T, q_seed[:n].copy())
        if single and self.revolute[n - 1]:
            q[n - 1] = float(_wrap(q[n - 1]))
        q = np.concatenate([q, q_seed[n:]])
        self.check_limits(q)
        return q

    def ik_path(self, Ts: np.ndarray, q_seed: np.ndarray, righty: bool | None = None) -> np.ndarray:
        """Joint vectors (n x dof) for the flange poses `Ts` (n x 4 x 4) of a continuous motion:
        row i is `ik(Ts[i], row i - 1, righty, continuous=True)`, row -1 being `q_seed`.

        For a SCARA the closed form runs on all the poses at once (numpy), each multi-turn
        joint on the branch nearest the previous pose, and the result is checked with the
        vectorised forward kinematics.  A pose that is out of reach, past a joint limit or
        not landed on within `_refine`'s tolerance sends the whole path through `ik` one
        pose at a time, which raises that pose's error as a single `ik` would."""
        Ts = np.asarray(Ts, dtype=float)
        q_seed = np.asarray(q_seed, dtype=float)
        if self.scara is not None and len(Ts):
            Q = self._scara_ik_path(Ts, q_seed, self.is_righty(q_seed) if righty is None else righty)
            if Q is not None:
                return Q
        out = np.empty((len(Ts), self.dof))
        q = q_seed
        for i, T in enumerate(Ts):
            q = out[i] = self.ik(T, q, righty=righty, continuous=True)
        return out

    def _scara_ik_path(self, Ts: np.ndarray, seed: np.ndarray, righty: bool) -> np.ndarray | None:
        """`ik_path` for a SCARA; None when a pose needs `ik`'s own handling."""
        s = self.scara
        tilt_ok = Ts[:, 2, :3] @ self._home_rotation[2, :] >= math.cos(TILT_TOLERANCE)
        arm = Ts.copy()
        arm[:, :3, 3] -= self.rail_offset(seed)  # the arm reaches the poses from where the rail is
        raw1, raw2, q3, psi, c = s.closed_form(arm, righty)
        if not (np.all(tilt_ok) and np.all(np.abs(c) <= 1 + 1e-12)):
            return None
        Q = np.empty((len(Ts), self.dof))
        Q[:, self.arm_dof:] = seed[self.arm_dof:]  # a rail stays where it is
        Q[:, s.slide] = q3
        q1, q4 = float(seed[s.shoulder]), float(seed[s.wrist])
        for k, pose in enumerate(zip(raw1.tolist(), raw2.tolist(), psi.tolist())):
            q1, q2, q4 = self._scara_branches(*pose, q1, q4, within=False)
            Q[k, s.shoulder], Q[k, s.elbow_joint], Q[k, s.wrist] = q1, q2, q4
        if np.any(Q < self.lower - LIMIT_EPS) or np.any(Q > self.upper + LIMIT_EPS):
            return None
        # The closed form is exact for a model `_Scara.valid` accepts (about 1e-15 m on the
        # Cobra and the PF400); `_refine` would stop at once.  J4 is built from the yaw.
        if not np.all(np.abs(self.fk_positions(Q) - Ts[:, :3, 3]) < LANDED):
            return None
        return Q

    def _scara_branches(self, q1, q2, psi, seed1, seed4, within: bool) -> tuple[float, float, float]:
        """Shoulder, elbow and wrist of one closed-form solution: the shoulder and the wrist
        on the turn nearest the seed's (within the limits with `within`), the elbow (not
        multi-turn) nearest zero within its limits."""
        s = self.scara
        lo, hi = self.lower, self.upper
        i1, i2, i4 = s.shoulder, s.elbow_joint, s.wrist
        q1 = _branch_nearest(q1, seed1, lo[i1], hi[i1], within)
        q2 = _branch_nearest(q2, 0.0, lo[i2], hi[i2], True)
        q4 = _branch_nearest(s.s4 * (psi - s.s1 * q1 - s.s2 * q2), seed4, lo[i4], hi[i4], within)
        return q1, q2, q4

    def _scara_ik(self, T, seed, righty: bool, continuous: bool) -> np.ndarray:
        s = self.scara
        q1, q2, q3, psi, c = (float(v[0]) for v in s.closed_form(T[None], righty))
        if c > 1 + 1e-12:
            raise KinematicsError.out_of_range("beyond the reach of the arm")
        if c < -1 - 1e-12:
            raise KinematicsError.out_of_range("too close to the J1 axis")
        q1, q2, q4 = self._scara_branches(q1, q2, psi, seed[s.shoulder], seed[s.wrist], within=not continuous)
        return s.joints(q1, q2, q3, q4)

    def _lands(self, T: np.ndarray, q_arm: np.ndarray) -> bool:
        """The arm's flange at q_arm is where T puts it, to LANDED (what `_refine` asks).
        A SCARA's closed form is exact on a model `_Scara.valid` accepts (about 1e-15 m on
        the Cobra and the PF400) and builds J4 from T's yaw, so `_refine` would only check
        it, at about ten times the cost of this one forward kinematics (belt tracking solves
        an IK every servo step)."""
        return bool(np.all(np.abs(self._arm_fk(q_arm)[:3, 3] - T[:3, 3]) < LANDED))

    def _task_error(self, T: np.ndarray, M: pin.SE3) -> np.ndarray:
        e = np.empty(6)
        e[:3] = T[:3, 3] - M.translation
        e[3:] = pin.log3(T[:3, :3] @ M.rotation.T)
        return e[self._rows]

    def _refine(self, T: np.ndarray, q: np.ndarray, iterations: int = 50) -> np.ndarray:
        """Newton / damped least squares on the pinocchio model, in the task rows."""
        model, data, fid = self.model, self.data, self.frame_id
        q = q.copy()
        for _ in range(iterations):
            pin.forwardKinematics(model, data, q)
            M = pin.updateFramePlacement(model, data, fid)
            e = self._task_error(T, M)
            if np.linalg.norm(e[:3]) < LANDED and np.all(np.abs(e[3:]) < LANDED):
                return q
            J = pin.computeFrameJacobian(model, data, q, fid, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)[self._rows]
            lam = 1e-10 if self.scara is not None else 1e-6
            dq = J.T @ np.linalg.solve(J @ J.T + lam * np.eye(len(e)), e)
            q = q + dq
            if self.scara is None:
                q = np.clip(q, self.lower[: self.arm_dof], self.upper[: self.arm_dof])
        pin.forwardKinematics(model, data, q)
        M = pin.updateFramePlacement(model, data, fid)
        if np.linalg.norm(T[:3, 3] - M.translation) > POSITION_TOLERANCE:
            raise KinematicsError.out_of_range("no converged solution")
        return q
