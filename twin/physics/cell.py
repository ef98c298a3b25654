"""The physical cell: the list of components a scene file describes, in one MuJoCo model.

Built with ``mujoco.MjSpec`` from a validated scene (``scenes/*.toml``, docs/scene.md):
the robot MJCF is the base spec, then each component adds itself (`components.REGISTRY`
gives the kinds and their order: robot, gripper, table, feeders, conveyors, sources,
sensors, bins, trays), then the part pool its feeders and sources reserved, and the
gripper's one inactive weld per pooled part. After compiling, each component binds to the
model; while running, the cell steps MuJoCo and calls every component's ``check`` once per
check interval (every step while one of them is ``busy``, e.g. a gripper closing), in
order: gripper, the scene's components, robot (collisions), part pool (floor, bins).

What the controller and the run loop use: the robot's servo interface (`set_servo`,
`robot_qpos`, ...), `set_gripper`, `encoders` (see `components.conveyor` for that
contract), `conveyors`, `take_collisions`, `events`, and for the report `parts_report`,
`region_counts`, `counts`, `components_report`.

Units: SI inside (m, rad, kg, N, s); reports give positions in mm.
"""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np

from ..controller.io import DigitalIO
from .components import REGISTRY, CellContext, Component, Conveyor, Encoder, Robot, WeldGripper
from .parts import PartPool
from .regions import Regions
from .scene import apply_overrides, load_scene
from .schema import Scene, validate_scene

INTEGRATORS = {"implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST,
               "implicit": mujoco.mjtIntegrator.mjINT_IMPLICIT,
               "euler": mujoco.mjtIntegrator.mjINT_EULER,
               "rk4": mujoco.mjtIntegrator.mjINT_RK4}
FLOOR_REGION = {"lo": [-1e4, -1e4, -100.0], "hi": [1e4, 1e4, 200.0], "place": False}


class Cell:
    """A MuJoCo model of the work cell made of components.

    Attributes: ``model``/``data`` (MuJoCo), ``scene`` (the scene's TOML as a dict),
    ``config`` (the validated `Scene`), ``timestep`` (s), ``robot_joint_names``,
    ``kinematics`` (the robot's pinocchio model), ``seed``, ``regions``, ``io``,
    ``components`` (all, build order), ``conveyors``/``encoders``/``trays`` by name/number,
    ``parts`` (the `PartPool`).
    """

    @classmethod
    def from_scene(cls, path: str | Path, seed: int | None = None, io: DigitalIO | None = None,
                   overrides: dict[str, object] | None = None) -> "Cell":
        """Load a scene file; ``seed`` overrides the scene's ``[physics] seed``, ``overrides``
        its values by dotted key (`scene.apply_overrides`)."""
        path = Path(path)
        scene = load_scene(path)
        return cls(apply_overrides(scene, overrides, path) if overrides else scene, path, seed, io)

    def __init__(self, scene: dict, scene_path: str | Path, seed: int | None = None, io: DigitalIO | None = None):
        self.scene = scene
        self.scene_path = Path(scene_path)
        config: Scene = validate_scene(scene, self.scene_path)
        self.config = config
        self.seed: int = int(seed if seed is not None else config.physics.seed)
        self.io = io if io is not None else DigitalIO()
        ctx = self.ctx = CellContext(scene=config, scene_path=self.scene_path, seed=self.seed, io=self.io)
        ctx.request_check = self._request_check
        ctx.held_part = lambda: self.gripper.held

        # Components, in registry order.
        self.components: list[Component] = []
        for kind, factory in REGISTRY.items():
            section = getattr(config, kind)
            entries = section if isinstance(section, list) else ([section] if section is not None else [])
            for entry in entries:
                component = factory(entry, ctx)
                self.components.append(component)
                ctx.by_kind.setdefault(kind, {})[component.name] = component
        self.robot: Robot = ctx.by_kind["robot"]["robot"]
        self.gripper: WeldGripper = ctx.by_kind["gripper"]["gripper"]
        self.conveyors: dict[str, Conveyor] = dict(ctx.by_kind.get("conveyor", {}))
        self.encoders: dict[int, Encoder] = {c.encoder.number: c.encoder for c in self.conveyors.values()
                                             if c.encoder is not None}
        self.trays = dict(ctx.by_kind.get("tray", {}))
        self.regions = ctx.regions = self._regions()
        ctx.retire_regions = [c.name for c in self.components if c.section in ("bin", "tray")]
        self.parts = ctx.parts = PartPool(config.part, ctx)
        for component in self.components:
            component.reserve_parts(self.parts)
        self._build()
        self._bind()

    def _regions(self) -> Regions:
        """Declared ``[regions]``, after the regions components define by their geometry
        (bins, trays, belts, nests) that the scene does not declare itself, and a floor."""
        declared = {name: r.model_dump() for name, r in self.config.regions.items()}
        derived = {name: {"lo": lo, "hi": hi, "place": place}
                   for c in self.components for name, lo, hi, place in c.derived_regions()
                   if name not in declared}
        table = {**derived, **declared}
        table.setdefault("floor", FLOOR_REGION)
        return Regions(table)

    def _build(self) -> None:
        phys = self.config.physics
        spec = self.robot.make_spec()
        self.robot_joint_names = self.robot.joint_names
        self.sleep_enabled = phys.sleep
        spec.option.timestep = phys.timestep
        spec.option.integrator = INTEGRATORS[phys.integrator]
        if phys.sleep:
            spec.option.enableflags |= int(mujoco.mjtEnableBit.mjENBL_SLEEP)
        robot, gripper, *others = self.components
        robot.build(spec, self.ctx)
        gripper.build(spec, self.ctx)
        wb = spec.worldbody
        spec.visual.headlight.ambient = [0.4, 0.4, 0.4]
        wb.add_light(name="cell_light", pos=[0.2, 0.2, 2.5], dir=[0, 0, -1], diffuse=[0.6, 0.6, 0.6])
        wb.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[3, 3, 0.05], rgba=[0.5, 0.5, 0.52, 1])
        for component in others:
            component.build(spec, self.ctx)
        self.parts.build(spec, self.ctx)
        self.gripper.add_part_welds(spec, self.parts.size)
        self.spec = spec
        self.model = spec.compile()
        self.data = mujoco.MjData(self.model)

    def _bind(self) -> None:
        m, d, ctx = self.model, self.data, self.ctx
        ctx.model, ctx.data = m, d
        self.timestep: float = float(m.opt.timestep)
        self.robot.bind(m, d, ctx)
        self.kinematics = self.robot.kinematics
        self.parts.bind(m, d, ctx)
        for component in self.components[1:]:
            component.bind(m, d, ctx)
        self._check_steps = max(1, round(self.config.physics.check_interval / self.timestep))
        self._steps_to_check = 1
        self._steps_done = 0  # physics steps since the start: checks keep their phase (`step`)
        # Check order: the gripper first (grasps), the scene's components, collisions, parts.
        # Components without a check of their own (a table, a bin) are not called.
        self._checked = [c for c in (self.gripper, *self.components[2:], self.robot, self.parts)
                         if type(c).check is not Component.check]
        self._busy = [c for c in self._checked if type(c).busy is not Component.busy]
        self.robot.home(self.config.locations[self.config.robot.home])
        mujoco.mj_forward(m, d)

    def _request_check(self) -> None:
        self._steps_to_check = 1

    # ------------------------------------------------------------------ robot interface
    @property
    def time(self) -> float:
        """Simulated time, s."""
        return float(self.data.time)

    def robot_qpos(self) -> np.ndarray:
        """Robot joint positions (rad for revolute, m for prismatic joints), order of robot_joint_names."""
        return self.robot.qpos()

    def robot_qvel(self) -> np.ndarray:
        """Robot joint velocities (rad/s, m/s)."""
        return self.robot.qvel()

    def set_servo(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray | None = None) -> None:
        """Servo references: positions (rad, m), velocity feed-forward (rad/s, m/s) and, when
        given, acceleration feed-forward (rad/s^2, m/s^2): the drives add the torque M(q) qdd
        that the planned acceleration needs, as a servo with inertia feed-forward does."""
        self.robot.set_servo(q, qd, qdd)

    def servo_feed(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray):
        """Servo references for several steps (one row each): the function `step` takes as
        its `feed` (`Robot.servo_feed`)."""
        return self.robot.servo_feed(q, qd, qdd)

    def set_gripper(self, closed: bool) -> None:
        """The hand: fingers closed/open, or a suction cup's vacuum on/off. Letting go
        releases any held part at once."""
        self.gripper.set_closed(closed)

    def gripper_holding(self) -> int | None:
        """Pool index (body) of the part held by a weld, or None."""
        return self.gripper.held

    def grip_force(self) -> float:
        """Squeeze on a gripped part, N (finger gripper)."""
        return self.gripper.grip_force()

    def locations(self) -> dict[str, list[float]]:
        """Taught locations, V+ form [x, y, z mm, yaw, pitch, roll deg], robot base frame."""
        return {k: [float(v) for v in loc] for k, loc in self.config.locations.items()}

    def robot_base_pose(self) -> np.ndarray:
        """4x4 world pose of the robot base frame (m)."""
        return self.robot.base_T.copy()

    def tcp_position(self) -> np.ndarray:
        """World position of the gripper's TCP site, m."""
        return self.gripper.tcp_position()

    def part_position(self, i: int) -> np.ndarray:
        """World position of pooled part i's centre, m."""
        return self.parts.position(i)

    def mark_missed(self, part_id: int, cause: str) -> None:
        """A part instance (report id) missed its window (the controller's word); a part
        already picked is not missed."""
        body = self.parts.instances[part_id]["body"]
        if self.parts.instance_of[body] == part_id:
            self.parts.mark_missed(body, cause)

    # ------------------------------------------------------------------ stepping
    def step(self, n: int = 1, feed=None) -> None:
        """Advance physics by n steps; the components' checks run every check interval
        (every step while one is busy).  `feed(j)`, when given, is called before the j-th
        (0-based) of the n steps: the servo references of that step (`servo_feed`);
        without it MuJoCo runs the steps between two checks in one call."""
        m, d = self.model, self.data
        j = 0
        while n > 0:
            k = min(n, self._steps_to_check)
            if feed is None:
                mujoco.mj_step(m, d, k)
            else:
                for row in range(j, j + k):
                    feed(row)
                    mujoco.mj_step(m, d)
                j += k
            n -= k
            self._steps_done += k
            self._steps_to_check -= k
            if self._steps_to_check <= 0:
                t = d.time
                for component in self._checked:
                    component.check(t)
                # Every step while busy; else on the interval's own grid (the end of each
                # controller cycle by default), whatever a busy spell did to the phase.
                every = self._check_steps
                self._steps_to_check = 1 if any(c.busy for c in self._busy) else every - self._steps_done % every

    def take_collisions(self) -> list[dict]:
        """Collisions recorded since the last call (each is also in `events`)."""
        new, self.robot.collisions = self.robot.collisions, []
        return new

    # ------------------------------------------------------------------ reports
    @property
    def events(self) -> list[dict]:
        """Physics events in time order: present/spawn, grasp, release, slip, dropped, missed,
        feeder_empty, source_empty, overload, collision.

        Each has ``t`` (s) and ``kind``; ``part`` is a part id (the report's), ``where`` a region name.
        """
        return self.ctx.events

    def parts_report(self) -> list[dict]:
        """Every part ever brought in: id, type, WORLD pose [x, y, z mm, qw, qx, qy, qz], region,
        dropped, picked, missed, and tray/cell when it lies in a tray cell."""
        self.parts.check_floor()
        return self.parts.report_entries()

    def counts(self, parts: list[dict] | None = None) -> dict[str, int]:
        """created, picked, placed, missed, dropped (see twin/report.py)."""
        return self.parts.counts(parts if parts is not None else self.parts_report())

    def region_counts(self, parts: list[dict] | None = None) -> dict[str, int]:
        """Parts per region; every region is listed (0 when empty)."""
        counts = {name: 0 for name in self.regions.names}
        for p in parts if parts is not None else self.parts_report():
            if p["region"] is not None:
                counts[p["region"]] += 1
        return counts

    def components_report(self) -> dict[str, dict]:
        """Each component's report contribution, keyed ``<kind>.<name>``."""
        out = {}
        for c in self.components:
            r = c.report()
            if r is not None:
                out[f"{c.section}.{c.name}"] = r
        return out

    def record(self, recorder) -> None:
        """Time series of the components (belts, encoders, sensors) at a recording frame."""
        t = self.time
        for c in self.components:
            c.record(recorder, t)
