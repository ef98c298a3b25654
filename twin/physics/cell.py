"""The physical cell: robot + gripper + feeder + outfeed belt + bin + parts, in MuJoCo.

Built from a scene file (``scenes/*.toml``) with ``mujoco.MjSpec``:

* the robot MJCF is the base spec (its names, its joints in chain order and their
  <joint>_pos/_vel actuators, are kept), its root body moved to the scene's base pose; any
  serial robot with one position and one velocity actuator per joint fits (the Cobra SCARA,
  the Cartesian gantry);
* the gripper MJCF is attached at the robot's flange site with a prefix;
* table, nest, belt (a static box with ``surfacevel``), bin and a pool of parts are added;
* one inactive weld per part (gripper palm -> part) is declared for grasping.

Grasping is by friction, made robust with a weld that engages only from real contact:
when the gripper is commanded closed and BOTH pads touch the same part, the current
relative pose is written into the weld and the weld is activated; it is released when
the gripper opens, or when the net force the gripper applies to the part (weld plus jaw
contacts) exceeds the friction capacity 2 * mu * grip force (slip: the part is dropped
and falls).

Collisions (docs/motion.md): every check interval the contacts of the robot's and the
gripper's geoms are examined.  A robot geom touching the fixed cell, or touching a part
other than with its jaws while they close on it, hold it or have just let go of it, is a
collision: it is recorded as an event (kind "collision") and handed to the run loop, which
stops the robot and the program (`take_collisions`).

Units: SI inside (m, rad, kg, N, s); reports give positions in mm.
"""

from __future__ import annotations

import math
from pathlib import Path

import mujoco
import trimesh
import numpy as np

from ..controller.kinematics import RobotKinematics
from .camera import add_camera, cameras_of
from .geometry import MM, matrix_to_quat, vplus_to_matrix, yaw_quat
from .regions import Regions
from .scene import load_scene, resolve

PARK_Z = -0.5  # m: pooled parts wait under the floor, contacts off, gravity compensated
GRASP_WINDOW_S = 0.3  # s after a close command during which a grasp may engage
SLIP_GRACE_S = 0.05  # s after a grasp before slip is checked (grip force builds up)
FLOOR_CHECK_S = 0.1  # s between checks for parts on the floor / at rest in the bin
# Contact bits: static cell + robot geoms use 1/1. Live parts collide with both bits; parts
# retired at rest in the bin (type 2, affinity 0) touch only live parts.
LIVE_CONTYPE, LIVE_CONAFFINITY = 1, 3
RETIRED_CONTYPE, RETIRED_CONAFFINITY = 2, 0
RETIRE_SPEED = 2e-3  # m/s and rad/s: a part in the bin slower than this ...
RETIRE_CHECKS = 3  # ... at this many floor checks in a row (0.1 s apart) retires
RETIRED_DAMPING = (1e5, 100.0)  # N s/m and N m s/rad on a retired part's free joint (~um/s under a part's weight)
RELEASE_GRACE_S = 0.5  # s after the jaws let go of a part during which they may still touch it


class Cell:
    """A MuJoCo model of the work cell and the physics-side logic (feeder, grasp, slip).

    Attributes: ``model``/``data`` (MuJoCo), ``scene`` (parsed TOML), ``timestep`` (s),
    ``robot_joint_names``, ``kinematics`` (the robot's pinocchio model), ``seed`` (feeder
    seed in use), ``regions``.
    """

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_scene(cls, path: str | Path, seed: int | None = None) -> "Cell":
        """Load a scene file; ``seed`` overrides the scene's feeder seed."""
        path = Path(path)
        return cls(load_scene(path), path, seed)

    def __init__(self, scene: dict, scene_path: Path, seed: int | None = None):
        self.scene = scene
        self.scene_path = Path(scene_path)
        feeder = scene["feeder"]
        self.seed: int = int(seed if seed is not None else feeder.get("seed", 0))
        self.regions = Regions(scene["regions"])
        self._build_model()
        self._init_runtime()

    def _build_model(self) -> None:
        sc = self.scene
        phys = sc.get("physics", {})
        self.robot_model_path = resolve(sc["robot"]["model"], self.scene_path)
        spec = mujoco.MjSpec.from_file(str(self.robot_model_path))
        spec.modelname = "twin_cell"
        # The robot's joints, in chain order (the robot file holds nothing else).
        self.robot_joint_names: list[str] = [j.name for j in spec.joints]
        self.sleep_enabled = bool(phys.get("sleep", True))

        # Options.
        spec.option.timestep = float(phys.get("timestep", 0.002))
        integrators = {"implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST,
                       "implicit": mujoco.mjtIntegrator.mjINT_IMPLICIT,
                       "euler": mujoco.mjtIntegrator.mjINT_EULER,
                       "rk4": mujoco.mjtIntegrator.mjINT_RK4}
        spec.option.integrator = integrators[phys.get("integrator", "implicitfast")]
        if self.sleep_enabled:
            spec.option.enableflags |= int(mujoco.mjtEnableBit.mjENBL_SLEEP)

        # Robot base pose on the table; the robot never sleeps (its servos move it).
        robot_root = spec.worldbody.first_body()
        self._robot_root = robot_root.name
        self._base_T = vplus_to_matrix(sc["robot"].get("base", [0, 0, 0, 0, 0, 0]))
        robot_root.pos = self._base_T[:3, 3]
        robot_root.quat = matrix_to_quat(self._base_T[:3, :3])
        # The moving tree's root (first body with a joint under the static base).
        robot_root.first_body().sleep = mujoco.mjtSleepPolicy.mjSLEEP_NEVER

        # Gripper at the flange.
        g = sc["gripper"]
        gspec = mujoco.MjSpec.from_file(str(resolve(g["model"], self.scene_path)))
        self._gp = g.get("prefix", "gripper/")
        spec.attach(gspec, prefix=self._gp, site=spec.site(g.get("site", "flange")))

        # The drives hold the arm's weight: gravity compensation on the robot and gripper bodies
        # stands in for the servo's integral action / gravity feed-forward (the robot file's
        # pure P+V servos otherwise sag J3 by ~0.12 mm, beyond the controller's FINE band).
        for body in spec.bodies:
            if body.name != "world":
                body.gravcomp = 1.0

        wb = spec.worldbody
        spec.visual.headlight.ambient = [0.4, 0.4, 0.4]
        wb.add_light(name="cell_light", pos=[0.2, 0.2, 2.5], dir=[0, 0, -1], diffuse=[0.6, 0.6, 0.6])
        wb.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[3, 3, 0.05],
                    rgba=[0.5, 0.5, 0.52, 1])

        # Table.
        t = sc["table"]
        self.table_top_z = (t["center"][2] + t["size"][2] / 2) / MM
        wb.add_geom(name="table", type=mujoco.mjtGeom.mjGEOM_BOX, pos=np.array(t["center"]) / MM,
                    size=np.array(t["size"]) / MM / 2, rgba=[0.62, 0.5, 0.38, 1])

        # Feeder nest: a plate on a pedestal, top face at the nest pose.
        f = sc["feeder"]
        nest = np.array(f["nest"], dtype=float) / MM
        nsize = np.array(f.get("nest_size", [44.0, 44.0]), dtype=float) / MM
        h = nest[2] - self.table_top_z
        wb.add_geom(name="nest", type=mujoco.mjtGeom.mjGEOM_BOX,
                    pos=[nest[0], nest[1], self.table_top_z + h / 2],
                    quat=yaw_quat(math.radians(f.get("nest_yaw", 0.0))),
                    size=[nsize[0] / 2, nsize[1] / 2, h / 2], rgba=[0.25, 0.45, 0.3, 1])
        self._nest_top = nest

        # Outfeed belt: a thin static box with surfacevel (moves what touches it, any face),
        # side rails, and a support that collides with nothing.
        c = sc["conveyor"]
        top = np.array(c["top_center"], dtype=float) / MM
        width, length, thick = (v / MM for v in c["size"])
        d = np.array(c.get("direction", [1.0, 0.0]), dtype=float)
        d /= np.linalg.norm(d)
        yaw = math.atan2(d[1], d[0])
        q = yaw_quat(yaw)
        speed = float(c["speed"]) / MM
        belt = wb.add_geom(name="belt", type=mujoco.mjtGeom.mjGEOM_BOX, pos=top - [0, 0, thick / 2],
                           quat=q, size=[length / 2, width / 2, thick / 2], rgba=[0.15, 0.15, 0.15, 1],
                           friction=[0.8, 0.005, 0.0001])
        belt.surfacevel = np.array([speed, 0.0, 0.0, 0.0, 0.0, 0.0])  # geom frame: local x = travel direction (checked by test)
        rail_h = float(c.get("rail_height", 8.0)) / MM
        side = np.array([-d[1], d[0], 0.0])
        for k, s in (("left", 1.0), ("right", -1.0)):
            wb.add_geom(name=f"belt_rail_{k}", type=mujoco.mjtGeom.mjGEOM_BOX,
                        pos=top + s * side * (width / 2 + 0.004) + [0, 0, (rail_h - thick) / 2], quat=q,
                        size=[length / 2, 0.004, (rail_h + thick) / 2], rgba=[0.7, 0.7, 0.72, 1])
        frame_h = top[2] - thick - self.table_top_z
        if frame_h > 0:
            wb.add_geom(name="belt_frame", type=mujoco.mjtGeom.mjGEOM_BOX, contype=0, conaffinity=0,
                        pos=[top[0], top[1], self.table_top_z + frame_h / 2], quat=q,
                        size=[length / 2 * 0.95, width / 2, frame_h / 2], rgba=[0.4, 0.4, 0.45, 1])
        self.belt_speed = speed

        # Bin: floor + four walls, inner floor at floor_center.
        b = sc["bin"]
        fc = np.array(b["floor_center"], dtype=float) / MM
        ix, iy, ih = (v / MM for v in b["inner_size"])
        w = float(b.get("wall", 8.0)) / MM
        col = [0.2, 0.3, 0.6, 1]
        wb.add_geom(name="bin_floor", type=mujoco.mjtGeom.mjGEOM_BOX, pos=fc + [0, 0, w / 2 - w],
                    size=[ix / 2 + w, iy / 2 + w, w / 2], rgba=col)
        for name, pos, size in (
            ("bin_wall_xn", [-(ix + w) / 2, 0, ih / 2], [w / 2, iy / 2 + w, ih / 2]),
            ("bin_wall_xp", [(ix + w) / 2, 0, ih / 2], [w / 2, iy / 2 + w, ih / 2]),
            ("bin_wall_yn", [0, -(iy + w) / 2, ih / 2], [ix / 2, w / 2, ih / 2]),
            ("bin_wall_yp", [0, (iy + w) / 2, ih / 2], [ix / 2, w / 2, ih / 2]),
        ):
            wb.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_BOX, pos=fc + pos, size=size, rgba=col)
        spreader = b.get("spreader")
        if spreader is not None:
            self._add_spreader(spec, fc, spreader)
        if b.get("stand", False) and fc[2] - w > 0.01:
            hs = fc[2] - w
            wb.add_geom(name="bin_stand", type=mujoco.mjtGeom.mjGEOM_BOX, pos=[fc[0], fc[1], hs / 2],
                        size=[ix / 2, iy / 2, hs / 2], rgba=[0.45, 0.45, 0.48, 1])

        # Part pool: free bodies parked under the floor, no contacts, gravity compensated.
        p = sc["part"]
        half = np.array(p["size"], dtype=float) / MM / 2
        self.part_half = half
        npool = int(f["pool"])
        self._npool = npool
        friction = float(p.get("friction", 0.5))
        for i in range(npool):
            body = wb.add_body(name=f"part_{i}", pos=self._park_pos(i), gravcomp=1.0)
            if self.sleep_enabled:
                body.sleep = mujoco.mjtSleepPolicy.mjSLEEP_INIT
            body.add_freejoint(name=f"part_{i}_free")
            body.add_geom(name=f"part_{i}_geom", type=mujoco.mjtGeom.mjGEOM_BOX, size=half,
                          mass=float(p["mass"]), friction=[friction, 0.005, 0.0001],
                          contype=0, conaffinity=0, rgba=p.get("rgba", [0.9, 0.55, 0.1, 1.0]))
            spec.add_equality(name=f"grasp_{i}", type=mujoco.mjtEq.mjEQ_WELD,
                              objtype=mujoco.mjtObj.mjOBJ_BODY, name1=f"{self._gp}gripper_base",
                              name2=f"part_{i}", active=False, solref=[0.004, 1.0])

        self.cameras = cameras_of(sc)  # [[camera]] components
        for camera in self.cameras:
            add_camera(spec, camera)

        self.spec = spec
        self.model = spec.compile()
        self.data = mujoco.MjData(self.model)

    @staticmethod
    def _add_spreader(spec: mujoco.MjSpec, floor_center: np.ndarray, cfg: dict) -> None:
        """A spreader cone on the bin floor under the drop point (as in hoppers and bins fed
        from one spout): a part landing on the apex slides off in the direction its centre of
        mass leans, so the parts heap around the cone instead of stacking into one column
        that grows back up to the belt."""
        radius, height = float(cfg["radius"]) / MM, float(cfg["height"]) / MM
        centre = np.array(cfg.get("center", floor_center * MM), dtype=float) / MM
        cone = trimesh.creation.cone(radius=radius, height=height, sections=32)
        spec.add_mesh(name="bin_spreader", uservert=cone.vertices.flatten(),
                      userface=cone.faces.flatten())
        spec.worldbody.add_geom(name="bin_spreader", type=mujoco.mjtGeom.mjGEOM_MESH,
                                meshname="bin_spreader", pos=[centre[0], centre[1], floor_center[2]],
                                rgba=[0.3, 0.4, 0.7, 1])

    @staticmethod
    def _park_pos(i: int) -> list[float]:
        return [-1.0 + 0.06 * (i % 20), -1.5 + 0.06 * (i // 20), PARK_Z]

    def _init_runtime(self) -> None:
        m, d = self.model, self.data
        self.timestep: float = float(m.opt.timestep)
        jids = [m.joint(n).id for n in self.robot_joint_names]
        self._rq = np.array([m.jnt_qposadr[j] for j in jids])
        self._rv = np.array([m.jnt_dofadr[j] for j in jids])
        self._qdd_full = np.zeros(m.nv)  # scratch vectors for the acceleration feed-forward
        self._torque_full = np.zeros(m.nv)
        self._act_pos = np.array([m.actuator(f"{n}_pos").id for n in self.robot_joint_names])
        self._act_vel = np.array([m.actuator(f"{n}_vel").id for n in self.robot_joint_names])
        gp = self._gp
        self._finger_act = np.array([m.actuator(f"{gp}finger_left_act").id,
                                     m.actuator(f"{gp}finger_right_act").id])
        self._close_ctrl = m.actuator_ctrlrange[self._finger_act, 1].copy()
        self._pads = (m.geom(f"{gp}pad_left").id, m.geom(f"{gp}pad_right").id)
        self._palm = m.body(f"{gp}gripper_base").id
        self._tcp = m.site(f"{gp}tcp").id
        n = self._npool
        self._part_body = np.array([m.body(f"part_{i}").id for i in range(n)])
        self._part_geom = np.array([m.geom(f"part_{i}_geom").id for i in range(n)])
        self._part_qadr = np.array([m.jnt_qposadr[m.joint(f"part_{i}_free").id] for i in range(n)])
        self._part_dadr = np.array([m.jnt_dofadr[m.joint(f"part_{i}_free").id] for i in range(n)])
        self._part_eq = np.array([m.equality(f"grasp_{i}").id for i in range(n)])
        self._geom_part = np.full(m.ngeom, -1, dtype=int)
        self._geom_part[self._part_geom] = np.arange(n)
        pad_mu = max(m.geom_friction[self._pads[0], 0], m.geom_friction[self._pads[1], 0])
        self.grip_mu = float(max(pad_mu, m.geom_friction[self._part_geom[0], 0]))

        phys = self.scene.get("physics", {})
        self._check_steps = max(1, round(float(phys.get("check_interval", 0.01)) / self.timestep))
        self._floor_steps = max(1, round(FLOOR_CHECK_S / self.timestep))

        f = self.scene["feeder"]
        self._rng = np.random.default_rng(self.seed)
        self._feeder_delay = float(f.get("delay", 0.3))
        self._jitter_xy = float(f.get("jitter_xy", 0.0)) / MM
        self._jitter_yaw = math.radians(float(f.get("jitter_yaw", 0.0)))
        self._nest_yaw = math.radians(float(f.get("nest_yaw", 0.0)))

        # Runtime state.
        self._events: list[dict] = []
        self._presented: list[int] = []
        self._presented_bodies = np.zeros(0, dtype=int)
        self._dropped = np.zeros(n, dtype=bool)
        self._retired = np.zeros(n, dtype=bool)
        names = self.regions.names
        self._floor_region = names.index("floor") if "floor" in names else -2
        self._bin_region = names.index("bin") if "bin" in names else -2
        self._still = np.zeros(n, dtype=int)
        self._held: int | None = None
        self._held_since = 0.0
        self._closed = False
        self._grasp_until = -1.0
        self._nest_empty_since: float | None = 0.0
        self._feeder_exhausted = False
        self._steps_to_check = 1
        self._steps_to_floor = self._floor_steps
        self.wall_time_in_step = 0.0

        # Collision bookkeeping: which geoms belong to the moving robot (gripper included) and
        # which of those are the jaws.
        root = m.body(self._robot_root).id
        robot_body = np.array([self._descends_from(b, root) and m.body_weldid[b] != 0 for b in range(m.nbody)])
        jaw_body = np.array([m.body(b).name.startswith(f"{gp}finger") for b in range(m.nbody)])
        self._robot_geom = robot_body[m.geom_bodyid]
        self._jaw_geom = jaw_body[m.geom_bodyid]
        self._touching: set[tuple[int, int]] = set()
        self._collisions: list[dict] = []
        self._released: tuple[int, float] = (-1, -1.0)

        # Home: the robot at the IK of the home location (RIGHTY), held by its servos; gripper open.
        home = self.scene["robot"].get("home", "start")
        kin = self.kinematics = RobotKinematics.from_mjcf(self.robot_model_path)
        seed = np.where(np.isfinite(kin.lower + kin.upper), (kin.lower + kin.upper) / 2, 0.0)
        q = kin.ik(vplus_to_matrix(self.scene["locations"][home]), seed, righty=True)
        d.qpos[self._rq] = q
        d.ctrl[self._act_pos] = q
        d.ctrl[self._act_vel] = 0.0
        d.ctrl[self._finger_act] = 0.0
        mujoco.mj_forward(m, d)

    def _descends_from(self, body: int, root: int) -> bool:
        parent = self.model.body_parentid
        while body not in (0, root):
            body = int(parent[body])
        return body == root

    # ------------------------------------------------------------------ robot interface
    @property
    def time(self) -> float:
        """Simulated time, s."""
        return float(self.data.time)

    def robot_qpos(self) -> np.ndarray:
        """Robot joint positions (rad for revolute, m for prismatic joints), order of robot_joint_names."""
        return self.data.qpos[self._rq].copy()

    def robot_qvel(self) -> np.ndarray:
        """Robot joint velocities (rad/s, m/s)."""
        return self.data.qvel[self._rv].copy()

    def set_servo(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray | None = None) -> None:
        """Servo references: positions (rad, m), velocity feed-forward (rad/s, m/s) and, when
        given, acceleration feed-forward (rad/s^2, m/s^2): the drives add the torque M(q) qdd
        that the planned acceleration needs, as a servo with inertia feed-forward does."""
        ctrl = self.data.ctrl
        ctrl[self._act_pos] = q
        ctrl[self._act_vel] = qd
        applied = self.data.qfrc_applied
        if qdd is None:
            applied[self._rv] = 0.0
            return
        self._qdd_full[self._rv] = qdd
        mujoco.mj_mulM(self.model, self.data, self._torque_full, self._qdd_full)
        applied[self._rv] = self._torque_full[self._rv]

    def set_gripper(self, closed: bool) -> None:
        """Command the jaws closed or open. Opening releases any held part at once."""
        closed = bool(closed)
        self.data.ctrl[self._finger_act] = self._close_ctrl if closed else 0.0
        if closed and not self._closed:
            self._grasp_until = self.time + GRASP_WINDOW_S
            self._steps_to_check = 1
        if not closed and self._held is not None:
            self._release(self._held, commanded=True)
        if not closed:
            self._grasp_until = -1.0
        self._closed = closed

    def gripper_holding(self) -> int | None:
        """Index of the part held by a weld, or None."""
        return self._held

    def grip_force(self) -> float:
        """Squeeze on a gripped part, N: the smaller of the two jaw actuator forces."""
        return float(np.min(np.abs(self.data.actuator_force[self._finger_act])))

    def locations(self) -> dict[str, list[float]]:
        """Taught locations, V+ form [x, y, z mm, yaw, pitch, roll deg], robot base frame."""
        return {k: [float(v) for v in loc] for k, loc in self.scene["locations"].items()}

    def robot_base_pose(self) -> np.ndarray:
        """4x4 world pose of the robot base frame (m)."""
        return self._base_T.copy()

    def tcp_position(self) -> np.ndarray:
        """World position of the gripper's TCP site (between the pads), m."""
        return self.data.site_xpos[self._tcp].copy()

    def part_position(self, i: int) -> np.ndarray:
        """World position of part i's centre, m."""
        return self.data.xpos[self._part_body[i]].copy()

    # ------------------------------------------------------------------ stepping
    def step(self, n: int = 1) -> None:
        """Advance physics by n steps; feeder/grasp/slip logic runs every check interval
        (every step while a grasp may engage)."""
        m, d = self.model, self.data
        while n > 0:
            k = min(n, self._steps_to_check)
            mujoco.mj_step(m, d, k)
            n -= k
            self._steps_to_check -= k
            if self._steps_to_check <= 0:
                self._housekeeping()

    def _housekeeping(self) -> None:
        t = self.data.time
        grasping = self._closed and self._held is None and t <= self._grasp_until
        if grasping:
            self._check_grasp()
        elif self._held is not None and t >= self._held_since + SLIP_GRACE_S:
            self._check_slip()
        self._check_feeder(t)
        self._check_collisions(t)
        self._steps_to_floor -= self._check_steps if not grasping else 1
        if self._steps_to_floor <= 0:
            self._steps_to_floor = self._floor_steps
            self._check_floor()
        self._steps_to_check = 1 if (self._closed and self._held is None
                                     and t <= self._grasp_until) else self._check_steps

    # ------------------------------------------------------------------ grasp and slip
    def _check_grasp(self) -> None:
        d = self.data
        ncon = d.ncon
        if ncon == 0:
            return
        g = d.contact.geom[:ncon]
        dist = d.contact.dist[:ncon]
        touching = dist <= 0.0
        pl, pr = self._pads
        left = touching & ((g[:, 0] == pl) | (g[:, 1] == pl))
        right = touching & ((g[:, 0] == pr) | (g[:, 1] == pr))
        if not left.any() or not right.any():
            return
        other_l = np.where(g[left, 0] == pl, g[left, 1], g[left, 0])
        other_r = np.where(g[right, 0] == pr, g[right, 1], g[right, 0])
        parts_l = set(self._geom_part[other_l].tolist()) - {-1}
        parts_r = set(self._geom_part[other_r].tolist()) - {-1}
        both = parts_l & parts_r
        if both:
            self._engage(min(both))

    def _engage(self, i: int) -> None:
        """Weld part i to the palm at their current relative pose."""
        m, d = self.model, self.data
        b1, b2 = self._palm, self._part_body[i]
        p1, p2 = d.xpos[b1], d.xpos[b2]
        R1 = d.xmat[b1].reshape(3, 3)
        q1inv = np.zeros(4)
        mujoco.mju_negQuat(q1inv, d.xquat[b1])
        relq = np.zeros(4)
        mujoco.mju_mulQuat(relq, q1inv, d.xquat[b2])
        eq = self._part_eq[i]
        m.eq_data[eq, 0:3] = 0.0  # anchor at the part's origin (body2 frame)
        m.eq_data[eq, 3:6] = R1.T @ (p2 - p1)  # part origin in the palm frame
        m.eq_data[eq, 6:10] = relq
        m.eq_data[eq, 10] = 1.0  # torquescale
        d.eq_active[eq] = 1
        self._held = i
        self._held_since = float(d.time)
        self._events.append({"t": round(float(d.time), 4), "kind": "grasp", "part": int(i),
                             "where": self.regions.region_of(p2)})
        self._check_payload(i)

    def _check_payload(self, i: int) -> None:
        """A part heavier than the robot's maximum payload (the model's `payload` numeric) is
        an "overload" event.  The controller does not weigh what it carries (PAYLOAD is the
        program's own indication), so it is not a program error: the twin reports it."""
        payload = self.kinematics.payload_kg
        mass = float(self.model.body_mass[self._part_body[i]])
        if payload is not None and mass > payload[-1]:
            self._events.append({"t": round(self.time, 4), "kind": "overload", "part": int(i),
                                 "mass_kg": round(mass, 3), "max_payload_kg": payload[-1]})

    def _grip_load(self, i: int) -> float:
        """Norm of the net force the gripper applies to part i, N: its weld plus every contact
        of a robot geom with the part.  The weld and the squeezing pads push against each
        other (tens of newtons that cancel); only their sum is what friction must carry
        (the part's weight and inertia, and whatever presses the part against the cell)."""
        m, d = self.model, self.data
        eq = self._part_eq[i]
        nefc = d.nefc
        # Equality rows come first in the constraint list; only one weld is ever active.
        rows = np.flatnonzero((d.efc_type[:min(nefc, 12)] == mujoco.mjtConstraint.mjCNSTR_EQUALITY)
                              & (d.efc_id[:min(nefc, 12)] == eq))
        if len(rows) < 3:
            return 0.0
        total = -d.efc_force[rows[:3]]  # the weld pulls body2 (the part) against its error
        g = self._part_geom[i]
        pairs = d.contact.geom[:d.ncon]
        robot = self._robot_geom[pairs]
        gripping = np.flatnonzero(((pairs[:, 0] == g) & robot[:, 1]) | ((pairs[:, 1] == g) & robot[:, 0]))
        wrench = np.zeros(6)
        for k in gripping.tolist():
            mujoco.mj_contactForce(m, d, k, wrench)
            force = d.contact.frame[k].reshape(3, 3).T @ wrench[:3]  # on geom2, world axes
            total = total + (force if pairs[k, 1] == g else -force)
        return float(np.linalg.norm(total))

    def _check_slip(self) -> None:
        i = self._held
        capacity = 2.0 * self.grip_mu * self.grip_force()
        force = self._grip_load(i)
        if force > capacity:
            self._events.append({"t": round(self.time, 4), "kind": "slip", "part": int(i),
                                 "force_n": round(force, 2), "capacity_n": round(capacity, 2)})
            self._release(i, commanded=False)

    def _release(self, i: int, commanded: bool) -> None:
        d = self.data
        d.eq_active[self._part_eq[i]] = 0
        self._held = None
        self._released = (i, float(d.time))
        pos = d.xpos[self._part_body[i]]
        where = self.regions.region_of(pos)
        if commanded and self.regions.is_place(where):
            self._events.append({"t": round(float(d.time), 4), "kind": "release", "part": int(i),
                                 "where": where})
        else:
            self._mark_dropped(i, where, "slip" if not commanded else "released outside a place region")

    def _mark_dropped(self, i: int, where: str | None, cause: str) -> None:
        if self._dropped[i]:
            return
        self._dropped[i] = True
        self._events.append({"t": round(self.time, 4), "kind": "dropped", "part": int(i),
                             "where": where, "cause": cause})

    # ------------------------------------------------------------------ collisions
    def _check_collisions(self, t: float) -> None:
        """Record each new robot contact that is a collision (see the module docstring)."""
        d = self.data
        ncon = d.ncon
        touching: set[tuple[int, int]] = set()
        if ncon:
            g = d.contact.geom[:ncon]
            robot = self._robot_geom[g]
            mixed = np.flatnonzero((robot[:, 0] != robot[:, 1]) & (d.contact.dist[:ncon] < 0.0))
            for k in mixed.tolist():
                ours, other = (int(g[k, 0]), int(g[k, 1])) if robot[k, 0] else (int(g[k, 1]), int(g[k, 0]))
                if not self._contact_allowed(ours, other, t):
                    touching.add((ours, other))
        m = self.model
        for ours, other in sorted(touching - self._touching):
            part = int(self._geom_part[other])
            event = {"t": round(t, 4), "kind": "collision", "robot_geom": m.geom(ours).name,
                     "with": f"part {part}" if part >= 0 else m.geom(other).name,
                     "where": self.regions.region_of(self.data.geom_xpos[ours])}
            self._events.append(event)
            self._collisions.append(event)
        self._touching = touching

    def _contact_allowed(self, ours: int, other: int, t: float) -> bool:
        """Jaws may touch the part they close on, hold, or have just let go of."""
        part = int(self._geom_part[other])
        if part < 0 or not self._jaw_geom[ours]:
            return False
        released, when = self._released
        return self._closed or part == self._held or (part == released and t - when < RELEASE_GRACE_S)

    def take_collisions(self) -> list[dict]:
        """Collisions recorded since the last call (each is also in `events`)."""
        new, self._collisions = self._collisions, []
        return new

    # ------------------------------------------------------------------ feeder
    def _check_feeder(self, t: float) -> None:
        if len(self._presented_bodies):
            pts = self.data.xpos[self._presented_bodies]
            occupied = bool(self.regions.contains("nest", pts).any())
        else:
            occupied = False
        if occupied:
            self._nest_empty_since = None
            return
        if self._nest_empty_since is None:
            self._nest_empty_since = t
        elif t >= self._nest_empty_since + self._feeder_delay - 1e-9:
            self._present()

    def _present(self) -> None:
        """Move the next pooled part to the nest (zero velocity, contacts on)."""
        i = len(self._presented)
        if i >= self._npool:
            if not self._feeder_exhausted:
                self._feeder_exhausted = True
                self._events.append({"t": round(self.time, 4), "kind": "feeder_empty"})
            self._nest_empty_since = None
            return
        m, d = self.model, self.data
        jx, jy = self._rng.uniform(-1.0, 1.0, 2) * self._jitter_xy
        jyaw = self._rng.uniform(-1.0, 1.0) * self._jitter_yaw
        pos = self._nest_top + [jx, jy, self.part_half[2] + 0.0005]
        qa, da = self._part_qadr[i], self._part_dadr[i]
        d.qpos[qa:qa + 3] = pos
        d.qpos[qa + 3:qa + 7] = yaw_quat(self._nest_yaw + jyaw)
        d.qvel[da:da + 6] = 0.0
        d.qvel[da + 2] = -1e-9  # a nonzero velocity wakes the (sleeping) parked tree
        g = self._part_geom[i]
        m.geom_contype[g] = LIVE_CONTYPE
        m.geom_conaffinity[g] = LIVE_CONAFFINITY
        b = self._part_body[i]
        m.body_contype[b] = LIVE_CONTYPE  # body-level masks filter the broadphase: set them too
        m.body_conaffinity[b] = LIVE_CONAFFINITY
        m.body_gravcomp[b] = 0.0
        d.xpos[b] = pos  # so the checks before the next step see the part where it now is
        d.xquat[b] = d.qpos[qa + 3:qa + 7]
        self._presented.append(i)
        self._presented_bodies = self._part_body[np.array(self._presented)]
        self._nest_empty_since = None
        self._events.append({"t": round(float(d.time), 4), "kind": "present", "part": int(i),
                             "where": "nest"})

    def _check_floor(self) -> None:
        """Live parts: on the floor -> dropped; at rest in the bin -> retired."""
        if not len(self._presented):
            return
        live = np.array(self._presented)
        live = live[~self._retired[live]]
        if not len(live):
            return
        d = self.data
        where = self.regions.first_index(d.xpos[self._part_body[live]])
        for i, r in zip(live.tolist(), where.tolist()):
            if r == self._floor_region and not self._dropped[i]:
                self._mark_dropped(i, "floor", "fell to the floor")
            elif r == self._bin_region and i != self._held:
                da = self._part_dadr[i]
                if np.max(np.abs(d.qvel[da:da + 6])) < RETIRE_SPEED:
                    self._still[i] += 1
                    if self._still[i] >= RETIRE_CHECKS:
                        self._retire(i)
                else:
                    self._still[i] = 0

    def _retire(self, i: int) -> None:
        """Freeze a part that has come to rest in the bin.

        A heap of parts in contact is one island: every part landing on it would wake it all
        and the cost grows with the heap (measured: 100 parts -> slower than real time). A
        retired part keeps its rest pose, is gravity compensated and heavily damped, and
        touches only live parts (so new parts still land on the heap), never other retired
        parts or the bin: the heap costs nothing, and parts landing on it move a retired
        part by about a millimetre at most (measured 1.1 mm over a 40-part heap).
        """
        m, d = self.model, self.data
        g, b, da = self._part_geom[i], self._part_body[i], self._part_dadr[i]
        m.geom_contype[g] = m.body_contype[b] = RETIRED_CONTYPE
        m.geom_conaffinity[g] = m.body_conaffinity[b] = RETIRED_CONAFFINITY
        m.body_gravcomp[b] = 1.0
        m.dof_damping[da:da + 3] = RETIRED_DAMPING[0]
        m.dof_damping[da + 3:da + 6] = RETIRED_DAMPING[1]
        d.qvel[da:da + 6] = 0.0
        self._retired[i] = True

    # ------------------------------------------------------------------ reports
    @property
    def events(self) -> list[dict]:
        """Physics events in time order: present, grasp, release, slip, dropped, feeder_empty,
        collision.

        Each has ``t`` (s) and ``kind``; ``part`` is a part index, ``where`` a region name.
        """
        return self._events

    def parts_report(self) -> list[dict]:
        """Every part ever presented: id, WORLD pose [x, y, z mm, qw, qx, qy, qz], region, dropped."""
        self._check_floor()
        out = []
        for i in self._presented:
            b = self._part_body[i]
            pos = self.data.xpos[b]
            quat = self.data.xquat[b]
            out.append({"id": int(i),
                        "pose": [round(float(v) * MM, 3) for v in pos] + [round(float(v), 6) for v in quat],
                        "region": self.regions.region_of(pos),
                        "dropped": bool(self._dropped[i])})
        return out

    def region_counts(self) -> dict[str, int]:
        """Presented parts per region; every scene region is listed (0 when empty)."""
        counts = {name: 0 for name in self.regions.names}
        for p in self.parts_report():
            if p["region"] is not None:
                counts[p["region"]] += 1
        return counts
