"""The V+ system: programs in memory, global variables, parameters, switches
and the tasks that run programs.

`VPlusSystem.load(path)` parses and compiles a file; `start(name)` makes a
task whose generator the shared scheduler runs.  Errors raised inside a
program are turned into `ProgramError`s that name the V+ step, file line and
the controller's message, and stop the task as the controller would.
"""

from __future__ import annotations

import re
import sys
import traceback
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, TextIO

import numpy as np

from ...controller.location import Location
from ...controller.scheduler import NEXT_CYCLE, RELEASE
from ...errors import ProgramError
from . import messages as msg
from . import values
from .compiler import CompiledProgram, compile_program
from .fileio import Devices
from .formats import _fmt, render
from .keywords import FUNCTIONS, INSTRUCTIONS, STRING_FUNCTIONS
from .keywords.strings import typed_number
from .parser import normalize_name, parse, parse_file
# Parameters and switches with the manuals' defaults and limits.
from .settings import PARAMETER_DEFAULTS, SWITCH_DEFAULTS, in_range
from .tasking import PROGRAM_FAULTS, HaltProgram, StopProgram, TaskControl

MAJOR_CYCLE = 0.016  # s: the V+ scheduler's major cycle and trajectory period
# Program stacks ([000] "Program Stacks", [001] L441-465): 6 KB per task in V+, 32 KB in
# eV+; a call takes 20 bytes, each argument 32 plus its value (a real 4, a transformation
# 48, a precision point 4 per joint, a string 132; an array, passed by reference, nothing
# more), each AUTO variable its size (compiler.frame_bytes).  Past the stack:
# *Too many subroutine calls*.
STACK_BYTES = {"V+": 6 * 1024, "eV+": 32 * 1024}
CALL_BYTES, ARGUMENT_BYTES = 20, 32
# The deepest eV+ stack (32 KB of 20-byte calls) nests ~1640 calls, two Python generator
# frames each: Python's own limit must allow it.
sys.setrecursionlimit(max(sys.getrecursionlimit(), 8000))


def _value_bytes(value) -> int:
    """Stack bytes of an argument's value ([000] "Stack Space Required by a Subroutine")."""
    if isinstance(value, float):
        return 4
    if isinstance(value, str):
        return 132
    if isinstance(value, Location):
        return 48
    if isinstance(value, tuple):
        return 4 * len(value)
    return 0  # an array (by reference) or an omitted argument


def parse_real(text: str) -> float:
    """VAL(): the number at the start of a string, 0 if there is none."""
    text = text.strip()
    for end in range(len(text), 0, -1):
        try:
            return float(text[:end])
        except ValueError:
            continue
    return 0.0


def _pick(names: dict, key: str) -> str:
    """Parameter and switch names may be shortened to a unique prefix."""
    key = key.upper()
    if key in names:
        return key
    matches = [n for n in names if n.startswith(key)]
    if len(matches) != 1:
        raise values.fail(msg.ILLEGAL_VALUE, f"unknown or ambiguous name {key}")
    return matches[0]


@dataclass
class Console:
    """The system terminal: TYPE output and PROMPT input."""

    stdin: TextIO = field(default_factory=lambda: sys.stdin)
    echo: TextIO | None = field(default_factory=lambda: sys.stdout)
    text: list[str] = field(default_factory=list)

    def write(self, s: str) -> None:
        self.text.append(s)
        if self.echo is not None:
            self.echo.write(s)
            self.echo.flush()

    def read_line(self) -> str | None:
        line = self.stdin.readline()
        return None if line == "" else line.rstrip("\r\n")

    @property
    def output(self) -> str:
        return "".join(self.text)


class VPlusSystem:
    """Controller memory for V+: programs, variables, parameters, switches."""

    def __init__(self, robot, io, clock: Callable[[], float], console: Console | None = None, seed: int = 0,
                 sandbox: str | Path | None = None):
        self.robot = robot  # the shared virtual controller (motion, hand)
        self.io = io  # digital signals
        self.clock = clock  # simulated time, s
        self.console = console or Console()
        self.globals: dict = {}
        self.locals: dict[str, dict] = {}
        self.programs: dict[str, CompiledProgram] = {}
        self.parameters = dict(PARAMETER_DEFAULTS)
        self.switches = dict(SWITCH_DEFAULTS)
        self.random = np.random.default_rng(seed)
        self.tasks: list[Task] = []  # every task started, in order; `task(n)` finds the current one
        self.robot_holder: Task | None = None  # the task the robot is attached to
        # Where the guides differ, eV+ rules by default; "V+" selects the V+ v17
        # ones (task 0 attaches the robot when it starts, [000] L899-905).
        self.dialect = "eV+"
        self.sources: dict[str, list[str]] = {}  # file -> its lines, for error messages
        # Logical units; disk files live in `sandbox` (no disk when it is None).
        self.devices = Devices(sandbox, self.console, clock)
        self.accel_profile = 0  # ACCEL (profile): the robot's acceleration profile number
        self.timers: dict[int, float] = {}  # TIMER n = value: the clock reading that timer n counts from

    # ------------------------------------------------------------ loading
    def load(self, path: str | Path) -> list[str]:
        """LOAD a file: parse, compile; returns the program names in file order."""
        return self._load_module(parse_file(path))

    def load_files(self, paths: list[str | Path]) -> list[str]:
        """LOAD several files, as a cell keeps its modules (programs in one, .LOCATIONS and
        .REALS in another); returns the first file's program names.  A program two files
        define is a load-time error at its second definition."""
        first: list[str] | None = None
        for path in paths:
            module = parse_file(path)
            for program in module.programs:
                if program.name in self.programs:
                    raise ProgramError(
                        f"{msg.message(msg.SYNTAX_ERROR)} program {program.name} is already loaded from "
                        f"{self.programs[program.name].file}", msg.SYNTAX_ERROR, file=program.file,
                        line=program.line, column=1, text=module.lines[program.line - 1])
            names = self._load_module(module)
            first = names if first is None else first
        return first or []

    def load_text(self, text: str, file: str = "<string>") -> list[str]:
        return self._load_module(parse(text, file))

    def _load_module(self, module) -> list[str]:
        self.sources[module.file] = module.lines
        names = []
        for program in module.programs:
            if program.name in names:  # one file cannot hold a program twice
                raise ProgramError(f"{msg.message(msg.SYNTAX_ERROR)} program {program.name} defined twice",
                                   msg.SYNTAX_ERROR, file=program.file, line=program.line, column=1,
                                   text=self.source_line(program.file, program.line))
            try:
                compiled, code = _python_code(program)
            except ProgramError as err:
                err.located(file=program.file, program=program.name)
                raise err.located(text=self.source_line(program.file, err.line or 0)) from None
            namespace = dict(_NAMESPACE)
            exec(code, namespace)
            compiled.function = namespace["program"]
            self.programs[program.name] = compiled
            names.append(program.name)
        for section in module.data:
            from .data import load_data_section

            load_data_section(section, self.globals)
        return names

    def source_line(self, file: str, line: int) -> str | None:
        lines = self.sources.get(file, [])
        return lines[line - 1] if 0 < line <= len(lines) else None

    def define_location(self, name: str, location: Location) -> None:
        self.globals[normalize_name(name)] = location

    # ------------------------------------------------------------ tasks
    def start(self, program: str, number: int = 0, args: list | None = None, cycles: int = 1) -> "Task":
        """EXECUTE: run `program` in task `number` (`cycles` < 0: for ever)."""
        name = normalize_name(program)
        if name not in self.programs:
            raise ProgramError(f"{msg.message(msg.UNDEFINED_PROGRAM)} {program}", msg.UNDEFINED_PROGRAM)
        running = self.task(number)
        if running is not None and not running.finished:
            raise values.fail(msg.TASK_RUNNING, f"task {number}")
        task = Task(self, number, name, args or [], cycles)
        self.tasks.append(task)
        return task

    def task(self, number: int) -> "Task | None":
        """The task most recently started under `number`."""
        for task in reversed(self.tasks):
            if task.number == number:
                return task
        return None

    def status(self) -> list[dict]:
        """What the monitor's STATUS command shows, per task (the latest run
        of each task number): program, state, the step it is at, program
        priority and cycles left."""
        rows = []
        for number in sorted({t.number for t in self.tasks}):
            task = self.task(number)
            where = task.current_step()
            state = ("error" if task.error is not None else "idle") if task.finished else (
                "paused" if task.paused else "running")
            rows.append({"task": number, "program": task.program, "state": state,
                         "at": where, "priority": task.program_priority, "cycles": task.cycles})
        return rows

    def proceed(self, number: int = 0) -> None:
        """PROCEED: a paused task goes on after its PAUSE."""
        task = self.task(number)
        if task is None or task.finished or not task.paused:
            raise values.fail(msg.ILLEGAL_OPERATION, f"task {number} is not paused")
        task.paused = False


class _Slice:
    """Yielded when a task has used up its 1 ms time slice: it goes on in a later slice."""

    def __repr__(self) -> str:
        return "SLICE"


class Task(TaskControl):
    """One V+ task running a program.  `rt` in the generated code."""

    SLICE = _Slice()
    RELEASE = RELEASE
    NEXT_CYCLE = NEXT_CYCLE

    def __init__(self, system: VPlusSystem, number: int, program: str, args: list, cycles: int = 1):
        self.system = system
        self.number = number
        self.program = program
        self.globals = system.globals
        self.io = system.io
        self.random = system.random
        self.stack_used = 0  # bytes of the program stack the active calls take
        self.last_error: int | None = None
        self.error: ProgramError | None = None
        self.finished = False
        self.init_control(cycles)
        self.generator = self._drive(args)
        if number == 0 and system.dialect == "V+" and system.robot is not None and system.robot_holder is None:
            system.robot_holder = self

    @property
    def robot(self):
        """The robot; a task that does not hold it may read it but not move it."""
        robot = self.system.robot
        if robot is None:  # a system made without a cell (the interpreter alone)
            raise values.fail(msg.DEVICE_NOT_READY, "no robot")
        if self.system.robot_holder is self:
            return robot
        return _RobotOfAnotherTask(robot, self)

    def ended(self) -> None:
        """The task ended without an error: detach its units and close its files."""
        self.system.devices.release_task(self.number)

    def _frames(self, tb) -> list[tuple[CompiledProgram, int]]:
        found = []
        for frame, lineno in traceback.walk_tb(tb):
            filename = frame.f_code.co_filename
            if filename.startswith("<vplus:"):
                found.append((self.system.programs[filename[7:-1]], lineno))
        return found

    def _locate(self, err: ProgramError, tb) -> ProgramError:
        # The innermost step that has one: an error in a program's prologue
        # (its arguments) belongs to the CALL that passed them.
        for compiled, lineno in reversed(self._frames(tb)):
            statement = compiled.line_map.get(lineno)
            if statement is not None:
                err.located(
                    file=compiled.file, line=statement.line, column=statement.column,
                    step=statement.step, program=compiled.name,
                    text=self.system.source_line(compiled.file, statement.line),
                )
                break
        return err

    def _translate(self, err: Exception) -> ProgramError:
        """A Python error inside generated code is the program's error."""
        frames = self._frames(err.__traceback__)
        innermost = traceback.extract_tb(err.__traceback__)[-1].filename
        if not frames or not innermost.startswith(("<vplus:", str(Path(values.__file__).parent))):
            raise err  # not the program's fault: a bug in twin, let it show
        if isinstance(err, (KeyError, NameError)):
            name = err.args[0] if isinstance(err, KeyError) else getattr(err, "name", "")
            problem = ProgramError(f"{msg.message(msg.UNDEFINED_VALUE)} {name}", msg.UNDEFINED_VALUE)
        elif isinstance(err, ZeroDivisionError):
            problem = ProgramError(msg.message(msg.DIVIDE_BY_ZERO), msg.DIVIDE_BY_ZERO)
        elif isinstance(err, OverflowError):
            problem = ProgramError(msg.message(msg.OVERFLOW), msg.OVERFLOW)
        elif isinstance(err, ValueError):  # math domain errors, values a keyword cannot take
            problem = ProgramError(msg.message(msg.ILLEGAL_VALUE), msg.ILLEGAL_VALUE)
        else:
            problem = ProgramError(msg.message(msg.WRONG_TYPE), msg.WRONG_TYPE)
        return self._locate(problem, err.__traceback__)

    def call(self, name: str, args: list):
        compiled = self.system.programs.get(name)
        if compiled is None:
            raise ProgramError(f"{msg.message(msg.UNDEFINED_PROGRAM)} {name}", msg.UNDEFINED_PROGRAM)
        frame = compiled.frame_bytes + sum(ARGUMENT_BYTES + _value_bytes(a) for a in args)
        stack = STACK_BYTES[self.system.dialect]
        if self.stack_used + frame > stack:
            err = ProgramError(f"{msg.message(msg.TOO_MANY_CALLS)} (a {stack // 1024} KB stack)", msg.TOO_MANY_CALLS)
            if not self.stack_used:  # the task's own program: no CALL step to blame, its .PROGRAM line
                err.located(file=compiled.file, line=compiled.line, column=1, step=1, program=name,
                            text=self.system.source_line(compiled.file, compiled.line))
            raise err
        self.stack_used += frame
        try:
            return (yield from compiled.function(self, args))
        finally:
            self.stack_used -= frame

    def program_locals(self, name: str) -> dict:
        return self.system.locals.setdefault(name, {})

    @staticmethod
    def results(frame_locals: dict, names: tuple) -> list:
        return [frame_locals.get(n) for n in names]

    def too_many_arguments(self, name: str, count: int) -> None:
        raise values.fail(msg.INVALID_ARGUMENT, f"{count} arguments for {name}")

    def zero_step(self) -> None:
        raise values.fail(msg.ILLEGAL_VALUE, "FOR loop STEP 0")

    def loop_not_started(self) -> None:
        raise values.fail(msg.CONTROL_STRUCTURE, "a FOR loop entered by GOTO, not through its FOR step")

    def stop(self) -> None:
        raise StopProgram()

    def halt(self) -> None:
        raise HaltProgram()

    # ------------------------------------------------------------ time
    def sleep(self, seconds: float):
        """Wait `seconds` of simulated time."""
        end = self.system.clock() + seconds
        clock = self.system.clock
        yield lambda: clock() >= end - 1e-9

    def timer(self, number: int) -> float:
        return self.system.clock()

    def hand_time(self) -> float:
        # HAND.TIME is rounded to a multiple of the 16 ms major cycle (V+ guide v17).
        cycles = round(self.system.parameters["HAND.TIME"] / MAJOR_CYCLE)
        return cycles * MAJOR_CYCLE

    # ------------------------------------------------------------ terminal
    def type_out(self, items: tuple) -> None:
        text, newline = render(items)
        if self.system.switches["MESSAGES"]:
            self.system.console.write(text + ("\n" if newline else ""))

    def prompt(self, text) -> str:
        self.system.console.write(values._str(text))
        line = self.system.console.read_line()
        if line is None:
            raise values.fail(msg.UNEXPECTED_EOF)
        return line

    def prompt_numbers(self, text: str, count: int) -> list[float | None]:
        """The numbers typed for `count` real variables: one entry is one
        number ("11+1" is *Unexpected text at end of line*); several are
        separated by commas or spaces.  More numbers than variables is
        unexpected text; a variable with no number typed is left as it was."""
        if count == 1:
            return [typed_number(text)]
        fields = [f for f in re.split(r"[\s,]+", text.strip()) if f]
        if len(fields) > count:
            raise values.fail(msg.UNEXPECTED_TEXT, repr(text))
        numbers: list[float | None] = [typed_number(f) for f in fields]
        return numbers + [None] * (count - len(fields))

    # ------------------------------------------------------------ settings
    def set_parameter(self, name: str, index, value) -> None:
        key = _pick(self.system.parameters, name)
        if not in_range(key, values._real(value)):
            raise values.fail(msg.ILLEGAL_VALUE, f"{key} = {value}")
        self.system.parameters[key] = values._real(value)

    def switch(self, name: str) -> bool:
        return self.system.switches[_pick(self.system.switches, name)]

    def set_switch(self, name: str, on: bool) -> None:
        self.system.switches[_pick(self.system.switches, name)] = on

    def monitor_command(self, command: str, text: str) -> None:
        """An "MC" line of a command program that no program instruction does.  LOAD of
        a file this run has loaded (twin run loads every file it is given) does nothing;
        anything else is an error at its step: twin run has no monitor."""
        if command == "LOAD":
            wanted = re.split(r"[\\/:]", text[4:].split("/")[0].strip().strip('"'))[-1]
            stem = wanted.rsplit(".", 1)[0].lower()
            if stem and any(Path(f).stem.lower() == stem for f in self.system.sources):
                return
            raise values.fail(msg.NONEXISTENT_FILE, f"MC {text}: twin run loads the files it is given "
                                                    "(name this one on its command line)")
        raise values.fail(msg.DEVICE_NOT_READY, f"MC {text}: there is no monitor (twin run loads the files "
                                                "and starts the program)")

    def set_speed(self, value, rotation, modifiers: tuple) -> None:
        self.robot.set_speed(values._real(value), always="ALWAYS" in modifiers,
                             monitor="MONITOR" in modifiers,
                             units="MMPS" if "MMPS" in modifiers else "IPS" if "IPS" in modifiers else None)


def _python_code(program) -> tuple[CompiledProgram, object]:
    """The program compiled to Python source and to Python code.  Loops nested
    deeper than Python's 20 blocks are compiled again to the flat jump-table
    form, which has no nested blocks."""
    compiled = compile_program(program)
    try:
        return compiled, _python_compile(compiled)
    except SyntaxError as err:  # IndentationError included: "too many levels of indentation"
        if "too many statically nested blocks" not in str(err) and "too many levels of indentation" not in str(err):
            raise
    compiled = compile_program(program, flat=True)
    return compiled, _python_compile(compiled)


def _python_compile(compiled: CompiledProgram):
    """Python's compile(); an expression nested too deeply for it is the
    user's *Syntax error* at that step."""
    try:
        return compile(compiled.source, f"<vplus:{compiled.name}>", "exec")
    except (SyntaxError, RecursionError) as err:
        if isinstance(err, SyntaxError) and "nested parentheses" not in str(err):
            raise
        statement = compiled.line_map.get(getattr(err, "lineno", None) or 0)
        where = {} if statement is None else {"line": statement.line, "column": statement.column,
                                              "step": statement.step}
        raise ProgramError(f"{msg.message(msg.SYNTAX_ERROR)} expression too complicated", msg.SYNTAX_ERROR,
                           **where) from None


class _RobotOfAnotherTask:
    """The robot as seen by a task it is not attached to: reading it (HERE,
    DEST, SPEED()) is fine; the first motion attaches it to task 0, and in
    any other task is "*Robot not attached to this program*" ([000] L899-930)."""

    # What moves the robot or changes its TOOL, BASE or motion settings (the
    # motion branch's controller adds drive, set_tool...); BRAKE (stop) is
    # allowed from any task ([000] L4592-4595).
    _MOTION = {"move", "drive", "dwell", "wait_stopped", "hand", "hand_at_next_motion", "request_configuration",
               "set_speed", "set_accel", "set_duration", "set_modifier", "set_tool", "set_base"}

    def __init__(self, robot, task: Task):
        self._robot = robot
        self._task = task

    def __getattr__(self, name: str):
        if name in self._MOTION:
            return getattr(self._task.robot_for_motion(), name)
        return getattr(self._robot, name)


# The names the generated code sees.
_NAMESPACE = {
    "F": {**FUNCTIONS, **STRING_FUNCTIONS},
    "I": {name: spec.function for name, spec in INSTRUCTIONS.items()},
    "_fmt": _fmt,
    # What a step may raise that the error trap (REACTE) catches.
    "_TRAPPED": (ProgramError, *PROGRAM_FAULTS),
    **{name: getattr(values, name) for name in dir(values) if name.startswith("_") and not name.startswith("__")},
}
