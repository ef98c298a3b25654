"""What the programs do, into the recording: TYPE output line by line at the simulated
time it was typed, the program line each V+ task and each GPL thread is at (a text line and
the line number as a scalar, logged only when it changes, so a motion that takes 400 cycles
costs one entry), and the tool-tip path of each motion the controller plans.

Called once per major cycle from Simulation._record.  The console's chunks are read from
where the last cycle left off (never the whole output again); a line still open at the end
of the run goes out at `close`.  Where a task or thread is costs one walk down its chain of
generators (a few microseconds), the same walk the watchdog's message makes, in the cycles
where some task ran (most cycles a program only waits for its motion).
"""

from __future__ import annotations

import mujoco
import numpy as np

from .recorder import entity_part

__all__ = ["ProgramTrace", "PlanTrace"]

PLAN_POINTS = 32  # samples of a planned path drawn: enough for a joint move's curve


class ProgramTrace:
    def __init__(self, recorder, system, simulation=None) -> None:
        self.recorder = recorder
        self.system = system
        self._chunks = 0          # console chunks already read
        self._partial = ""        # typed text after the last line break
        self._where: dict[str, tuple[str, int] | None] = {}
        self._thread_entities: dict[int, str] = {}   # escaping a name costs more than the lookup
        self._scheduler = None if simulation is None else simulation.scheduler
        self._runs = -1  # the scheduler's `runs` when the tasks were last looked at
        if simulation is not None:
            simulation.controller.on_plan = PlanTrace(recorder, simulation.cell).plan

    def cycle(self, t: float) -> None:
        text = self.system.console.text
        if len(text) > self._chunks:
            *lines, self._partial = (self._partial + "".join(text[self._chunks:])).split("\n")
            self._chunks = len(text)
            for line in lines:
                self.recorder.log_text(t, line, path="program/log")
        if self._scheduler is not None:  # no task ran since the last look: none moved on
            if self._scheduler.runs == self._runs:
                return
            self._runs = self._scheduler.runs
        for entity, where in self._positions().items():
            if self._where.get(entity) == where:
                continue
            self._where[entity] = where
            if where is not None:
                program, line, source = where
                self.recorder.log_text(t, f"{program} line {line}: {(source or '').strip()}", path=f"{entity}/line")
                self.recorder.log_scalar(f"{entity}/line_number", t, float(line))

    def _positions(self) -> dict[str, tuple[str, int, str | None] | None]:
        """entity -> (program, line, source text), or None when not running, for each V+
        task and GPL thread (a task number started again: the latest start counts)."""
        system = self.system
        positions = {}
        for task in getattr(system, "tasks", ()):
            found = task.current_statement()
            where = None
            if found is not None:
                compiled, line = found[0], found[1].line
                where = (compiled.name, line, system.source_line(compiled.file, line))
            positions[f"program/task{task.number}"] = where
        for thread in getattr(system, "threads", ()):
            found = None if thread.finished else thread.current_location()
            where = None if found is None else (found["program"], found["line"], found["text"])
            entity = self._thread_entities.get(id(thread))
            if entity is None:
                entity = self._thread_entities[id(thread)] = f"program/thread_{entity_part(thread.name)}"
            positions[entity] = where
        return positions

    def close(self, t: float) -> None:
        self.cycle(t)
        if self._partial:
            self.recorder.log_text(t, self._partial, path="program/log")
            self._partial = ""


class PlanTrace:
    """The tool-tip path of each planned motion, at the simulated time it was planned: the
    joint samples put through MuJoCo's kinematics on a scratch copy of the cell's state, so
    the planned path and the executed one (world/tcp) are the same point of the same model."""

    def __init__(self, recorder, cell) -> None:
        self.recorder = recorder
        self.cell = cell
        self._data = mujoco.MjData(cell.model)
        self._qadr = cell.robot.qadr
        self._site = cell.gripper.tcp_site

    def plan(self, q: np.ndarray, straight: bool) -> None:
        cell, data = self.cell, self._data
        rows = np.unique(np.linspace(0, len(q) - 1, min(len(q), PLAN_POINTS)).round().astype(int))
        data.qpos[:] = cell.data.qpos
        points = np.empty((len(rows), 3))
        for i, row in enumerate(rows):
            data.qpos[self._qadr] = q[row]
            mujoco.mj_kinematics(cell.model, data)
            points[i] = data.site_xpos[self._site]
        self.recorder.log_plan(cell.time, points, "straight" if straight else "joint")
