"""A cell, its controller and the programs running on it, stepped together.

The pipeline, once per major cycle (16 ms, the V+ scheduler's cycle):
  tasks run until they wait (scheduler) -> the controller feeds the servos
  each physics step -> the cell steps MuJoCo (grippers, feeder, belt) ->
  the recorder samples a frame when one is due.
Simulated time drives everything; nothing waits on the wall clock.
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from .controller.controller import COLLISION, MotionSettings, VirtualController
from .controller.io import DigitalIO
from .controller.location import Location
from .controller.scheduler import Scheduler
from .errors import ProgramError
from .physics.cell import Cell
from .resources import bundled
from .vision.server import VisionServer

MAJOR_CYCLE_S = 0.016
DEFAULT_SCENE = bundled("scenes/scara_pick.toml")


@dataclass
class RunOutcome:
    sim_time_s: float
    wall_time_s: float
    program_time_s: float  # when the last program task ended
    errors: list[dict] = field(default_factory=list)


class Simulation:
    """A loaded cell with its robot controller, I/O and task scheduler."""

    def __init__(self, scene: str | Path = DEFAULT_SCENE, seed: int | None = None, recorder=None):
        self.scene_path = Path(scene)
        self.io = DigitalIO()  # the controller's signals; the cell's components read and drive them
        self.cell = Cell.from_scene(self.scene_path, seed=seed, io=self.io)
        self.kinematics = self.cell.kinematics
        controller_cfg = self.cell.scene.get("controller", {})
        settings = MotionSettings(
            monitor_speed=float(controller_cfg.get("monitor_speed", MotionSettings.monitor_speed)),
            cartesian_speed_mm_s=float(
                controller_cfg.get("cartesian_speed_mm_s", MotionSettings.cartesian_speed_mm_s)
            ),
        )
        self.controller = VirtualController(self.cell, self.kinematics, settings)
        self.scheduler = Scheduler()
        self.recorder = recorder
        self.trace = None  # twin.program_trace.ProgramTrace: TYPE lines and program lines, recorded
        self.vision = VisionServer.for_cell(self.cell, self.cell.scene, self.scene_path)  # None without [vision]
        self._events_recorded = 0  # cell events already sent to the recorder
        self.settle_s = float(controller_cfg.get("settle_after_program_s", 3.0))
        self.stop = threading.Event()   # set (by a signal handler): the run stops at the next cycle
        self.interrupted = False        # the last run was stopped by `stop`

    def taught_locations(self) -> dict[str, Location]:
        return {name: Location(*values) for name, values in self.cell.locations().items()}

    def clock(self) -> float:
        return self.cell.time

    def run(self, max_sim_time: float = 3600.0, on_cycle: Callable[[], bool] | None = None) -> RunOutcome:
        """Run until every task has ended and the cell has settled, or until `on_cycle`,
        called after every major cycle (`twin serve` paces and stops with it), says stop,
        or `stop` is set."""
        self.begin(max_sim_time)
        self.advance(on_cycle=on_cycle)
        return self.outcome()

    def begin(self, max_sim_time: float = 3600.0) -> None:
        """Start a run that `advance` carries on, in as many pieces as wanted (a notebook
        runs to a time, a line or a signal, looks, and continues)."""
        self.max_sim_time = max_sim_time
        self.errors: list[dict] = []
        self.program_end: float | None = None
        self.finished = False
        self.interrupted = False
        self._crashed = False
        self._wall_s = 0.0

    def advance(self, until: Callable[[], bool] | None = None,
                on_cycle: Callable[[], bool | None] | None = None) -> bool:
        """Major cycles until the run is over or `until()` is true after a cycle; returns
        whether the run is over.  `on_cycle` is called after every cycle (progress, pacing);
        a true answer ends the run there."""
        wall_start = time.perf_counter()
        try:
            while not self.finished:
                self._cycle()
                if on_cycle is not None and on_cycle() and not self.finished:
                    self.finished = True
                    self.program_end = self.program_end if self.program_end is not None else self.cell.time
                if self.stop.is_set() and not self.finished:
                    self.finished = self.interrupted = True
                    self.program_end = self.program_end if self.program_end is not None else self.cell.time
                if until is not None and until():
                    break
        finally:
            self._wall_s += time.perf_counter() - wall_start
        return self.finished

    def outcome(self) -> RunOutcome:
        return RunOutcome(self.cell.time, self._wall_s, self.program_end, self.errors)

    def _cycle(self) -> None:
        """One major cycle: the tasks, then the servos and the physics; sets `finished`."""
        cell, controller, scheduler, errors = self.cell, self.controller, self.scheduler, self.errors
        steps = max(1, round(MAJOR_CYCLE_S / cell.timestep))
        if self.program_end is None:
            scheduler.run_cycle()
            for task in scheduler.tasks:
                error = getattr(task, "error", None)
                if error is not None and not getattr(task, "reported", False):
                    task.reported = True
                    controller.stop()
                    errors.append(error.as_dict(cell.time))
            if not scheduler.alive:
                self.program_end = cell.time
        # After the programs end the robot finishes its motion and parts come to rest.
        elif not controller.moving and cell.time >= self.program_end + self.settle_s:
            self.finished = True
            return
        if cell.time >= self.max_sim_time:
            error = ProgramError(f"*Simulation time limit reached* ({self.max_sim_time:g} s)")
            errors.append(error.as_dict(cell.time))
            self.program_end = self.program_end if self.program_end is not None else cell.time
            self.finished = True
            return
        for _ in range(steps):
            controller.servo_step()
            cell.step(1)
        collisions = cell.take_collisions()
        if collisions and not self._crashed:  # the first one stops everything; all are events
            self._crashed = True
            error = self._stop_for_collision(collisions[0])
            if error is not None:  # no program was running to take it
                errors.append(error.as_dict(cell.time))
        fault = controller.take_fault()  # the robot stopped by itself (a belt window violation)
        if fault is not None and self._give_to_tasks(fault) is not None:
            errors.append(fault.as_dict(cell.time))
        self._record()

    def _record(self) -> None:
        """Once per major cycle: a recording frame when one is due, and the digital signals
        and cell events (grasp, release, slip, drop, collision...) of the cycle, at their
        times.  Without a recorder the signal changes are dropped so they do not pile up."""
        cell, recorder, changes = self.cell, self.recorder, self.io.changes
        if recorder is None:
            changes.clear()
            return
        for number, value in changes:
            recorder.log_scalar(f"signals/{number}", cell.time, float(value))
        changes.clear()
        if self.trace is not None:
            self.trace.cycle(cell.time)
        events = cell.events
        for event in events[self._events_recorded:]:
            detail = ", ".join(f"{k}={v}" for k, v in event.items() if k not in ("t", "kind"))
            recorder.log_text(event["t"], f"{event['kind']}: {detail}", path="cell/events")
        self._events_recorded = len(events)
        if recorder.wants_frame(cell.time):
            recorder.sample(cell.time, cell.data)
            cell.record(recorder)

    def _stop_for_collision(self, collision: dict) -> ProgramError | None:
        """The robot hit something: it stops where it is, and each running program stops with
        the error at the step it was executing (docs/motion.md, collision policy).  Returns
        the error when no program took it (none was running, or a task's generator does not
        turn errors into its own report)."""
        self.controller.halt()
        text = f"*Collision detected* {collision['robot_geom']} with {collision['with']}"
        return self._give_to_tasks(ProgramError(text, COLLISION))

    def _give_to_tasks(self, error: ProgramError) -> ProgramError | None:
        """Each running program stops with `error` at the step it is executing; returns the
        error when no program took it."""
        taken = False
        for task in [task for task in self.scheduler.tasks if not task.finished]:
            try:
                task.generator.throw(ProgramError(error.message, error.code))  # one each: it gets located
                taken = True
            except StopIteration:
                taken = True
            except ProgramError:
                task.finished = True
        return None if taken else error
