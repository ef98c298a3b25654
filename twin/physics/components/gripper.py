"""Grippers at the robot's flange: two fingers, or a suction cup (``[gripper] type``).

Both hold a part with a weld that engages only from real contact (MuJoCo's contacts on
rotating links drift, so friction or adhesion alone lets a carried part creep: see
/work/shared/notes/modelling-notes.md): one inactive weld per pooled part (gripper body ->
part) is declared; on engagement the current relative pose is written into it and it is
activated; it is released when the gripper lets go, or when the force the gripper applies
to the part (the weld's) exceeds what the grip can carry; then the part is lost (a "slip"
event, the part dropped) and falls.

* Fingers (`FingerGripper`): engage when the jaws are commanded closed and BOTH pads touch
  the same part; capacity 2 * mu * grip force.
* Suction (`SuctionGripper`): engage while the vacuum is on and the cup's face is on a part
  (``mujoco.mj_geomDistance`` from the cup geom to a part within 1 mm: the lip seals;
  MuJoCo 4's contact ``gap`` does not keep such a near contact force-free, so no margin
  is used); capacity = cup area x vacuum level
  (``vacuum_kpa``), the pull-off force of a sealed cup. The vacuum is on while the hand
  is closed (V+ CLOSEI/OPENI, GPL's gripper signal) or ``vacuum_output`` is on;
  ``blowoff_output`` releases the part at once; ``vacuum_input`` is on while a part is held.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from ...errors import SceneError
from ..scene import load_model
from .base import LIVE, CellContext, Component
from .robot import Robot

GRASP_WINDOW_S = 0.3  # s after a close command during which a finger grasp may engage
SLIP_GRACE_S = 0.05  # s after a grasp before slip is checked (grip force builds up)
# s between updates of the joint torques that carry a held part's weight (they change with
# the posture only on axes that are not vertical: not at all on a SCARA or a gantry)
CARRY_UPDATE_S = 0.1
# A grip carrying less than this share of its capacity is checked for slip only every
# SLIP_RELAXED_S (the demo's carries: under 1 %; its inertia cannot grow tenfold in that time
# within the joints' acceleration limits); nearer its capacity, every check.
SLIP_MARGIN, SLIP_RELAXED_S = 0.1, 0.05
RELEASE_GRACE_S = 0.5  # s after the gripper lets go of a part during which it may still touch it
CUP_SEAL = 0.001  # m: the cup seals on a part this close to its face
SEAL_SEARCH = 0.1  # m: parts whose centre is this near the cup are tested
# As a plain int: numpy compares an array with MuJoCo's enum object element by element
# in Python (measured 60 us for 12 rows, the slip check's largest cost).
EQUALITY_ROW = int(mujoco.mjtConstraint.mjCNSTR_EQUALITY)


class WeldGripper(Component):
    """What both grippers share: the model at the flange, the welds, engage/release/slip."""

    section = "gripper"
    body_name = ""  # the gripper body the welds hold parts to

    def __init__(self, config, ctx: CellContext):
        super().__init__(config, ctx)
        self.name = "gripper"
        self.prefix = config.prefix
        self.held: int | None = None  # body index of the held part
        self._held_since = 0.0
        self._released: tuple[int, float] = (-1, -1.0)
        self._carried_at = -1.0
        self._slip_check_at = -1.0  # no slip check before (a grip far from its capacity)
        self.closed = False

    def build(self, spec: mujoco.MjSpec, ctx: CellContext) -> None:
        gspec = load_model(self.config.model, ctx.scene_path, "gripper.model")
        site = spec.site(self.config.site)
        if site is None:
            raise SceneError(f"gripper.site: {self.config.site!r}: no site of that name in the robot model (has: "
                             f"{', '.join(s.name for s in spec.sites) or 'none'})", file=str(ctx.scene_path))
        spec.attach(gspec, prefix=self.prefix, site=site)
        Robot.gravity_compensate(spec)

    def add_part_welds(self, spec: mujoco.MjSpec, count: int) -> None:
        for i in range(count):
            spec.add_equality(name=f"grasp_{i}", type=mujoco.mjtEq.mjEQ_WELD,
                              objtype=mujoco.mjtObj.mjOBJ_BODY, name1=f"{self.prefix}{self.body_name}",
                              name2=f"part_{i}", active=False, solref=[0.004, 1.0])

    def bind(self, model: mujoco.MjModel, data: mujoco.MjData, ctx: CellContext) -> None:
        self.model, self.data = model, data
        self.parts = ctx.parts
        self._palm = model.body(f"{self.prefix}{self.body_name}").id
        self._tcp = model.site(f"{self.prefix}tcp").id
        self._eq = np.array([model.equality(f"grasp_{i}").id for i in range(ctx.parts.size)], dtype=int)
        robot: Robot = ctx.by_kind["robot"]["robot"]
        self._robot = robot

    @property
    def time(self) -> float:
        return float(self.data.time)

    def tcp_position(self) -> np.ndarray:
        return self.data.site_xpos[self._tcp].copy()

    @property
    def tcp_site(self) -> int:
        """The MuJoCo site id of the tool tip (the recording draws its path)."""
        return self._tcp

    def record(self, recorder, t: float) -> None:
        """At a recording frame: closed (0/1) and the grip force on the held part (N)."""
        recorder.log_scalar("gripper/closed", t, float(self.closed))
        recorder.log_scalar("gripper/force_n", t, float(self.load(self.held)) if self.held is not None else 0.0)

    # ------------------------------------------------------------------ weld
    def _engage(self, i: int) -> None:
        """Weld part i to the gripper at their current relative pose."""
        m, d = self.model, self.data
        b1, b2 = self._palm, self.parts.body[i]
        p1, p2 = d.xpos[b1], d.xpos[b2]
        R1 = d.xmat[b1].reshape(3, 3)
        q1inv = np.zeros(4)
        mujoco.mju_negQuat(q1inv, d.xquat[b1])
        relq = np.zeros(4)
        mujoco.mju_mulQuat(relq, q1inv, d.xquat[b2])
        eq = self._eq[i]
        m.eq_data[eq, 0:3] = 0.0  # anchor at the part's origin (body2 frame)
        m.eq_data[eq, 3:6] = R1.T @ (p2 - p1)  # part origin in the gripper frame
        m.eq_data[eq, 6:10] = relq
        m.eq_data[eq, 10] = 1.0  # torquescale
        d.eq_active[eq] = 1
        self._hold_jaws(i)
        self.parts.hold(i, True)
        self.held = i
        self._held_since = self.time
        self._slip_check_at = -1.0
        self._carry(i)
        self.parts.mark_picked(i)
        self.ctx.event("grasp", part=int(self.parts.instance_of[i]), where=self.ctx.regions.region_of(p2))
        self._check_payload(i)

    def _carry(self, i: int) -> None:
        self._robot.carry(int(self.parts.body[i]), self._palm)
        self._carried_at = self.time

    def _check_payload(self, i: int) -> None:
        """A part heavier than the robot's maximum payload (the model's `payload` numeric) is
        an "overload" event.  The controller does not weigh what it carries (PAYLOAD is the
        program's own indication), so it is not a program error: the twin reports it."""
        payload = self._robot.kinematics.payload_kg
        mass = float(self.model.body_mass[self.parts.body[i]])
        if payload is not None and mass > payload[-1]:
            self.ctx.event("overload", part=int(self.parts.instance_of[i]), mass_kg=round(mass, 3),
                           max_payload_kg=payload[-1])

    def load(self, i: int) -> float:
        """Norm of the net force the gripper applies to part i, N: the force of its weld (the
        held part does not touch the robot, see the module docstring), what the grip must
        carry: the part's weight and inertia, and whatever presses it against the cell."""
        d = self.data
        eq = self._eq[i]
        head = min(d.nefc, 12)
        # Equality rows come first in the constraint list; only one weld is ever active.
        rows = np.flatnonzero((d.efc_type[:head] == EQUALITY_ROW) & (d.efc_id[:head] == eq))
        if len(rows) < 3:
            return 0.0
        return float(np.linalg.norm(d.efc_force[rows[:3]]))

    def _hold_jaws(self, i: int) -> None:
        """Keep the jaws on part i once its contacts are off (a finger gripper's)."""

    def _free_jaws(self) -> None:
        """After a slip: the hand's command back on the jaws (a finger gripper's)."""

    def _check_slip(self) -> None:
        i, t = self.held, self.time
        if t < self._slip_check_at:
            return
        if t >= self._carried_at + CARRY_UPDATE_S:  # the arm's posture changed
            self._carry(i)
        capacity = self.capacity(i)
        force = self.load(i)
        if force > capacity:
            self.ctx.event("slip", part=int(self.parts.instance_of[i]), force_n=round(force, 2),
                           capacity_n=round(capacity, 2))
            self._release(i, commanded=False)
        elif force < SLIP_MARGIN * capacity:  # far from slipping: look again a little later
            self._slip_check_at = t + SLIP_RELAXED_S

    def _release(self, i: int, commanded: bool) -> None:
        d = self.data
        d.eq_active[self._eq[i]] = 0
        self.held = None
        self.parts.hold(i, False)
        if not commanded:  # a slip: the jaws are still commanded closed (opening set their command)
            self._free_jaws()
        self._robot.carry(None)
        self.parts.wake_body(i)  # a part let go at rest must not sleep in mid-air
        self._released = (i, float(d.time))
        pos = d.xpos[self.parts.body[i]]
        where = self.ctx.regions.region_of(pos)
        if commanded and self.ctx.regions.is_place(where):
            self.ctx.event("release", part=int(self.parts.instance_of[i]), where=where)
        else:
            self.parts.mark_dropped(i, where, "slip" if not commanded else "released outside a place region")

    def contact_allowed(self, ours: int, part: int, t: float) -> bool:
        """A robot geom may touch a part only as the gripper (see the subclasses)."""
        if part < 0 or not self._gripping_geom[ours]:
            return False
        released, when = self._released
        return self.closed or part == self.held or (part == released and t - when < RELEASE_GRACE_S)

    def capacity(self, i: int) -> float:
        raise NotImplementedError


class FingerGripper(WeldGripper):
    body_name = "gripper_base"

    def __init__(self, config, ctx: CellContext):
        super().__init__(config, ctx)
        self._grasp_until = -1.0

    def bind(self, model: mujoco.MjModel, data: mujoco.MjData, ctx: CellContext) -> None:
        super().bind(model, data, ctx)
        gp = self.prefix
        self._finger_act = np.array([model.actuator(f"{gp}finger_left_act").id,
                                     model.actuator(f"{gp}finger_right_act").id])
        self._close_ctrl = model.actuator_ctrlrange[self._finger_act, 1].copy()
        self._pads = (model.geom(f"{gp}pad_left").id, model.geom(f"{gp}pad_right").id)
        self._jaw_qadr = model.jnt_qposadr[model.actuator_trnid[self._finger_act, 0]]
        self._jaw_hold = np.zeros(2)  # jaw positions at the held part's faces (m)
        self.pad_mu = float(max(model.geom_friction[self._pads[0], 0], model.geom_friction[self._pads[1], 0]))
        jaw_body = np.array([model.body(b).name.startswith(f"{gp}finger") for b in range(model.nbody)])
        self._gripping_geom = jaw_body[model.geom_bodyid]
        data.ctrl[self._finger_act] = 0.0

    @property
    def busy(self) -> bool:
        return self.closed and self.held is None and self.time <= self._grasp_until

    def set_closed(self, closed: bool) -> None:
        """Command the jaws closed or open. Opening releases any held part at once."""
        closed = bool(closed)
        self.data.ctrl[self._finger_act] = self._close_ctrl if closed else 0.0
        if closed and not self.closed:
            self._grasp_until = self.time + GRASP_WINDOW_S
            self.ctx.request_check()
        if not closed and self.held is not None:
            self._release(self.held, commanded=True)
        if not closed:
            self._grasp_until = -1.0
        self.closed = closed

    def grip_force(self) -> float:
        """Squeeze on a gripped part, N: the smaller of the two jaw actuator forces; while a
        part is held, the force each closed jaw's servo pushes with at the part's face
        (its gain times the command's lead on that face, within its force range)."""
        left, right = self._finger_act.tolist()  # two floats: plain Python beats numpy's reductions
        if self.held is None:
            force = self.data.actuator_force
            return min(abs(float(force[left])), abs(float(force[right])))
        m, pushes = self.model, []
        for jaw, act in enumerate((left, right)):
            f = float(m.actuator_gainprm[act, 0] * (self._close_ctrl[jaw] - self._jaw_hold[jaw]))
            if m.actuator_forcelimited[act]:
                f = min(max(f, float(m.actuator_forcerange[act, 0])), float(m.actuator_forcerange[act, 1]))
            pushes.append(abs(f))
        return min(pushes)

    def capacity(self, i: int) -> float:
        mu = max(self.pad_mu, float(self.model.geom_friction[self.parts.geom[i], 0]))
        return 2.0 * mu * self.grip_force()

    def _hold_jaws(self, i: int) -> None:
        """Each jaw's servo holds it where its pad's face meets part i (the jaw's position
        less the pad's penetration); `grip_force` is then what the closed jaw pushes with
        there."""
        d = self.data
        g = int(self.parts.geom[i])
        ncon = d.ncon
        contact = d.contact  # each attribute read copies MuJoCo's arrays: read them once
        pairs, dist = contact.geom[:ncon], contact.dist[:ncon]
        for jaw, pad in enumerate(self._pads):
            q = float(d.qpos[self._jaw_qadr[jaw]])
            ks = np.flatnonzero(((pairs[:, 0] == pad) & (pairs[:, 1] == g)) | ((pairs[:, 1] == pad) & (pairs[:, 0] == g)))
            if len(ks):
                q += min(float(dist[ks].min()), 0.0)
            self._jaw_hold[jaw] = q
        d.ctrl[self._finger_act] = self._jaw_hold

    def _free_jaws(self) -> None:
        self.data.ctrl[self._finger_act] = self._close_ctrl if self.closed else 0.0  # the jaws close on

    def check(self, t: float) -> None:
        if self.config.holding_input is not None:
            self.ctx.io.set(self.config.holding_input, self.held is not None)
        if self.busy:
            self._check_grasp()
        elif self.held is not None and t >= self._held_since + SLIP_GRACE_S:
            self._check_slip()

    def _check_grasp(self) -> None:
        d = self.data
        ncon = d.ncon
        if ncon == 0:
            return
        g = d.contact.geom[:ncon]
        touching = d.contact.dist[:ncon] <= 0.0
        pl, pr = self._pads
        left = touching & ((g[:, 0] == pl) | (g[:, 1] == pl))
        right = touching & ((g[:, 0] == pr) | (g[:, 1] == pr))
        if not left.any() or not right.any():
            return
        geom_part = self.parts.geom_part
        other_l = np.where(g[left, 0] == pl, g[left, 1], g[left, 0])
        other_r = np.where(g[right, 0] == pr, g[right, 1], g[right, 0])
        both = (set(geom_part[other_l].tolist()) - {-1}) & (set(geom_part[other_r].tolist()) - {-1})
        if both:
            self._engage(min(both))


class SuctionGripper(WeldGripper):
    body_name = "suction_base"

    def bind(self, model: mujoco.MjModel, data: mujoco.MjData, ctx: CellContext) -> None:
        super().bind(model, data, ctx)
        self._cup = model.geom(f"{self.prefix}cup").id
        radius = float(model.geom_size[self._cup, 0])
        self.area_m2 = math.pi * radius ** 2
        cup_body = np.zeros(model.nbody, dtype=bool)
        cup_body[model.geom_bodyid[self._cup]] = True
        self._gripping_geom = cup_body[model.geom_bodyid]
        self.io = ctx.io
        self.vacuum = False
        self.blowoff = False

    @property
    def holding_force_n(self) -> float:
        """Pull-off force of the sealed cup, N: area x vacuum level."""
        return self.area_m2 * self.config.vacuum_kpa * 1000.0

    def capacity(self, i: int) -> float:
        return self.holding_force_n

    @property
    def busy(self) -> bool:
        return self.vacuum and self.held is None

    def set_closed(self, closed: bool) -> None:
        """The hand valve: closed = vacuum on (V+ CLOSEI), open = vacuum off (OPENI)."""
        self.closed = bool(closed)
        self._update_valves()

    def _update_valves(self) -> None:
        state = self.io.state
        out = self.config.vacuum_output
        blow = self.config.blowoff_output
        self.blowoff = blow is not None and state.get(blow, False)
        vacuum = (self.closed or (out is not None and state.get(out, False))) and not self.blowoff
        if vacuum and not self.vacuum:
            self.ctx.request_check()
        self.vacuum = vacuum
        if not vacuum and self.held is not None:
            self._release(self.held, commanded=True)
        if self.config.vacuum_input is not None:
            self.io.set(self.config.vacuum_input, self.held is not None)

    def check(self, t: float) -> None:
        self._update_valves()
        if self.busy:
            self._check_seal()
        elif self.held is not None and t >= self._held_since + SLIP_GRACE_S:
            self._check_slip()
            if self.held is None and self.config.vacuum_input is not None:
                self.io.set(self.config.vacuum_input, False)

    def _check_seal(self) -> None:
        """Hold the nearest live part whose surface is within CUP_SEAL of the cup."""
        m, d, parts = self.model, self.data, self.parts
        live = parts.live[parts.state[parts.live] == LIVE]
        if not len(live):
            return
        cup = d.geom_xpos[self._cup]
        near = live[np.linalg.norm(d.xpos[parts.body[live]] - cup, axis=1) < SEAL_SEARCH]
        for i in near.tolist():
            if mujoco.mj_geomDistance(m, d, self._cup, int(parts.geom[i]), 2 * CUP_SEAL, None) <= CUP_SEAL:
                self._engage(i)
                if self.config.vacuum_input is not None:
                    self.io.set(self.config.vacuum_input, True)
                return

    def contact_allowed(self, ours: int, part: int, t: float) -> bool:
        return super().contact_allowed(ours, part, t) or (part >= 0 and self._gripping_geom[ours] and self.vacuum)


def make_gripper(config, ctx: CellContext) -> WeldGripper:
    return (SuctionGripper if config.type == "suction" else FingerGripper)(config, ctx)
