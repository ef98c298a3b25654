"""A feeder nest: a plate on a pedestal; whenever the nest has been empty for ``delay``
seconds the next part is put on it (position jitter ``jitter_xy`` mm, yaw jitter
``jitter_yaw`` deg, uniform, from the cell's seeded random stream)."""

from __future__ import annotations

import math

import mujoco
import numpy as np

from ..geometry import MM, yaw_quat
from .base import CellContext, Component

NEST_REGION_MARGIN = 8.0  # mm around the plate
NEST_REGION_HEIGHT = 30.0  # mm above its top


class NestFeeder(Component):
    section = "feeder"

    def __init__(self, config, ctx: CellContext):
        super().__init__(config, ctx)
        self.part_type = config.part or ctx.scene.part[0].name
        self.bodies = None  # reserved in `reserve_parts`
        self.presented = 0
        self._rng = ctx.rng()
        self._nest_top = np.array(config.nest, dtype=float) / MM
        self._empty_since: float | None = 0.0
        self._exhausted = False
        self._presented = np.zeros(0, dtype=int)  # bodies presented (the pool's part ids)

    def derived_regions(self):
        c = self.config
        half = np.array(c.nest_size) / 2 + NEST_REGION_MARGIN
        top = np.array(c.nest)
        return [(self.name, list(top - [half[0], half[1], 5.0]),
                 list(top + [half[0], half[1], NEST_REGION_HEIGHT]), False)]

    def reserve_parts(self, pool) -> None:
        self.bodies = pool.reserve(self, [self.part_type], self.config.pool)

    def build(self, spec: mujoco.MjSpec, ctx: CellContext) -> None:
        c = self.config
        nest = self._nest_top
        nsize = np.array(c.nest_size, dtype=float) / MM
        h = nest[2] - ctx.table_top_z
        spec.worldbody.add_geom(name=self.name, type=mujoco.mjtGeom.mjGEOM_BOX,
                                pos=[nest[0], nest[1], ctx.table_top_z + h / 2],
                                quat=yaw_quat(math.radians(c.nest_yaw)),
                                size=[nsize[0] / 2, nsize[1] / 2, h / 2], rgba=[0.25, 0.45, 0.3, 1])

    def bind(self, model, data, ctx: CellContext) -> None:
        self.parts = ctx.parts
        r = ctx.regions.index(self.name)
        self._box = list(zip(ctx.regions.lo[r].tolist(), ctx.regions.hi[r].tolist()))

    def _in_nest(self, body: int) -> bool:
        """Part body `body`'s centre is in the nest (three float comparisons: this runs
        every check, and numpy's per-call cost is ten times that)."""
        x = self.parts.data.xpos[self.parts.body[body]].tolist()
        return all(lo <= v <= hi for v, (lo, hi) in zip(x, self._box))

    def check(self, t: float) -> None:
        parts, presented = self.parts, self._presented
        # The part last presented is the one usually there; any other counts too.
        occupied = len(presented) > 0 and (self._in_nest(int(presented[-1])) or bool(
            self.ctx.regions.contains(self.name, parts.data.xpos[parts.body[presented]]).any()))
        if occupied:
            self._empty_since = None
            return
        if self._empty_since is None:
            self._empty_since = t
        elif t >= self._empty_since + self.config.delay - 1e-9:
            self._present()

    def _present(self) -> None:
        """Move the next pooled part to the nest (zero velocity, contacts on)."""
        c, parts = self.config, self.parts
        i = parts.take(self)
        if i is None:
            if not self._exhausted:
                self._exhausted = True
                self.ctx.event("feeder_empty")
            self._empty_since = None
            return
        jx, jy = self._rng.uniform(-1.0, 1.0, 2) * c.jitter_xy / MM
        jyaw = self._rng.uniform(-1.0, 1.0) * math.radians(c.jitter_yaw)
        pos = self._nest_top + [jx, jy, parts.half_height(i) + 0.0005]
        parts.activate(i, pos, yaw_quat(math.radians(c.nest_yaw) + jyaw), where=self.name)
        self._presented = np.append(self._presented[self._presented != i], i)
        self.presented += 1
        self._empty_since = None

    def report(self) -> dict:
        return {"presented": self.presented}
