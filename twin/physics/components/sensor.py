"""Sensors wired to digital inputs (V+ numbering 1001-1512).

* ``type = "photo_eye"``: a light beam across a belt, ``position`` mm from its upstream end
  and ``height`` mm above its surface, tested with a ray (``mujoco.mj_ray``, moving bodies
  only: the rails do not break it) every check. The input is on while the beam is broken.
  On each rising edge the encoder ``latch_encoder`` (if any) latches the count at which the
  part's leading edge crossed the beam: the check finds the beam broken up to one check
  interval late, so the count is taken back by how far the part's leading edge (its
  support point along the travel) is past the beam, giving the crossing within one count.
* ``type = "presence"``: on while the centre of any live part is inside the world box
  ``lo``..``hi`` (mm), e.g. a proximity switch at a nest or a tray.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from ..geometry import MM
from .base import CellContext, Component


class PhotoEye(Component):
    section = "sensor"

    def __init__(self, config, ctx: CellContext):
        super().__init__(config, ctx)
        self.state = False
        self.breaks = 0

    def bind(self, model: mujoco.MjModel, data: mujoco.MjData, ctx: CellContext) -> None:
        self.model, self.data = model, data
        c = self.config
        belt = self.belt = ctx.component("conveyor", c.conveyor)
        self.x_local = -belt.length / 2 + c.position / MM
        reach = belt.width / 2 + 0.02  # emitter and reflector just outside the rails
        self._start = belt.to_world([self.x_local, reach, c.height / MM])
        self._dir = -belt.frame_world[:3, 1]
        self._length = 2 * reach
        self._geomid = np.zeros(1, dtype=np.int32)
        self.encoder = None
        if c.latch_encoder is not None:
            self.encoder = next(b.encoder for b in ctx.by_kind["conveyor"].values()
                                if b.encoder is not None and b.encoder.number == c.latch_encoder)
            self.encoder.latch_input = c.input
        ctx.io.set(c.input, False)

    def _beam(self) -> int:
        """Geom breaking the beam, or -1."""
        dist = mujoco.mj_ray(self.model, self.data, self._start, self._dir, None, 0, -1, self._geomid)
        return int(self._geomid[0]) if 0 <= dist <= self._length else -1

    def check(self, t: float) -> None:
        geom = self._beam()
        broken = geom >= 0
        if broken == self.state:
            return
        self.state = broken
        self.ctx.io.set(self.config.input, broken)
        if broken:
            self.breaks += 1
            if self.encoder is not None:
                self._latch(t, geom)

    def _latch(self, t: float, geom: int) -> None:
        belt = self.belt
        v = belt.speed_mm_s
        travel = belt.travel_mm()
        s = 1.0 if v >= 0 else -1.0
        lead = max(0.0, s * (self._support(geom, s * belt.axis) @ belt.axis - self._beam_x_world()))
        t_cross = t - (lead * MM / abs(v) if v != 0 else 0.0)
        self.encoder.latch(round(t_cross, 6), travel - s * lead * MM)

    def _beam_x_world(self) -> float:
        return float(self._start @ self.belt.axis)

    def _support(self, geom: int, u: np.ndarray) -> np.ndarray:
        """The geom's farthest point along the world direction u (box, cylinder, mesh)."""
        m, d = self.model, self.data
        c, R = d.geom_xpos[geom], d.geom_xmat[geom].reshape(3, 3)
        ul = R.T @ u
        size = m.geom_size[geom]
        gtype = m.geom_type[geom]
        if gtype == mujoco.mjtGeom.mjGEOM_BOX:
            local = np.sign(ul) * size
        elif gtype == mujoco.mjtGeom.mjGEOM_CYLINDER:
            radial = np.array([ul[0], ul[1], 0.0])
            n = np.linalg.norm(radial)
            local = (radial / n * size[0] if n > 0 else np.zeros(3)) + [0.0, 0.0, math.copysign(size[1], ul[2])]
        elif gtype == mujoco.mjtGeom.mjGEOM_MESH:
            mid = m.geom_dataid[geom]
            va, vn = m.mesh_vertadr[mid], m.mesh_vertnum[mid]
            verts = m.mesh_vert[va:va + vn]
            local = verts[np.argmax(verts @ ul)]
        else:  # the bounding box: never short of the true support
            local = np.sign(ul) * m.geom_aabb[geom, 3:] + m.geom_aabb[geom, :3]
        return c + R @ local

    def report(self) -> dict:
        return {"input": self.config.input, "breaks": self.breaks}

    def record(self, recorder, t: float) -> None:
        recorder.log_scalar(f"sensor/{self.name}", t, float(self.state))


class PresenceSensor(Component):
    section = "sensor"

    def __init__(self, config, ctx: CellContext):
        super().__init__(config, ctx)
        self.lo = np.array(config.lo, dtype=float) / MM
        self.hi = np.array(config.hi, dtype=float) / MM
        self.state = False

    def bind(self, model, data, ctx: CellContext) -> None:
        self.parts = ctx.parts
        ctx.io.set(self.config.input, False)

    def check(self, t: float) -> None:
        parts = self.parts
        live = parts.live
        pos = parts.data.xpos[parts.shown[live]]
        on = bool(len(live)) and bool(np.all((pos >= self.lo) & (pos <= self.hi), axis=1).any())
        if on != self.state:
            self.state = on
            self.ctx.io.set(self.config.input, on)

    def report(self) -> dict:
        return {"input": self.config.input, "on": self.state}

    def record(self, recorder, t: float) -> None:
        recorder.log_scalar(f"sensor/{self.name}", t, float(self.state))


def make_sensor(config, ctx: CellContext) -> Component:
    return (PhotoEye if config.type == "photo_eye" else PresenceSensor)(config, ctx)
