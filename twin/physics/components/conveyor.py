"""Conveyors: straight belts at any pose that carry parts by contact and friction.

The belt is a thin static box with MuJoCo's ``surfacevel`` (since 3.11): whatever touches
it is moved by friction at the surface speed, with no degrees of freedom; side rails are
separate geoms (``surfacevel`` acts on every face of the belt). The surface speed ramps
toward its target at ``accel`` mm/s^2, updated every check (10 ms): a part follows the
ramp while friction can accelerate it (mu * g, about 4.9 m/s^2 for mu 0.5); a steeper ramp
makes it slip. Parts leave by the far end and fall.

Signals (V+ numbering, through the cell's `DigitalIO`): ``run_output`` on = running (when
set; otherwise ``running`` and `start`/`stop`), ``reverse_output`` on = backwards. The
speed is a cell parameter: ``speed`` in the scene, `set_speed` at run time.

Contract with the controller (conveyor tracking; names kept stable):

* ``conveyor.frame_world``: 4x4 world pose (m) of the belt's top-face centre; the belt
  travels along +x of that frame, z is the belt's normal;
* ``conveyor.encoder``: an `Encoder` or None; the cell collects them in
  ``cell.encoders: dict[int, Encoder]`` keyed by the 1-based encoder number;
* ``Encoder.number``, ``Encoder.counts_per_mm: float``, ``Encoder.counts() -> int`` (the
  belt's integrated travel x counts_per_mm, rounded; exact between checks, signed: a
  reversed belt counts down), ``Encoder.latches: collections.deque[tuple[float, int]]``
  of (sim time s, count) appended on each latch (a photo-eye's rising edge, the count at
  the moment the part's leading edge crossed the beam), ``Encoder.latch_input: int | None``
  (the digital input of the photo-eye that latches it).
"""

from __future__ import annotations

import collections
import math

import mujoco
import numpy as np

from ..geometry import MM, matrix_to_quat, yaw_quat
from .base import CellContext, Component

LATCH_BUFFER = 1000  # latches kept per encoder (oldest dropped)
RAIL_THICKNESS = 0.008  # m
REGION_HEIGHT = 100.0  # mm above the belt that count as "on the belt"
# Contact stiffness of the belt: MuJoCo's soft friction lets a part lag a changing belt
# speed by about v * timeconst (measured 5 mm after a ramp to 500 mm/s with the default
# 0.02 s, 2.5 mm with 0.004 s: the stiffest a 2 ms step allows).
BELT_SOLREF = [0.004, 1.0]


class Encoder:
    """A belt encoder (see the module docstring)."""

    def __init__(self, number: int, counts_per_mm: float, conveyor: "Conveyor"):
        self.number = number
        self.counts_per_mm = float(counts_per_mm)
        self.conveyor = conveyor
        self.latches: collections.deque[tuple[float, int]] = collections.deque(maxlen=LATCH_BUFFER)
        self.latch_input: int | None = None

    def counts(self) -> int:
        return self.counts_at(self.conveyor.travel_mm())

    def counts_at(self, travel_mm: float) -> int:
        return int(math.floor(travel_mm * self.counts_per_mm + 0.5))

    def latch(self, t: float, travel_mm: float) -> None:
        self.latches.append((float(t), self.counts_at(float(travel_mm))))


class Conveyor(Component):
    section = "conveyor"

    def __init__(self, config, ctx: CellContext):
        super().__init__(config, ctx)
        c = config
        d = np.array(list(c.direction) + [0.0] * (3 - len(c.direction)), dtype=float)
        d /= np.linalg.norm(d)
        side = np.cross([0.0, 0.0, 1.0], d)
        if np.linalg.norm(side) < 1e-6:
            side = np.array([0.0, 1.0, 0.0])
        side /= np.linalg.norm(side)
        normal = np.cross(d, side)
        self.frame_world = np.eye(4)
        self.frame_world[:3, :3] = np.column_stack([d, side, normal])
        self.frame_world[:3, 3] = np.array(c.top_center, dtype=float) / MM
        self.flat = abs(d[2]) < 1e-12
        self.width, self.length, self.thickness = (v / MM for v in c.size)
        self.target_mm_s = float(c.speed)
        self._running = bool(c.running)
        self._v = self._target() / MM  # m/s, signed: the belt starts at its speed
        self._travel = 0.0  # m up to _t_last
        self._t_last = 0.0
        self.encoder = Encoder(c.encoder.number, c.encoder.counts_per_mm, self) if c.encoder else None

    # ------------------------------------------------------------------ geometry
    @property
    def axis(self) -> np.ndarray:
        return self.frame_world[:3, 0]

    def to_local(self, points: np.ndarray) -> np.ndarray:
        """World points (N x 3, m) in the belt frame (m)."""
        return (np.asarray(points) - self.frame_world[:3, 3]) @ self.frame_world[:3, :3]

    def to_world(self, local) -> np.ndarray:
        return self.frame_world[:3, 3] + self.frame_world[:3, :3] @ np.asarray(local, dtype=float)

    def _quat(self) -> np.ndarray:
        if self.flat:  # the exact yaw quaternion (the cells' belts were built this way)
            return yaw_quat(math.atan2(self.axis[1], self.axis[0]))
        return matrix_to_quat(self.frame_world[:3, :3])

    def _bounds_mm(self, below: float, above: float) -> tuple[np.ndarray, np.ndarray]:
        corners = np.array([[sx * self.length / 2, sy * self.width / 2, z]
                            for sx in (-1, 1) for sy in (-1, 1) for z in (-below, above)])
        pts = np.array([self.to_world(c) for c in corners]) * MM
        return pts.min(axis=0), pts.max(axis=0)

    def derived_regions(self):
        lo, hi = self._bounds_mm(0.005, REGION_HEIGHT / MM)
        return [(self.name, list(lo), list(hi), self.config.place)]

    def build(self, spec: mujoco.MjSpec, ctx: CellContext) -> None:
        c, wb, n = self.config, spec.worldbody, self.name
        top = self.frame_world[:3, 3]
        normal, side = self.frame_world[:3, 2], self.frame_world[:3, 1]
        q = self._quat()
        belt = wb.add_geom(name=f"{n}_belt", type=mujoco.mjtGeom.mjGEOM_BOX, pos=top - normal * self.thickness / 2,
                           quat=q, size=[self.length / 2, self.width / 2, self.thickness / 2],
                           rgba=[0.15, 0.15, 0.15, 1], friction=[c.friction, 0.005, 0.0001],
                           solref=BELT_SOLREF)
        # Geom frame: local x = travel. MuJoCo moves parts only on a geom compiled with a
        # nonzero surfacevel (measured: one compiled at 0 ignores later values), so a belt
        # that starts stopped is compiled at 1 nm/s and set to 0 in `bind`.
        belt.surfacevel = np.array([self._v or 1e-9, 0.0, 0.0, 0.0, 0.0, 0.0])
        rail_h = c.rail_height / MM
        if rail_h > 0:
            for k, s in (("left", 1.0), ("right", -1.0)):
                wb.add_geom(name=f"{n}_belt_rail_{k}", type=mujoco.mjtGeom.mjGEOM_BOX,
                            pos=top + s * side * (self.width / 2 + RAIL_THICKNESS / 2)
                            + normal * (rail_h - self.thickness) / 2, quat=q,
                            size=[self.length / 2, RAIL_THICKNESS / 2, (rail_h + self.thickness) / 2],
                            rgba=[0.7, 0.7, 0.72, 1])
        frame_h = top[2] - self.thickness - ctx.table_top_z
        if frame_h > 0 and self.flat:
            wb.add_geom(name=f"{n}_belt_frame", type=mujoco.mjtGeom.mjGEOM_BOX, contype=0, conaffinity=0,
                        pos=[top[0], top[1], ctx.table_top_z + frame_h / 2], quat=q,
                        size=[self.length / 2 * 0.95, self.width / 2, frame_h / 2], rgba=[0.4, 0.4, 0.45, 1])

    def bind(self, model: mujoco.MjModel, data: mujoco.MjData, ctx: CellContext) -> None:
        self.model, self.data = model, data
        self._geom = model.geom(f"{self.name}_belt").id
        model.geom_surfacevel[self._geom, 0] = self._v
        lo, hi = self._bounds_mm(0.005, REGION_HEIGHT / MM)
        self._wake_box = (lo / MM, hi / MM)

    # ------------------------------------------------------------------ control
    def start(self) -> None:
        self._running = True

    def stop(self) -> None:
        self._running = False

    def set_speed(self, mm_s: float) -> None:
        """The belt's set speed (mm/s, >= 0); it ramps there at ``accel``."""
        if not math.isfinite(mm_s) or mm_s < 0:
            raise ValueError(f"conveyor speed must be a finite number >= 0, got {mm_s!r}")
        self.target_mm_s = float(mm_s)

    @property
    def running(self) -> bool:
        out = self.config.run_output
        return self.ctx.io.state.get(out, False) if out is not None else self._running

    @property
    def reversed(self) -> bool:
        out = self.config.reverse_output
        return out is not None and self.ctx.io.state.get(out, False)

    def _target(self) -> float:
        """Target surface speed, mm/s, signed."""
        if not self.running:
            return 0.0
        return -self.target_mm_s if self.reversed else self.target_mm_s

    @property
    def speed_mm_s(self) -> float:
        """Current surface speed, mm/s (negative when reversed)."""
        return self._v * MM

    def travel_mm(self) -> float:
        """Belt travel since the start, mm (signed), exact at the current time."""
        return (self._travel + self._v * (float(self.data.time) - self._t_last)) * MM

    def check(self, t: float) -> None:
        dt = t - self._t_last
        self._travel += self._v * dt
        self._t_last = t
        target = self._target() / MM
        if target == self._v:
            return
        step = self.config.accel / MM * dt
        v = target if abs(target - self._v) <= step else self._v + math.copysign(step, target - self._v)
        if self._v == 0.0:
            self.ctx.parts.wake(*self._wake_box)
        self._v = v
        self.model.geom_surfacevel[self._geom, 0] = v

    # ------------------------------------------------------------------ outputs
    def report(self) -> dict:
        out = {"speed_mm_s": round(self.speed_mm_s, 3), "travel_mm": round(self.travel_mm(), 3)}
        if self.encoder is not None:
            out.update(encoder=self.encoder.number, counts=self.encoder.counts(),
                       latches=len(self.encoder.latches))
        return out

    def record(self, recorder, t: float) -> None:
        recorder.log_scalar(f"conveyor/{self.name}/speed_mm_s", t, self.speed_mm_s)
        if self.encoder is not None:
            recorder.log_scalar(f"conveyor/{self.name}/encoder_{self.encoder.number}", t,
                                float(self.encoder.counts()))
