"""A belt encoder for tests: driven by the cell's simulated time, no conveyor needed.

It follows the cell's encoder contract (docs/scene.md): `number`, `counts_per_mm`,
`counts()`, `latches` (a deque of (time s, count)) and `latch_input`.  The belt runs at
`speed` mm/s from `start_s`; the photo-eye latches the counter at `latch_times`.
"""

from __future__ import annotations

import math
from collections import deque

from twin.controller.belt import counter


class ClockEncoder:
    def __init__(self, cell, number: int = 1, counts_per_mm: float = 10.0, speed: float = 100.0,
                 start_s: float = 0.0, latch_times=(), latch_input: int | None = 1001, initial: int = 0):
        self.cell = cell
        self.number = number
        self.counts_per_mm = counts_per_mm
        self.speed = speed
        self.start_s = start_s
        self.initial = initial
        self.latch_input = latch_input
        self.latches: deque[tuple[float, int]] = deque()
        self._pending = sorted(latch_times)

    def _count_at(self, t: float) -> int:
        return counter(self.initial + math.floor(self.counts_per_mm * self.speed * max(t - self.start_s, 0.0)))

    def travel_mm(self, t: float) -> float:
        """Belt travel at time t (exact, not quantised to counts)."""
        return self.speed * max(t - self.start_s, 0.0)

    def counts(self) -> int:
        t = self.cell.time
        while self._pending and self._pending[0] <= t:
            when = self._pending.pop(0)
            self.latches.append((when, self._count_at(when)))
        return self._count_at(t)


class ClockConveyor:
    """A straight belt for tests, as the cell's conveyors expose it to the controller:
    `frame_world` (4x4, metres: the top face's centre, X along the travel) and `encoder`."""

    def __init__(self, frame_world, encoder: ClockEncoder):
        self.frame_world = frame_world
        self.encoder = encoder


def on_cell(cell, conveyors: dict[str, ClockConveyor]) -> None:
    """Give a cell these belts (its `conveyors` and `encoders`)."""
    cell.conveyors = conveyors
    cell.encoders = {c.encoder.number: c.encoder for c in conveyors.values()}
