"""The cell's parts: a pool of free bodies, parked until a feeder or source brings one in.

Each feeder or source reserves its own bodies (``reserve``) of the scene's part types
(``[[part]]``: box, cylinder, or a mesh read with trimesh); they are built last, parked
under the floor with contacts off and gravity compensated.  A part brought into the cell
(``activate``) is a new *instance* with its own id (the report's ``parts[].id``); when an
owner has no parked body left it takes back the body that finished first (at rest in a
bin or tray, or fallen to the floor): that instance's report entry is frozen where it
was, and the body comes back as a new instance.  A missed part (it left a belt unpicked)
goes back to the pool as soon as it has fallen to rest, so rejects never heap up.  So a
pool never runs out in a long run.

Every 0.1 s of simulated time (``check``): a live part on the floor is dropped (unless
missed); one at rest in a bin or tray is retired (frozen, see ``_retire``).

Units: SI inside (m, kg, s); reports in mm.
"""

from __future__ import annotations

import numpy as np
import mujoco

from .components.base import (FINISHED, HELD_CONAFFINITY, HELD_CONTYPE, LIVE, LIVE_CONAFFINITY, LIVE_CONTYPE,
                              PARKED, RETIRED, RETIRED_CONAFFINITY, RETIRED_CONTYPE, CellContext, Component)
from .geometry import MM
from .scene import resolve

PARK_Z = -0.5  # m: pooled parts wait under the floor, contacts off, gravity compensated
# At least this long between checks for parts on the floor / at rest in a bin or tray: the
# first component check after it (every 0.112 s with the 16 ms check interval).
FLOOR_CHECK_S = 0.1  # s
# A part in a bin slower than this (m/s, and rad/s) ... MuJoCo's soft friction lets a part
# on a sloping heap creep at a few mm/s and turn at a few hundredths of a rad/s for tens of
# seconds (measured in the demo's bin: up to 14 such parts awake at once, 3 mm/s, 0.08 rad/s,
# doubling the cost of every step); at these speeds a part in a bin has come to rest.
RETIRE_SPEED, RETIRE_SPIN = 5e-3, 0.1
RETIRE_CHECKS = 3  # ... at this many floor checks in a row (0.1 s apart) retires
# The parts' contact stiffness: an 8 ms time constant (MuJoCo's default is 20 ms, under
# which a part at rest on the retired heap sank 1.1 mm into it, on the spreader cone 0.9 mm;
# now 0.07 and 0.2 mm).  MuJoCo averages the two geoms' values, so a part on the table or a
# bin gets 14 ms.  Stiffer (4 ms, the stiffest a 2 ms step allows) let a part settle in the
# nest where the closing jaw's finger struck it (docs/performance.md).
PART_SOLREF = [0.008, 1.0]
# Bodies a feeder or source builds per part type, whatever its `pool` asks: every body
# costs every physics step, asleep or parked (MuJoCo's per-dof work; measured 57 ns a body
# a step, a 2000-body pool made the demo 2.8x slower), and so does a bigger heap of
# retired parts under the landing ones (a 200-body heap: +60 % a part). No more are ever
# in play at once; beyond it the bodies are recycled (see `take`), each part's report
# entry frozen where it came to rest, so the report still gives every part's final pose
# (a bin shows the last of them). The demo asks for 120: with 24 its physics step costs
# a third less (measured 36 -> 24 us a step, docs/performance.md), and it never has more
# than 6 parts in play (nest, hand, belt, falling).
MAX_RECYCLED_BODIES = 24


class PartPool(Component):
    """Bodies ``part_<i>`` (geom ``part_<i>_geom``, joint ``part_<i>_free``), their
    instances and what became of each."""

    section = "part"

    def __init__(self, types, ctx: CellContext):
        super().__init__(None, ctx)
        self.name = "parts"
        self.types = {t.name: t for t in types}
        self._owner_of: list[Component] = []  # per body
        self._type_of: list[str] = []
        self.instances: list[dict] = []  # per instance: id, body, type, owner, picked, missed, dropped, frozen

    # ------------------------------------------------------------------ construction
    def reserve(self, owner: Component, type_names: list[str], count: int, recycled: bool = True) -> np.ndarray:
        """Reserve `count` bodies for `owner`, cycling through `type_names`, at most
        MAX_RECYCLED_BODIES a type when the owner recycles them (`take`); their indices."""
        if recycled:
            count = min(count, MAX_RECYCLED_BODIES * len(type_names))
        first = len(self._owner_of)
        for k in range(count):
            self._owner_of.append(owner)
            self._type_of.append(type_names[k % len(type_names)])
        return np.arange(first, first + count)

    @property
    def size(self) -> int:
        return len(self._owner_of)

    def half_height(self, i: int) -> float:
        """Half the part's height (m) standing on its base."""
        return float(self._half_z[i])

    def build(self, spec: mujoco.MjSpec, ctx: CellContext) -> None:
        self.sleep = ctx.scene.physics.sleep
        meshes: dict[str, float] = {}
        half_z = []
        for k, (name, t) in enumerate(self.types.items()):
            if t.shape == "mesh":
                import trimesh  # here: a third of the package's import time, for mesh parts only

                mesh = trimesh.load(str(resolve(t.mesh, ctx.scene_path, f"part[{k}].mesh")), force="mesh")
                v = np.asarray(mesh.vertices, dtype=float) / MM
                v -= (v.min(axis=0) + v.max(axis=0)) / 2  # origin at the bounding box centre
                spec.add_mesh(name=f"part_mesh_{name}", uservert=v.flatten(),
                              userface=np.asarray(mesh.faces).flatten())
                meshes[name] = float(v[:, 2].max())
        wb = spec.worldbody
        for i, tname in enumerate(self._type_of):
            t = self.types[tname]
            body = wb.add_body(name=f"part_{i}", pos=self._park_pos(i), gravcomp=1.0)
            if self.sleep:
                body.sleep = mujoco.mjtSleepPolicy.mjSLEEP_INIT
            body.add_freejoint(name=f"part_{i}_free")
            # Its rest body (see `_retire`): where the part lies once retired, static.
            rest = wb.add_body(name=f"part_{i}_rest", pos=self._park_pos(i), mocap=True)
            shape = dict(mass=t.mass, friction=[t.friction, 0.005, 0.0001], contype=0, conaffinity=0,
                         rgba=t.rgba, solref=PART_SOLREF)
            if t.shape == "box":
                half = np.array(t.size, dtype=float) / MM / 2
                shape.update(type=mujoco.mjtGeom.mjGEOM_BOX, size=half)
                half_z.append(half[2])
            elif t.shape == "cylinder":
                r, h = t.radius / MM, t.height / MM / 2
                shape.update(type=mujoco.mjtGeom.mjGEOM_CYLINDER, size=[r, h, 0])
                half_z.append(h)
            else:
                # Compiled as able to collide, so that MuJoCo builds the mesh's convex hull (it
                # skips it for a mesh no colliding geom uses, and a hull-less mesh touches with
                # one point: a plate on a face rocks and sinks); parked by `bind`.
                shape.update(type=mujoco.mjtGeom.mjGEOM_MESH, meshname=f"part_mesh_{tname}",
                             contype=RETIRED_CONTYPE)
                half_z.append(meshes[tname])
            body.add_geom(name=f"part_{i}_geom", **shape)
            rest.add_geom(name=f"part_{i}_rest_geom", **shape)
        self._half_z = np.array(half_z)

    @staticmethod
    def _park_pos(i: int) -> list[float]:
        return [-1.0 + 0.06 * (i % 20), -1.5 + 0.06 * (i // 20), PARK_Z]

    def bind(self, model: mujoco.MjModel, data: mujoco.MjData, ctx: CellContext) -> None:
        m = self.model = model
        self.data = data
        n = self.size
        self.body = np.array([m.body(f"part_{i}").id for i in range(n)], dtype=int)
        self.geom = np.array([m.geom(f"part_{i}_geom").id for i in range(n)], dtype=int)
        self.qadr = np.array([m.jnt_qposadr[m.joint(f"part_{i}_free").id] for i in range(n)], dtype=int)
        self.dadr = np.array([m.jnt_dofadr[m.joint(f"part_{i}_free").id] for i in range(n)], dtype=int)
        self.rest_body = np.array([m.body(f"part_{i}_rest").id for i in range(n)], dtype=int)
        self.rest_geom = np.array([m.geom(f"part_{i}_rest_geom").id for i in range(n)], dtype=int)
        self._rest_mocap = m.body_mocapid[self.rest_body]
        self.shown = self.body.copy()  # the body that holds each part's pose: its rest body once retired
        m.geom_contype[self.geom] = m.geom_contype[self.rest_geom] = 0  # parked: no contacts (see `build`)
        m.body_contype[self.rest_body] = m.body_conaffinity[self.rest_body] = 0
        self.geom_part = np.full(m.ngeom, -1, dtype=int)  # geom id -> body index
        self.geom_part[self.geom] = self.geom_part[self.rest_geom] = np.arange(n)
        self.state = np.zeros(n, dtype=int)
        self.instance_of = np.full(n, -1, dtype=int)
        self.since = np.zeros(n)  # time of the last change of state
        self._still = np.zeros(n, dtype=int)
        names = ctx.regions.names
        self._floor_region = names.index("floor") if "floor" in names else -2
        self._retire_regions = np.array([names.index(r) for r in ctx.retire_regions if r in names], dtype=int)
        self._next_floor = FLOOR_CHECK_S
        self.live = np.zeros(0, dtype=int)  # body indices in the cell (live or retired), in order

    # ------------------------------------------------------------------ life of a part
    def take(self, owner: Component, type_name: str | None = None) -> int | None:
        """A parked body of `owner`'s (of `type_name` when given), or the one of those that
        finished first; None when every one is still in play."""
        mine = np.flatnonzero(np.fromiter((o is owner and (type_name is None or t == type_name)
                                           for o, t in zip(self._owner_of, self._type_of)), bool, self.size))
        parked = mine[self.state[mine] == PARKED]
        if len(parked):
            return int(parked[0])
        done = mine[(self.state[mine] == FINISHED) | (self.state[mine] == RETIRED)]
        if not len(done):
            return None
        i = int(done[np.argmin(self.since[done])])
        self.park(i)
        return i

    def activate(self, i: int, pos, quat, where: str | None, velocity=None, kind: str = "present") -> int:
        """Bring body i into the cell at pos (m) / quat (wxyz), contacts on: a new instance."""
        m, d = self.model, self.data
        qa, da = self.qadr[i], self.dadr[i]
        d.qpos[qa:qa + 3] = pos
        d.qpos[qa + 3:qa + 7] = quat
        d.qvel[da:da + 6] = 0.0
        if velocity is not None:
            d.qvel[da:da + 3] = velocity
        d.qvel[da + 2] += -1e-9  # a nonzero velocity wakes the (sleeping) parked tree
        b = self.body[i]
        self._set_contacts(i, LIVE_CONTYPE, LIVE_CONAFFINITY)
        m.body_gravcomp[b] = 0.0
        d.xpos[b] = pos  # so the checks before the next step see the part where it now is
        d.xquat[b] = d.qpos[qa + 3:qa + 7]
        iid = len(self.instances)
        self.instances.append({"id": iid, "body": i, "type": self._type_of[i], "picked": False,
                               "missed": False, "dropped": False, "frozen": None})
        self.instance_of[i] = iid
        self.state[i] = LIVE
        self.since[i] = float(d.time)
        self._still[i] = 0
        self.live = np.append(self.live[self.live != i], i)
        self.ctx.event(kind, part=iid, where=where, **({"type": self._type_of[i]} if len(self.types) > 1 else {}))
        return iid

    def park(self, i: int) -> None:
        """Freeze body i's instance report where it is and send the body back under the floor."""
        iid = int(self.instance_of[i])
        if iid >= 0:
            self.instances[iid]["frozen"] = self._entry(iid)
        if self.state[i] == RETIRED:  # its rest body leaves the heap
            self._set_rest(i, self._park_pos(i), [1.0, 0.0, 0.0, 0.0], 0, 0)
            self.shown[i] = self.body[i]
        else:
            self._stow(i)
        self.state[i] = PARKED
        self.instance_of[i] = -1
        self.live = self.live[self.live != i]

    def _stow(self, i: int) -> None:
        """Body i under the floor: no contacts, gravity compensated, at rest (it falls asleep)."""
        m, d = self.model, self.data
        b, qa, da = self.body[i], self.qadr[i], self.dadr[i]
        self._set_contacts(i, 0, 0)
        m.body_gravcomp[b] = 1.0
        d.qpos[qa:qa + 3] = self._park_pos(i)
        d.qpos[qa + 3:qa + 7] = [1.0, 0.0, 0.0, 0.0]
        d.qvel[da:da + 6] = 0.0
        d.qvel[da + 2] = -1e-9

    def _set_rest(self, i: int, pos, quat, contype: int, conaffinity: int) -> None:
        """Body i's rest body (a mocap body: static, no degrees of freedom) at pos / quat
        (m, wxyz) with the given contact bits."""
        m, d, b, k, g = self.model, self.data, self.rest_body[i], self._rest_mocap[i], self.rest_geom[i]
        d.mocap_pos[k] = d.xpos[b] = pos
        d.mocap_quat[k] = d.xquat[b] = quat
        m.geom_contype[g] = m.body_contype[b] = contype
        m.geom_conaffinity[g] = m.body_conaffinity[b] = conaffinity

    def hold(self, i: int, held: bool) -> None:
        """Body i is held by a grasp (True: it no longer touches the robot) or let go (False)."""
        self._set_contacts(i, *((HELD_CONTYPE, HELD_CONAFFINITY) if held else (LIVE_CONTYPE, LIVE_CONAFFINITY)))

    def _set_contacts(self, i: int, contype: int, conaffinity: int) -> None:
        """Body i's contact bits (base.py), on its geom and its body: the body-level masks
        filter MuJoCo's broadphase, so both are set."""
        m, g, b = self.model, self.geom[i], self.body[i]
        m.geom_contype[g] = m.body_contype[b] = contype
        m.geom_conaffinity[g] = m.body_conaffinity[b] = conaffinity

    def instance(self, i: int) -> dict:
        """The current instance record of body i."""
        return self.instances[self.instance_of[i]]

    def mark_picked(self, i: int) -> None:
        self.instance(i)["picked"] = True

    def mark_missed(self, i: int, cause: str) -> None:
        """Body i's part passed its chance to be picked (left a belt, or a window)."""
        inst = self.instance(i)
        if inst["missed"] or inst["picked"]:
            return
        inst["missed"] = True
        self.ctx.event("missed", part=inst["id"], where=self.ctx.regions.region_of(self.data.xpos[self.body[i]]),
                       cause=cause)

    def mark_dropped(self, i: int, where: str | None, cause: str) -> None:
        inst = self.instance(i)
        if inst["dropped"]:
            return
        inst["dropped"] = True
        self.ctx.event("dropped", part=inst["id"], where=where, cause=cause)

    def position(self, i: int) -> np.ndarray:
        """World position of body i's part (m): where it rests once retired."""
        return self.data.xpos[self.shown[i]].copy()

    def wake_body(self, i: int) -> None:
        """Keep body i awake: a sleeping tree wakes at the next step when it has a nonzero
        velocity (MuJoCo's rule); an awake one about to fall asleep (a part let go at rest
        in mid-air) gets its full awake count back, so gravity can take it."""
        d = self.data
        tree = self.model.body_treeid[self.body[i]]
        if d.tree_asleep[tree] < 0:
            d.tree_asleep[tree] = -mujoco.mjMINAWAKE
        d.qvel[self.dadr[i] + 2] += -1e-9

    def wake(self, lo: np.ndarray, hi: np.ndarray) -> None:
        """Wake the live parts whose centre is in the world box lo..hi (m): a belt that starts
        must move parts that fell asleep on it."""
        if not len(self.live):
            return
        pts = self.data.xpos[self.body[self.live]]
        inside = self.live[np.all((pts >= lo) & (pts <= hi), axis=1)]
        for i in inside.tolist():
            if self.state[i] == LIVE:
                self.wake_body(i)

    # ------------------------------------------------------------------ floor and bins
    def check(self, t: float) -> None:
        if t + 1e-9 >= self._next_floor:
            self._next_floor = t + FLOOR_CHECK_S
            self.check_floor()

    def check_floor(self, held: int | None = None) -> None:
        """Live parts: on the floor -> dropped (or finished when missed); at rest in a bin
        or tray -> retired."""
        live = self.live[self.state[self.live] == LIVE]
        if not len(live):
            return
        d = self.data
        where = self.ctx.regions.first_index(d.xpos[self.body[live]])
        held = self.ctx.held_part() if held is None else held
        for i, r in zip(live.tolist(), where.tolist()):
            if r == self._floor_region:
                if not self.instance(i)["missed"]:
                    self.mark_dropped(i, "floor", "fell to the floor")
                self._finish(i)
            elif r in self._retire_regions and i != held:
                da = self.dadr[i]
                if np.max(np.abs(d.qvel[da:da + 3])) < RETIRE_SPEED and np.max(np.abs(d.qvel[da + 3:da + 6])) < RETIRE_SPIN:
                    self._still[i] += 1
                    if self._still[i] >= RETIRE_CHECKS:
                        self._retire(i)
                else:
                    self._still[i] = 0

    def _finish(self, i: int) -> None:
        """Body i's part is out of play (fallen, or missed and at rest): a part that was
        missed goes back to the pool at once (its entry frozen where it came to rest), so
        rejects never heap up; any other waits until its owner needs the body."""
        if self.instance(i)["missed"]:
            self.park(i)
            return
        self.state[i] = FINISHED
        self.since[i] = float(self.data.time)

    def _retire(self, i: int) -> None:
        """Freeze a part that has come to rest in a bin or tray.

        A heap of parts in contact is one island: every part landing on it would wake it all
        and the cost grows with the heap (measured: 100 parts -> slower than real time).  A
        retired part is its rest body, a static copy of it (MuJoCo's mocap body: no degrees
        of freedom) put where it came to rest, while its free body waits under the floor.
        The rest body touches only live parts (so new parts still land on the heap), never
        other retired parts or the bin, and a part landing on it is an island of its own:
        the heap costs only its contacts with the parts landing on it.  (Before, a retired
        part was its free body, damped: each part it touched woke it, and the awake heap
        was a quarter of the demo's physics, docs/performance.md.)
        """
        d = self.data
        b = self.body[i]
        self._set_rest(i, d.xpos[b].copy(), d.xquat[b].copy(), RETIRED_CONTYPE, RETIRED_CONAFFINITY)
        self._stow(i)
        self.shown[i] = self.rest_body[i]
        self.state[i] = RETIRED
        self.since[i] = float(d.time)
        if self.instance(i)["missed"]:
            self._finish(i)

    # ------------------------------------------------------------------ reports
    def _entry(self, iid: int) -> dict:
        inst = self.instances[iid]
        b = self.shown[inst["body"]]
        pos, quat = self.data.xpos[b], self.data.xquat[b]
        entry = {"id": iid, "type": inst["type"],
                 "pose": [round(float(v) * MM, 3) for v in pos] + [round(float(v), 6) for v in quat],
                 "region": self.ctx.regions.region_of(pos), "dropped": inst["dropped"],
                 "picked": inst["picked"], "missed": inst["missed"]}
        for tray in self.ctx.by_kind.get("tray", {}).values():
            if entry["region"] == tray.name:
                cell = tray.cell_of(pos)
                if cell is not None:
                    entry.update(tray=tray.name, cell=cell)
        return entry

    def report_entries(self) -> list[dict]:
        """Every instance ever brought in, in order: where it is now, or where it was when
        its body was taken back."""
        return [inst["frozen"] or self._entry(inst["id"]) for inst in self.instances]

    def counts(self, entries: list[dict]) -> dict[str, int]:
        """created, picked, placed (ended in a place region, neither dropped nor missed),
        missed, dropped."""
        regions = self.ctx.regions
        return {"created": len(entries),
                "picked": sum(e["picked"] for e in entries),
                "placed": sum(1 for e in entries if regions.is_place(e["region"])
                              and not e["dropped"] and not e["missed"]),
                "missed": sum(e["missed"] for e in entries),
                "dropped": sum(e["dropped"] for e in entries)}
