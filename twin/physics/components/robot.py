"""The robot: its MJCF is the cell's base spec; servo references in, joint state out; collisions.

The robot file's names, its joints in chain order and their <joint>_pos/_vel actuators are
kept; its root body is moved to the scene's base pose. Any serial robot with one position
and one velocity actuator per joint fits (the Cobra SCARA, the Cartesian gantry).  A
`[robot.rail]` makes the root body slide along a linear rail (a joint "rail" with its
servo, the last of the robot's joints; the kinematics' extra axis, docs/clients.md).

Collisions (docs/motion.md): every check the contacts of the robot's and the gripper's geoms
are examined. A robot geom touching the fixed cell, or touching a part other than as the
gripper allows (its jaws closing on it, holding it or just letting go; a suction cup on
it), is a collision: recorded as an event (kind "collision") and handed to the run loop,
which stops the robot and the program (`take_collisions`).
"""

from __future__ import annotations

from typing import Callable

import mujoco
import numpy as np

from ...controller.kinematics import LinearRail, RobotKinematics
from ..geometry import matrix_to_quat, vplus_to_matrix
from ..scene import load_model, resolve
from .base import ROBOT_CONAFFINITY, ROBOT_CONTYPE, CellContext, Component


class Robot(Component):
    section = "robot"

    def __init__(self, config, ctx: CellContext):
        super().__init__(config, ctx)
        self.model_path = resolve(config.model, ctx.scene_path, "robot.model")
        self.scene_path = ctx.scene_path
        self.base_T = vplus_to_matrix(config.base)

    def make_spec(self) -> mujoco.MjSpec:
        """The cell's spec starts as the robot's own file."""
        spec = load_model(self.config.model, self.scene_path, "robot.model")
        spec.modelname = "twin_cell"
        self.rail = _linear_rail(self.config.rail)
        self.kinematics = RobotKinematics.from_mjcf(self.model_path, rail=self.rail)
        # The robot's joints, in chain order (the robot file holds nothing else), then a rail.
        self.joint_names: list[str] = [j.name for j in spec.joints] + ([self.rail.name] if self.rail else [])
        return spec

    def build(self, spec: mujoco.MjSpec, ctx: CellContext) -> None:
        # Base pose on the table; the robot never sleeps (its servos move it).
        root = spec.worldbody.first_body()
        self.root_name = root.name
        root.pos = self.base_T[:3, 3]
        root.quat = matrix_to_quat(self.base_T[:3, :3])
        if self.rail is not None:
            self._add_rail(spec, root)
        # The moving tree's root (the base itself when it rides a rail).
        moving = root if self.rail is not None else root.first_body()
        moving.sleep = mujoco.mjtSleepPolicy.mjSLEEP_NEVER
        # MuJoCo counts the moving robot's contacts every step (a contact sensor on its
        # subtree, the gripper included: "found", at most one): most checks end there.
        spec.add_sensor(name=CONTACT_SENSOR, type=mujoco.mjtSensor.mjSENS_CONTACT,
                        objtype=mujoco.mjtObj.mjOBJ_XBODY, objname=moving.name, intprm=[1, 1, 1])
        self.gravity_compensate(spec)

    def _add_rail(self, spec: mujoco.MjSpec, root) -> None:
        """The base rides the rail: a slide joint on the root body, its position and velocity
        servo (gains for the ~20 kg that ride it; the feed-forward takes the inertia), and
        the rail beam under the base's travel (drawn only: the base glides above it)."""
        rail = self.rail
        root.add_joint(name=rail.name, type=mujoco.mjtJoint.mjJNT_SLIDE, axis=list(rail.direction),
                       range=[rail.lower, rail.upper], limited=mujoco.mjtLimited.mjLIMITED_TRUE,
                       damping=1.0, armature=0.1)
        joint = mujoco.mjtTrn.mjTRN_JOINT
        spec.add_actuator(name=f"{rail.name}_pos", target=rail.name, trntype=joint).set_to_position(kp=100000.0)
        spec.add_actuator(name=f"{rail.name}_vel", target=rail.name, trntype=joint).set_to_velocity(kv=2000.0)
        d = np.asarray(rail.direction)
        centre = self.base_T[:3, 3] + self.base_T[:3, :3] @ d * (rail.lower + rail.upper) / 2
        length = (rail.upper - rail.lower) / 2 + RAIL_BEAM_END
        spec.worldbody.add_geom(name=f"{rail.name}_beam", type=mujoco.mjtGeom.mjGEOM_BOX,
                                size=[length, RAIL_BEAM_WIDTH, RAIL_BEAM_HEIGHT / 2],
                                pos=centre - self.base_T[:3, 2] * RAIL_BEAM_HEIGHT / 2,
                                quat=matrix_to_quat(self.base_T[:3, :3] @ _frame_along(d)),
                                contype=0, conaffinity=0, group=2, rgba=[0.35, 0.37, 0.4, 1.0])

    @staticmethod
    def gravity_compensate(spec: mujoco.MjSpec) -> None:
        """The drives hold the arm's weight: gravity compensation on the robot (and gripper)
        bodies stands in for the servo's integral action / gravity feed-forward (the robot
        file's pure P+V servos otherwise sag J3 by ~0.12 mm, beyond the controller's FINE band)."""
        for body in spec.bodies:
            if body.name != "world":
                body.gravcomp = 1.0

    def bind(self, model: mujoco.MjModel, data: mujoco.MjData, ctx: CellContext) -> None:
        m = self.model = model
        self.data = data
        jids = [m.joint(n).id for n in self.joint_names]
        self.qadr = np.array([m.jnt_qposadr[j] for j in jids])
        self.dadr = np.array([m.jnt_dofadr[j] for j in jids])
        self._qdd_full = np.zeros(m.nv)  # scratch vectors for the acceleration feed-forward
        self._torque_full = np.zeros(m.nv)
        self.act_pos = np.array([m.actuator(f"{n}_pos").id for n in self.joint_names])
        self.act_vel = np.array([m.actuator(f"{n}_vel").id for n in self.joint_names])
        # The per-step servo writes go through slices where the indices are consecutive
        # (they are in the robot files): a slice assignment costs a third of an index array's.
        self._ctrl_pos, self._ctrl_vel, self._dofs = (_as_slice(self.act_pos), _as_slice(self.act_vel),
                                                      _as_slice(self.dadr))
        both = _as_slice(np.concatenate([self.act_pos, self.act_vel]))
        self._ctrl_both = both if isinstance(both, slice) else None
        self._feed_torque = np.zeros((0, len(self.dadr)))  # torque rows of the last `servo_feed`
        root = m.body(self.root_name).id
        robot_body = np.array([self._descends_from(b, root) and m.body_weldid[b] != 0 for b in range(m.nbody)])
        self.robot_geom = robot_body[m.geom_bodyid]  # moving robot geoms, gripper included
        self._robot_contact_bits(robot_body)
        self._contact_count = int(m.sensor_adr[m.sensor(CONTACT_SENSOR).id])  # in sensordata
        self._touching: set[tuple[int, int]] = set()
        self.collisions: list[dict] = []
        self._gripper = ctx.by_kind["gripper"]["gripper"]
        self.payload_torque = np.zeros(len(self.dadr))  # set by the gripper while it holds a part
        self._jacp = np.zeros((3, m.nv))
        self._mass_gather = self._mass_block_index()

    def _robot_contact_bits(self, robot_body: np.ndarray) -> None:
        """The moving robot's colliding geoms get the robot's contact bits (base.py), so that
        the part a grasp holds can stop touching it; the body-level masks follow."""
        m = self.model
        colliding = self.robot_geom & ((m.geom_contype != 0) | (m.geom_conaffinity != 0))
        m.geom_contype[colliding] = ROBOT_CONTYPE
        m.geom_conaffinity[colliding] = ROBOT_CONAFFINITY
        for b in np.flatnonzero(robot_body).tolist():
            geoms = m.geom_bodyid == b
            m.body_contype[b] = np.bitwise_or.reduce(m.geom_contype[geoms], initial=0)
            m.body_conaffinity[b] = np.bitwise_or.reduce(m.geom_conaffinity[geoms], initial=0)

    def home(self, location: list[float]) -> None:
        """Put the robot at the IK of `location` (RIGHTY), held there by its servos; a rail
        at 0, where the scene's base pose puts the base."""
        kin, d = self.kinematics, self.data
        seed = np.where(np.isfinite(kin.lower + kin.upper), (kin.lower + kin.upper) / 2, 0.0)
        seed[kin.arm_dof:] = 0.0
        q = kin.ik(vplus_to_matrix(location), seed, righty=True)
        d.qpos[self.qadr] = q
        d.ctrl[self.act_pos] = q
        d.ctrl[self.act_vel] = 0.0

    def _descends_from(self, body: int, root: int) -> bool:
        parent = self.model.body_parentid
        while body not in (0, root):
            body = int(parent[body])
        return body == root

    # ------------------------------------------------------------------ servo interface
    def qpos(self) -> np.ndarray:
        return self.data.qpos[self.qadr].copy()

    def qvel(self) -> np.ndarray:
        return self.data.qvel[self.dadr].copy()

    def set_servo(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray | None = None) -> None:
        ctrl = self.data.ctrl
        ctrl[self._ctrl_pos] = q
        ctrl[self._ctrl_vel] = qd
        applied = self.data.qfrc_applied
        dofs = self._dofs
        if qdd is None:
            applied[dofs] = self.payload_torque
            return
        self._qdd_full[dofs] = qdd
        mujoco.mj_mulM(self.model, self.data, self._torque_full, self._qdd_full)
        applied[dofs] = self._torque_full[dofs] + self.payload_torque

    def servo_feed(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> Callable[[int], None]:
        """The references of several physics steps at once (rows of q, qd, qdd): the function
        that sets row j's before step j, as `set_servo` does.  The inertia feed-forward is
        M qdd with the arm's mass matrix at the first step (it changes by well under a
        percent in the steps of one controller cycle)."""
        rows, cols, addresses = self._mass_gather
        block = np.zeros((len(self.dadr), len(self.dadr)))
        block[rows, cols] = block[cols, rows] = self.data.M[addresses]  # MuJoCo stores the lower triangle
        torque = self._feed_torque = qdd @ block.T + self.payload_torque  # `carry` keeps it current
        ctrl, applied, dofs = self.data.ctrl, self.data.qfrc_applied, self._dofs
        if self._ctrl_both is not None:  # positions and velocities side by side: one write a step
            rows, both = np.concatenate([q, qd], axis=1), self._ctrl_both

            def feed(j: int) -> None:
                ctrl[both] = rows[j]
                applied[dofs] = torque[j]
            return feed
        pos, vel = self._ctrl_pos, self._ctrl_vel

        def feed(j: int) -> None:
            ctrl[pos] = q[j]
            ctrl[vel] = qd[j]
            applied[dofs] = torque[j]
        return feed

    def _mass_block_index(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Where the arm's joint block of the mass matrix lies in MuJoCo's sparse `data.M`
        (its lower triangle, by rows: `M_rowadr`, `M_rownnz`, `M_colind`): the block's row
        and column of each entry, and the entry's address."""
        m, dofs = self.model, self.dadr.tolist()
        entries = []
        for a, dof in enumerate(dofs):
            start = int(m.M_rowadr[dof])
            for adr in range(start, start + int(m.M_rownnz[dof])):
                col = int(m.M_colind[adr])
                if col in dofs:
                    entries.append((a, dofs.index(col), adr))
        return tuple(np.array(column, dtype=int) for column in zip(*entries))

    def carry(self, part_body: int | None, holder_body: int = -1) -> None:
        """The drives take the weight of a held part (None: nothing held), as the servos'
        integral action does: the joint torques that hold its weight where it hangs on the
        arm (`holder_body`, at the part's centre of mass) are added to the servo's. The
        gripper's weld still carries the weight itself (what a grip or a cup must hold)."""
        torque = np.zeros(len(self.dadr))
        if part_body is not None:
            m, d = self.model, self.data
            mujoco.mj_jac(m, d, self._jacp, None, d.xipos[part_body], holder_body)
            torque = self._jacp[:, self.dadr].T @ (-m.body_mass[part_body] * m.opt.gravity)
        change = torque - self.payload_torque
        self.data.qfrc_applied[self.dadr] += change
        self._feed_torque += change  # the steps still to be fed carry it too
        self.payload_torque = torque

    # ------------------------------------------------------------------ collisions
    def check(self, t: float) -> None:
        """Record each new robot contact that is a collision (see the module docstring)."""
        touching = self._collisions_now(t)
        if not touching and not self._touching:
            return
        m, d, parts = self.model, self.data, self.ctx.parts
        for ours, other in sorted(touching - self._touching):
            part = int(parts.geom_part[other])
            event = self.ctx.event("collision", **{
                "robot_geom": m.geom(ours).name,
                "with": f"part {parts.instance_of[part]}" if part >= 0 else m.geom(other).name,
                "where": self.ctx.regions.region_of(d.geom_xpos[ours])})
            self.collisions.append(event)
        self._touching = touching

    def _collisions_now(self, t: float) -> set[tuple[int, int]]:
        """(robot geom, other geom) of each robot contact now that the gripper does not allow."""
        d = self.data
        if d.sensordata[self._contact_count] == 0.0:  # the robot touches nothing
            return set()
        ncon = d.ncon
        contact = d.contact  # each attribute read copies MuJoCo's arrays: read them once
        g = contact.geom[:ncon]
        robot = self.robot_geom[g]
        if not robot.any():  # most contacts are the parts' with the cell
            return set()
        mixed = (robot[:, 0] != robot[:, 1]) & (contact.dist[:ncon] < 0.0)
        if not mixed.any():
            return set()
        parts, gripper = self.ctx.parts, self._gripper
        pairs = np.where(robot[mixed, 0][:, None], g[mixed], g[mixed][:, ::-1])  # (ours, other)
        # A box on a pad makes up to 4 contacts: each geom pair is judged once.
        return {(ours, other) for ours, other in set(map(tuple, pairs.tolist()))
                if not gripper.contact_allowed(ours, int(parts.geom_part[other]), t)}


CONTACT_SENSOR = "twin_robot_contacts"
RAIL_BEAM_HEIGHT = 0.04  # m, between the bench and the base (a scene puts the base this high)
RAIL_BEAM_WIDTH = 0.07  # m, half width
RAIL_BEAM_END = 0.12  # m, beyond each end of the travel (half the carriage)


def _linear_rail(config) -> LinearRail | None:
    """The scene's [robot.rail] in SI units, for the kinematics (None: no rail)."""
    if config is None:
        return None
    d = np.asarray(config.direction, dtype=float)
    d = d / np.linalg.norm(d)
    return LinearRail(direction=(float(d[0]), float(d[1]), float(d[2])),
                      lower=config.travel[0] / 1000.0, upper=config.travel[1] / 1000.0,
                      max_velocity=config.speed / 1000.0, max_acceleration=config.acceleration / 1000.0,
                      axis_number=config.gpl_axis)


def _frame_along(d: np.ndarray) -> np.ndarray:
    """A rotation whose X axis is the unit vector d (the beam's long side)."""
    x = d / np.linalg.norm(d)
    helper = np.array([0.0, 0.0, 1.0]) if abs(x[2]) < 0.9 else np.array([0.0, 1.0, 0.0])
    y = np.cross(helper, x)
    y /= np.linalg.norm(y)
    return np.column_stack([x, y, np.cross(x, y)])


def _as_slice(indices: np.ndarray) -> slice | np.ndarray:
    """`indices` as a slice when they are consecutive and ascending, else unchanged."""
    if len(indices) and np.array_equal(indices, np.arange(indices[0], indices[0] + len(indices))):
        return slice(int(indices[0]), int(indices[0]) + len(indices))
    return indices
