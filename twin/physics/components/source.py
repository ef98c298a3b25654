"""A part source: puts parts on a belt, near its upstream end, at random intervals.

Intervals (s) between parts, from the source's own seeded random stream:
``distribution = "fixed"`` (always ``mean_interval``), ``"uniform"`` (0.5 to 1.5 x the
mean) or ``"exponential"`` (a Poisson stream of that mean); a part is held back until the
belt has moved ``min_gap`` mm since the last one, so parts never land on each other.
Each part: a type drawn from ``parts`` (with ``weights``), at ``position`` mm from the
belt's upstream end, ``lateral`` mm across it plus a uniform +/- ``jitter_lateral``, yaw
``yaw`` +/- ``jitter_yaw`` relative to the belt; it starts at the belt's speed.

A part that was never picked and leaves the belt (past its downstream end, or off a
side) is "missed" (an event, ``counts.missed``); once it has fallen (floor, or a bin) its
body goes back to the pool.
"""

from __future__ import annotations

import math

import numpy as np

from ..geometry import MM, matrix_to_quat
from .base import CellContext, Component

MISS_CHECK_S = 0.1  # s between checks for parts that left the belt


class Source(Component):
    section = "source"

    def __init__(self, config, ctx: CellContext):
        super().__init__(config, ctx)
        c = config
        self.types = list(c.parts) if c.parts else [p.name for p in ctx.scene.part]
        w = np.array(c.weights if c.weights else [1.0] * len(self.types), dtype=float)
        self.weights = w / w.sum()
        self._rng = ctx.rng()
        self._next_t = c.start
        self._last_travel: float | None = None
        self._next_miss_check = MISS_CHECK_S
        self.created = 0
        self._empty = False

    def reserve_parts(self, pool) -> None:
        self.bodies = pool.reserve(self, self.types, self.config.pool * len(self.types))

    def bind(self, model, data, ctx: CellContext) -> None:
        self.parts = ctx.parts
        self.conveyor = ctx.component("conveyor", self.config.conveyor)

    def _interval(self) -> float:
        c = self.config
        if c.distribution == "fixed":
            return c.mean_interval
        if c.distribution == "uniform":
            return float(self._rng.uniform(0.5, 1.5) * c.mean_interval)
        return float(self._rng.exponential(c.mean_interval))

    def check(self, t: float) -> None:
        if t + 1e-9 >= self._next_t:
            belt = self.conveyor
            gap_ok = (self._last_travel is None
                      or abs(belt.travel_mm() - self._last_travel) >= self.config.min_gap)
            if gap_ok and self._spawn():
                self._last_travel = belt.travel_mm()
                self._next_t = t + self._interval()
        if t + 1e-9 >= self._next_miss_check:
            self._next_miss_check = t + MISS_CHECK_S
            self._check_missed()

    def _spawn(self) -> bool:
        c, parts, belt = self.config, self.parts, self.conveyor
        type_name = self.types[int(self._rng.choice(len(self.types), p=self.weights))] if len(self.types) > 1 \
            else self.types[0]
        lateral = (c.lateral + self._rng.uniform(-1.0, 1.0) * c.jitter_lateral) / MM
        yaw = math.radians(c.yaw + self._rng.uniform(-1.0, 1.0) * c.jitter_yaw)
        i = parts.take(self, type_name)
        if i is None:
            if not self._empty:  # once until a part can be spawned again
                self._empty = True
                self.ctx.event("source_empty", source=self.name)
            return False
        self._empty = False
        local = [-belt.length / 2 + c.position / MM, lateral, parts.half_height(i) + 0.0005]
        pos = belt.to_world(local)
        R = belt.frame_world[:3, :3] @ np.array([[math.cos(yaw), -math.sin(yaw), 0.0],
                                                 [math.sin(yaw), math.cos(yaw), 0.0], [0.0, 0.0, 1.0]])
        parts.activate(i, pos, matrix_to_quat(R), where=belt.name, velocity=belt.axis * belt.speed_mm_s / MM, kind="spawn")
        self.created += 1
        return True

    def _check_missed(self) -> None:
        parts, belt = self.parts, self.conveyor
        mine = self.bodies[parts.instance_of[self.bodies] >= 0]
        if not len(mine):
            return
        local = belt.to_local(parts.data.xpos[parts.shown[mine]])
        off = (np.abs(local[:, 0]) > belt.length / 2) | (np.abs(local[:, 1]) > belt.width / 2) | (local[:, 2] < -0.01)
        held = self.ctx.held_part()
        for i in mine[off].tolist():
            inst = parts.instance(i)
            if not inst["picked"] and not inst["missed"] and i != held:
                parts.mark_missed(i, f"left {belt.name} unpicked")

    def report(self) -> dict:
        return {"created": self.created}
