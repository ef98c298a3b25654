"""Progress of a long run: simulated time, real-time factor, parts placed, errors so far.

On a terminal it is one line on standard error, redrawn in place (tqdm), that appears only
once a run has lasted a few seconds of wall-clock time, so short runs and test output stay
clean; `twin run` leaves it off when standard error is not a terminal or with --quiet.  In a
notebook the same figures go to tqdm's notebook widget (tqdm.auto).
"""

from __future__ import annotations

import sys
import time
from typing import TextIO

__all__ = ["Progress"]


class Progress:
    """Call once per major cycle (`Simulation.advance(on_cycle=...)`); `close` at the end."""

    def __init__(self, sim, *, delay_s: float = 3.0, interval_s: float = 0.5, file: TextIO | None = None,
                 notebook: bool = False) -> None:
        self.sim = sim
        self.delay_s = delay_s
        self.interval_s = interval_s
        self.file = file if file is not None else sys.stderr
        self.notebook = notebook
        self._start = time.perf_counter()
        self._start_sim = sim.cell.time
        self._next = self._start + delay_s
        self._bar = None

    def text(self) -> str:
        sim = self.sim
        wall = time.perf_counter() - self._start
        simulated = sim.cell.time - self._start_sim
        rate = simulated / wall if wall > 0 else 0.0
        placed = sum(1 for e in sim.cell.events if e["kind"] == "release")
        errors = len(getattr(sim, "errors", []))
        return (f"t = {sim.cell.time:.1f} s simulated, {rate:.1f}x real time, {placed} parts placed, "
                f"{errors} error{'' if errors == 1 else 's'}")

    def __call__(self) -> None:
        now = time.perf_counter()
        if now < self._next:
            return
        self._next = now + self.interval_s
        if self._bar is None:
            self._bar = self._open()
        self._bar.set_description_str(self.text())

    def _open(self):
        if self.notebook:
            from tqdm.auto import tqdm
        else:
            from tqdm import tqdm
        return tqdm(total=None, file=self.file, bar_format="twin: {desc}", leave=False, dynamic_ncols=True)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
            self._bar = None
