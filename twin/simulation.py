"""A cell, its controller and the programs running on it, stepped together.

The pipeline, once per major cycle (16 ms, the V+ scheduler's cycle):
  tasks run until they wait (scheduler) -> the controller computes the servo
  references of the cycle's physics steps (in chunks between motion starts) -> the
  cell steps MuJoCo, feeding them each step (grippers, feeder, belt) ->
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
from .controller.io import INPUTS, DigitalIO
from .controller.location import Location
from .controller.scheduler import Scheduler
from .controller.watchdog import (DEADLOCK_CONFIRM_S, DEFAULT_NO_PROGRESS_S, Watchdog, WatchdogLimits,
                                  is_external, task_is_blocked)
from .errors import ProgramError
from .physics.cell import Cell
from .resources import bundled

MAJOR_CYCLE_S = 0.016
AT_REST_SPEED = 1e-3  # m/s or rad/s: a body slower than this is not moving (watchdog)
DEFAULT_SCENE = bundled("scenes/scara_pick.toml")


@dataclass
class RunOutcome:
    sim_time_s: float
    wall_time_s: float
    program_time_s: float  # when the last program task ended
    errors: list[dict] = field(default_factory=list)


class Simulation:
    """A loaded cell with its robot controller, I/O and task scheduler."""

    def __init__(self, scene: str | Path = DEFAULT_SCENE, seed: int | None = None, recorder=None,
                 overrides: dict[str, object] | None = None):
        self.scene_path = Path(scene)
        self.io = DigitalIO()  # the controller's signals; the cell's components read and drive them
        self.cell = Cell.from_scene(self.scene_path, seed=seed, io=self.io, overrides=overrides)
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
        self.vision = self._vision_server()  # None without [vision]
        self._events_recorded = 0  # cell events already sent to the recorder
        self._windows_shown: dict[int, tuple] = {}  # belt frame -> the window last drawn
        self.settle_s = float(controller_cfg.get("settle_after_program_s", 3.0))
        self.stop = threading.Event()   # set (by a signal handler): the run stops at the next cycle
        self.interrupted = False        # the last run was stopped by `stop`
        no_progress = float(controller_cfg.get("no_progress_s", DEFAULT_NO_PROGRESS_S))
        self.no_progress_s: float | None = no_progress if no_progress > 0 else None
        self.clock_reads = 0  # how often the programs read the time (watchdog: a wait may end)
        self._events_watched = 0  # cell events the watchdog has seen
        self._hand_watched = self.controller.hand_state
        self._encoders_watched: tuple[int, ...] = ()
        # A source brings parts for ever and a feeder one after its delay: the cell is never a
        # fixed point with a source, and a feeder's delay is waited out before a deadlock.
        self._cell_lives = any(c.section == "source" for c in self.cell.components)
        self.deadlock_confirm_s = DEADLOCK_CONFIRM_S + max(
            (float(c.config.delay) for c in self.cell.components if c.section == "feeder"), default=0.0)

    def _vision_server(self):
        """The cell's vision server, or None for a cell without a [vision] section.  The
        vision package (OpenCV, the offscreen renderer) is imported only for a cell that
        has one: about 0.1 s of every other run's start-up."""
        if "vision" not in self.cell.scene:
            return None
        from .vision.server import VisionServer

        return VisionServer.for_cell(self.cell, self.cell.scene, self.scene_path)

    def taught_locations(self) -> dict[str, Location]:
        return {name: Location(*values) for name, values in self.cell.locations().items()}

    def clock(self) -> float:
        self.clock_reads += 1
        return self.cell.time

    def run(self, max_sim_time: float = 3600.0, on_cycle: Callable[[], bool] | None = None,
            max_wall_time: float | None = None) -> RunOutcome:
        """Run until every task has ended and the cell has settled, or until `on_cycle`,
        called after every major cycle (`twin serve` paces and stops with it), says stop,
        or `stop` is set, or a limit or the watchdog stops it (docs/robustness.md)."""
        self.begin(max_sim_time, max_wall_time)
        self.advance(on_cycle=on_cycle)
        return self.outcome()

    def begin(self, max_sim_time: float = 3600.0, max_wall_time: float | None = None) -> None:
        """Start a run that `advance` carries on, in as many pieces as wanted (a notebook
        runs to a time, a line or a signal, looks, and continues)."""
        self.max_sim_time = max_sim_time
        self.watchdog = Watchdog(WatchdogLimits(self.no_progress_s, max_wall_time, self.deadlock_confirm_s))
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
            reads, alive = self.clock_reads, self._live_tasks()
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
        while steps > 0:  # in chunks: MuJoCo steps as many as it can in one call
            k, feed = controller.servo_chunk(steps)
            cell.step(k, feed)
            steps -= k
        collisions = cell.take_collisions()
        if collisions and not self._crashed:  # the first one stops everything; all are events
            self._crashed = True
            error = self._stop_for_collision(collisions[0])
            if error is not None:  # no program was running to take it
                errors.append(error.as_dict(cell.time))
        fault = controller.take_fault()  # the robot stopped by itself (a belt window violation)
        if fault is not None and self._give_to_tasks(fault) is not None:
            errors.append(fault.as_dict(cell.time))
        if self.program_end is None:
            runaway = self._watch(self.clock_reads == reads, alive)
            if runaway is not None:
                controller.stop()
                errors.append(runaway.as_dict(cell.time))
                self.program_end = cell.time
                self.finished = True
        self._record()

    def _live_tasks(self) -> list:
        return [t for t in self.scheduler.tasks if not t.finished and not getattr(t, "paused", False)]

    def _watch(self, no_clock_read: bool, alive_before: list):
        """Tell the watchdog what this cycle changed (before `_record` drains the signal
        changes); the error that ends the run, if it is a runaway.  Progress is what the
        programs do or look at: the robot or the hand moving, an output or soft signal
        changing, an input a program has read changing, a task starting or ending (parts
        the cell moves on its own are not: a belt may run for ever)."""
        cell, io, controller, live = self.cell, self.io, self.controller, self._live_tasks()
        hand, self._hand_watched = self._hand_watched, controller.hand_state
        progressed = (live != alive_before or hand != controller.hand_state
                      or any(n not in INPUTS or n in io.watched for n, _ in io.changes)
                      or float(abs(cell.robot_qvel()).max(initial=0.0)) > AT_REST_SPEED)
        if progressed:  # most cycles: nothing is blocked, so the tasks' waits need no look
            return self.watchdog.observe(cell.time, True, False, False, live)
        waits = [self.scheduler.waiting_on(task) for task in live]
        external_wait = any(is_external(wait) for wait in waits)
        blocked = (no_clock_read and not progressed and not io.changes and not controller.moving
                   and not external_wait and all(task_is_blocked(w, t.SLICE) for w, t in zip(waits, live))
                   and self._cell_at_rest())
        return self.watchdog.observe(cell.time, progressed, blocked, external_wait, live)

    def _cell_at_rest(self) -> bool:
        """Nothing in the cell moves or happens, and nothing will by itself: no new event, no
        body moving, no encoder counting, no part source."""
        cell = self.cell
        events, self._events_watched = self._events_watched, len(cell.events)
        encoders, self._encoders_watched = self._encoders_watched, tuple(
            e.counts() for e in cell.encoders.values())
        return (not self._cell_lives and events == len(cell.events) and encoders == self._encoders_watched
                and float(abs(cell.data.qvel).max(initial=0.0)) <= AT_REST_SPEED)

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
            self._record_belt_windows()

    def _record_belt_windows(self) -> None:
        """Each belt window a program set, drawn once, and again when it changes."""
        for belt in self.controller.belts.frames:
            window = belt.window
            conveyor = getattr(belt.encoder, "conveyor", None)
            if window is None or conveyor is None:
                continue
            T = belt.nominal.matrix()
            shown = (window.upstream, window.downstream, T.tobytes())
            if self._windows_shown.get(id(belt)) == shown:
                continue
            self._windows_shown[id(belt)] = shown
            T[:3, 3] /= 1000.0
            self.recorder.log_belt_window(belt.name or f"encoder {belt.encoder_number}", self.cell.time,
                                          self.cell.robot_base_pose() @ T, window.upstream / 1000.0,
                                          window.downstream / 1000.0, conveyor.width)

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
