"""V+ multitasking and program interrupts, the part of a task that is not
about running one program: execution cycles, EXECUTE/ABORT/KILL/PAUSE,
reactions (REACT, REACTI, IGNORE, LOCK, PRIORITY), the error trap (REACTE,
RETURNE), event flags and robot attachment.

V+ guide v17 "Asynchronous Processing", "Error Trapping" (L1267-1345),
"Scheduling of Program Execution Tasks" (L1349-2075) and "Program Interrupt
Instructions" (L4455-4690); eV+ guide L406-432, L1320-1415.

A task's generator is `TaskControl._drive`: it runs the program's generator
and, between two of its steps (whenever the program yields to the
scheduler, or passes a LOCK), calls a due reaction "just as if a CALL
instruction had been executed" by pushing the reaction's generator on top.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterator

from ...controller.scheduler import RELEASE, SLICES
from ...errors import ProgramError
from . import messages as msg
from . import values
from .parser import normalize_name

TASKS = 28  # tasks 0..27 (0..6 without the V+ Extensions), [000] L1364
ERROR_TRAP_PRIORITY = 254  # program priority inside a REACTE routine, [000] L1340
MAX_PROGRAM_PRIORITY = 127  # LOCK and reaction priorities 0..127, [000] L1284
MAX_TASK_PRIORITY = 64  # task priorities in a slice: 1-31 user, up to 64 the servo ([000] L1376-1392)
REACT_SIGNALS = (range(1001, 1013), range(2001, 2009))
TASK_IDLE, TASK_PAUSED, TASK_STOPPED_BY_ERROR, TASK_EXECUTING = 0.0, 2.0, 3.0, 4.0  # TASK(1, n)  # inputs and soft signals, [000] L4507

# Default task priority in each of the 16 time slices ([000] L1960-2075, the
# "Default Task Priorities" table; tasks 7..27 share the last row).
_SLICE_PRIORITIES = {
    0: (20,) * 9 + (10,) * 4 + (0,) * 3,
    1: (19, 19, 21, 21, 19, 19, 21, 21, 19, 9, 11, 11, 9, 0, 0, 0),
    2: (0,) * 13 + (20, 0, 0),
    3: (0,) * 13 + (15, 0, 0),
    4: (15,) * 9 + (5,) * 4 + (0,) * 3,
    5: (0,) * 14 + (20, 0),
    6: (0,) * 14 + (15, 0),
}
_OTHER_TASKS = (0,) * 13 + (5, 0, 0)


def slice_priorities(number: int) -> tuple[int, ...]:
    return _SLICE_PRIORITIES.get(number, _OTHER_TASKS)


# Python errors a step of generated code may raise that are the program's fault (an
# undefined variable, a division by zero, a value of the wrong kind): runtime._translate
# turns them into the V+ error, located at the step; raised elsewhere they are twin's bugs.
PROGRAM_FAULTS = (KeyError, NameError, ZeroDivisionError, TypeError, IndexError, ValueError, OverflowError)


class StopProgram(Exception):
    """STOP (or RETURN from the top-level program): the current cycle ends."""


class HaltProgram(Exception):
    """HALT, ABORT or KILL: the task ends, whatever cycles remain."""


class _Check:
    """Yielded by LOCK: the driver looks for due reactions and goes on at once."""

    def __repr__(self) -> str:
        return "CHECK"


CHECK = _Check()


@dataclass
class Reaction:
    signal: int | None  # positive: react to off -> on; negative: on -> off; None: a belt window
    program: str | None  # None: REACTI signal alone stops the robot and calls nothing
    args: list
    priority: int
    immediate: bool  # REACTI: stop the robot at once
    level: bool  # the signal as last sampled
    triggered: bool = False


class TaskControl:
    """Mixed into runtime.Task: everything a V+ task does besides its program."""

    # ------------------------------------------------------------ state
    def init_control(self, cycles: int) -> None:
        self.cycles = cycles  # execution cycles left; negative: forever
        self.priorities = slice_priorities(self.number)
        self.program_priority = 0
        self.reactions: dict[int, Reaction] = {}
        self.error_trap: str | None = None
        self.trapping = False
        self.paused = False
        self.abort_requested = False
        self.event = False
        self.scheduler = None  # set by Scheduler.add
        self.run_signal: int | None = None  # RUNSIG
        self.levels: list[list] = []  # the program and the reactions on top of it (_interruptible)

    def _drive(self, args: list) -> Iterator:
        """The task's generator: its cycles, its reactions, its end."""
        try:
            while True:
                try:
                    yield from self._interruptible(self.call(self.program, args))
                except StopProgram:
                    pass
                self.cycles -= 1
                if self.cycles == 0:
                    break
            self.ended()
        except HaltProgram:
            self.ended()
        except ProgramError as err:
            self.error = self._locate(err, err.__traceback__)
            self.last_error = err.code
        except PROGRAM_FAULTS as err:
            self.error = self._translate(err)
            self.last_error = self.error.code
        finally:
            self.finished = True
            self.detach_robot()
            if self.run_signal is not None:
                self.io.signal(-self.run_signal)

    def _interruptible(self, main: Iterator) -> Iterator:
        """Run `main`, calling reactions between its steps.  An error thrown
        into the task (a collision the cell saw) goes to the step the program
        is at, where it is located or trapped like any other."""
        stack: list[list] = [[main, None]]  # [generator, the wait it is blocked on]
        self.levels = stack
        thrown: Exception | None = None
        while stack:
            if self.abort_requested:
                raise HaltProgram()
            top = stack[-1]
            if thrown is None:
                reaction = self._due_reaction()
                if reaction is not None:
                    stack.append([self._react(reaction), None])
                    continue
                if callable(top[1]) and not top[1]():
                    try:
                        yield top[1]  # a reaction ran while this level waited: wait on
                    except Exception as err:
                        thrown = err
                    continue
            top[1] = None
            try:
                if thrown is not None:
                    err, thrown = thrown, None
                    wait = top[0].throw(err)
                else:
                    wait = next(top[0])
            except StopIteration:
                stack.pop()
                continue
            if wait is CHECK:
                continue
            top[1] = wait
            try:
                yield wait
            except Exception as err:
                thrown = err

    # ------------------------------------------------------------ reactions
    def begin_cycle(self) -> None:
        """Sample the reaction signals: a transition is seen at the next major
        cycle ([000] L4627-4628); it also sets the task's event flag."""
        for reaction in self.reactions.values():
            if reaction.signal is None:  # a belt window reaction: the controller triggers it
                continue
            level = self.io.sig(abs(reaction.signal))
            if level != reaction.level and level == (reaction.signal > 0):
                reaction.triggered = True
                self.event = True
                if reaction.immediate and self.system.robot is not None:
                    self.system.robot.stop()  # REACTI: BRAKE at once
            reaction.level = level
        # REACTI signal without a program: stopping the robot was all it does, once.
        for number in [n for n, r in self.reactions.items() if r.triggered and r.program is None]:
            del self.reactions[number]

    def _due_reaction(self) -> Reaction | None:
        """The highest-priority triggered reaction above the program priority."""
        best = None
        for reaction in self.reactions.values():
            if reaction.triggered and reaction.priority > self.program_priority:
                if best is None or reaction.priority > best.priority:
                    best = reaction
        return best

    def interrupt_due(self) -> bool:
        return not self.paused and (self.abort_requested or self._due_reaction() is not None)

    def _react(self, reaction: Reaction) -> Iterator:
        """Fire `reaction`: it runs at its own program priority.  A reaction
        fires once; the routine re-enables itself if it wants more ([000] L4640)."""
        self.reactions = {key: r for key, r in self.reactions.items() if r is not reaction}
        saved, self.program_priority = self.program_priority, reaction.priority
        return self._restoring(self.call(reaction.program, list(reaction.args)), saved)

    def window_reaction(self, program: str, priority: int):
        """WINDOW %belt = ..., program, priority: a window violation calls `program` like a
        reaction, at `priority`, whatever the task is doing (the robot has stopped)."""
        def violated(state: str) -> None:
            self.reactions[("WINDOW", program)] = Reaction(None, normalize_name(program), [], priority,
                                                           False, False, triggered=True)
            self.event = True

        return violated

    def _restoring(self, routine: Iterator, priority: int) -> Iterator:
        try:
            yield from routine
        finally:
            self.program_priority = priority

    def react(self, signal, program: str | None, args: list, priority=None, immediate: bool = False) -> None:
        """REACT / REACTI signal, program(args), priority."""
        number = values.to_int(signal)
        level = 1 if priority is None else values.to_int(priority)
        if not 1 <= level <= MAX_PROGRAM_PRIORITY:
            raise values.fail(msg.ILLEGAL_VALUE, f"reaction priority {level}")
        if abs(number) not in REACT_SIGNALS[0] and abs(number) not in REACT_SIGNALS[1]:
            raise values.fail(msg.ILLEGAL_SIGNAL, f"REACT {number}")
        self.reactions[abs(number)] = Reaction(number, program, args, level, immediate,
                                               self.io.sig(abs(number)))

    def ignore(self, signal) -> None:
        self.reactions.pop(abs(values.to_int(signal)), None)

    def lock(self, priority):
        """LOCK: set the program priority; a reaction it no longer holds off runs now."""
        level = values.to_int(priority)
        if not 0 <= level <= ERROR_TRAP_PRIORITY:
            raise values.fail(msg.ILLEGAL_VALUE, f"LOCK {level}")
        self.program_priority = level
        yield CHECK

    def priority(self) -> float:
        return float(self.program_priority)

    # ------------------------------------------------------------ error trap
    def react_error(self, program: str | None) -> None:
        """REACTE program: errors call it instead of stopping the task."""
        self.error_trap = program

    def trap(self, err: Exception):
        """A step failed.  With REACTE, call the trap routine and go on with the
        next step when it returns (RETURNE); otherwise stop the task."""
        if self.error_trap is None or self.trapping or isinstance(err, (StopProgram, HaltProgram)):
            raise err
        if not isinstance(err, ProgramError):
            err = self._translate(err)  # re-raises a Python error that is not the program's
        self.last_error = err.code
        saved, self.program_priority = self.program_priority, ERROR_TRAP_PRIORITY
        self.trapping = True
        try:
            yield from self.call(self.error_trap, [])
        finally:
            self.trapping = False
            self.program_priority = saved
        if self._due_reaction() is not None:
            yield CHECK  # a reaction held off by the trap's priority runs now, before the next step

    # ------------------------------------------------------------ other tasks
    def execute(self, number, program: str, args: list, cycles=None, step=None, priority=None) -> None:
        """EXECUTE task program(args), cycles, step, priority: start a program
        in another task ([000] L1366-1374: EXECUTE may override the task's
        priorities; here one priority for all 16 slices)."""
        task_number = 0 if number is None else values.to_int(number)
        if not 0 <= task_number < TASKS:
            raise values.fail(msg.ILLEGAL_VALUE, f"task {task_number}")
        if step is not None and values.to_int(step) != 1:
            raise values.fail(msg.ILLEGAL_VALUE, "EXECUTE from a step other than the first")
        count = 1 if cycles is None else values.to_int(cycles)
        task = self.system.start(program, task_number, args, cycles=-1 if count < 0 else max(count, 1))
        if priority is not None:  # a task priority for every slice, in place of the defaults
            level = values.to_int(priority)
            if not 1 <= level <= MAX_TASK_PRIORITY:
                raise values.fail(msg.ILLEGAL_VALUE, f"task priority {level}")
            task.priorities = (level,) * SLICES
        if self.scheduler is not None:
            self.scheduler.add(task)

    def other(self, number) -> "TaskControl | None":
        task_number = values.to_int(number)
        if not 0 <= task_number < TASKS:
            raise values.fail(msg.ILLEGAL_VALUE, f"task {task_number}")
        return self.system.task(task_number)

    def abort(self, number=None) -> None:
        """ABORT [task]: stop it at the end of the step it is in (a motion it
        waits for completes first)."""
        task = self if number is None else self.other(number)
        if task is not None and not task.finished:
            task.abort_requested = True
            task.paused = False

    def kill(self, number) -> None:
        """KILL task: clear the task's stack at once (it must not be running)."""
        task = self.other(number)
        if task is None:
            return
        if task is self or (not task.finished and not task.paused):
            raise values.fail(msg.TASK_RUNNING, f"task {task.number}")
        task.generator.close()
        task.ended()  # its units are detached and its files closed ([000] L7480-7481)

    def cycle_end(self, number=None) -> None:
        """CYCLE.END [task]: the task stops at the end of its current cycle."""
        task = self if number is None else self.other(number)
        if task is not None:
            task.cycles = 1

    def pause(self):
        """PAUSE: the task stops where it is; `VPlusSystem.proceed` resumes it."""
        self.paused = True
        yield lambda: not self.paused

    def runsig(self, signal) -> None:
        """RUNSIG signal: the signal is on while this task runs and goes off
        when the task ends, normally or by an error (negative: the reverse)."""
        number = values.to_int(signal)
        self.io.signal(number)
        self.run_signal = number

    # ------------------------------------------------------------ events
    def set_event(self, number=None) -> None:
        task = self if number is None else self.other(number)
        if task is not None:
            task.event = True

    def clear_event(self, number=None) -> None:
        task = self if number is None else self.other(number)
        if task is not None:
            task.event = False

    def wait_event(self, mask=None, timeout=None):
        """WAIT.EVENT [mask], [timeout]: wait for the event flag (SET.EVENT, a
        reaction) or, with no mask, for `timeout` seconds."""
        clock = self.system.clock
        end = None if timeout is None else clock() + values._real(timeout)
        watch = mask is not None or timeout is None
        yield lambda: (watch and self.event) or (end is not None and clock() >= end - 1e-9)

    def get_event(self, number=None) -> float:
        task = self if number is None else self.other(number)
        return 1.0 if task is not None and task.event else 0.0

    def release(self, number=None):
        yield RELEASE

    # ------------------------------------------------------------ robot
    def attach_robot(self) -> None:
        """ATTACH (0) / first motion of task 0: the robot is this task's; only
        one task may hold it ([000] L899-930)."""
        holder = self.system.robot_holder
        if holder is not None and holder is not self and not holder.finished:
            raise values.fail(msg.ROBOT_ATTACHED, f"by task {holder.number}")
        self.system.robot_holder = self

    def detach_robot(self) -> None:
        """DETACH (0), or the end of the task: the robot is free for another task."""
        if self.system.robot_holder is self:
            self.system.robot_holder = None

    def robot_for_motion(self):
        """The robot, for an instruction that moves it: task 0 attaches it on
        its first motion (the eV+ rule, [001] L416); other tasks must ATTACH it."""
        if self.system.robot_holder is not self:
            if self.number != 0:
                raise values.fail(msg.ROBOT_NOT_ATTACHED, f"task {self.number}")
            self.attach_robot()
        return self.system.robot

    def current_step(self) -> tuple[str, int] | None:
        """(program, step) of the innermost V+ step this task is at, if running."""
        where = self.current_statement()
        return None if where is None else (where[0].name, where[1].step)

    def current_statement(self):
        """(compiled program, statement) of the innermost V+ step this task is at, if running
        (the statement has the source line: the notebook API and the recording's line trace)."""
        if self.finished or not self.levels:
            return None
        where = None
        generator = self.levels[-1][0]
        while generator is not None:
            frame = getattr(generator, "gi_frame", None)
            if frame is not None and frame.f_code.co_filename.startswith("<vplus:"):
                compiled = self.system.programs[frame.f_code.co_filename[7:-1]]
                statement = compiled.line_map.get(frame.f_lineno)
                if statement is not None:
                    where = (compiled, statement)
            generator = getattr(generator, "gi_yieldfrom", None)
        return where

    @property
    def label(self) -> str:
        return f"task {self.number}"

    def current_location(self) -> dict | None:
        """Where the task is, for the watchdog's message: program, step, file, line, source."""
        where = self.current_statement()
        if where is None:
            return None
        compiled, statement = where
        return {"program": compiled.name, "step": statement.step, "file": compiled.file,
                "line": statement.line, "text": self.system.source_line(compiled.file, statement.line)}

    # ------------------------------------------------------------ TASK()
    def task_info(self, select=None, number=None) -> float:
        """TASK(select, task): 0 or omitted: this task's number; 1: the state of `task`
        (0 idle or never run, 2 paused by PAUSE, 3 stopped by an error, 4 executing:
        running or waiting, the value field drivers test with TASK(1, n) == 4); 2: its
        program priority; 3: its execution cycles left (docs/vplus.md, "TASK(select, task)")."""
        which = 0 if select is None else values.to_int(select)
        if which == 0:
            return float(self.number)
        task = self if number is None else self.other(number)
        if which == 1:
            if task is None:
                return 0.0
            if task.finished:
                return TASK_STOPPED_BY_ERROR if task.error is not None else TASK_IDLE
            return TASK_PAUSED if task.paused else TASK_EXECUTING
        if task is None:
            raise values.fail(msg.ILLEGAL_VALUE, "no such task")
        if which == 2:
            return float(task.program_priority)
        if which == 3:
            return float(task.cycles)
        raise values.fail(msg.ILLEGAL_VALUE, f"TASK({which})")
