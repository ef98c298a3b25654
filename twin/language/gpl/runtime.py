"""A loaded GPL project and its threads.

`GplSystem.load_project(folder)` reads Project.gpr, parses and compiles every
file into one Python namespace; `start()` makes the main thread, which first
runs every module's variable initialisers and `Init` sub (User Manual ch. 10,
"Special Initialization"), then the start procedure.  A thread (`GplThread`)
is a scheduler task; it is also the `rt` that generated code and the
built-in classes receive (twin/language/gpl/library/__init__.py).
An error that no Catch handles stops its thread and is reported with the
file, line, column, GPL code and message.
"""

from __future__ import annotations

import random
import traceback
import types
from pathlib import Path
from typing import Any, Callable, Iterator

from ...errors import ProgramError
from ..vplus.runtime import Console
from . import builtins, values
from .compiler import CompiledProject, ProjectCompiler
from .expressions import library_arity, library_byref
from .errors import (
    ARITHMETIC_OVERFLOW, DIVIDE_BY_ZERO, INVALID_ARGUMENT, INVALID_NUMBER, INVALID_STATEMENT, ME_UNDEFINED, NO_START_PROCEDURE,
    NULL_OBJECT, OUT_OF_MEMORY, OVERFLOW, TOO_DEEP, STACK_OVERFLOW, TYPE_MISMATCH, UNDEFINED_SYMBOL, UNKNOWN_START_PROCEDURE, UNKNOWN_SYMBOL_AT_RUN_TIME, WRONG_ARGUMENT_COUNT,
    GplError, fail, message,
)
from . import library as library_package
from .library import CLASSES, Ref, member as library_member
from .library.codes import mapped_from_controller
from .parser import parse, parse_file
from .project import read_project

class GplObject:
    """Base of the Python classes made for user-defined GPL classes."""

    gpl_name = "Object"
    gpl_members: dict = {}


# ------------------------------------------------------------------ control flow
class _Control(BaseException):
    """Jumps that generated code raises; never seen by a GPL Catch."""


class _Jump(_Control):
    def __init__(self, block: int, segment: int):
        self.block = block
        self.segment = segment


class _Break(_Control):
    def __init__(self, loop: int):
        self.loop = loop


class _ExitTry(_Control):
    pass


class _Abort(_Control):
    """Thread.Abort of the running thread itself."""


class _Slice:
    def __repr__(self) -> str:
        return "SLICE"


SLICE = _Slice()


# ------------------------------------------------------------------ delegates
class Delegate:
    """A Delegate object: a procedure and, for a class method, its object."""

    def __init__(self, fn: Callable, me: Any, name: str, params: int):
        self.fn = fn
        self.me = me
        self.name = name
        self.params = params  # how many arguments the procedure takes

    def run(self, rt, args: tuple):
        return (yield from (self.fn(rt, self.me, *args) if self.me is not None else self.fn(rt, *args)))


# ------------------------------------------------------------------ ByRef references
class _GlobalRef:
    """A ByRef argument that is a module variable, Static or Shared field."""

    __slots__ = ("table", "name")

    def __init__(self, table: dict, name: str):
        self.table, self.name = table, name

    @property
    def value(self):
        return self.table[self.name]

    @value.setter
    def value(self, v) -> None:
        self.table[self.name] = v


class _AttrRef:
    """A ByRef argument that is a field of an object."""

    __slots__ = ("obj", "name")

    def __init__(self, obj, name: str):
        self.obj, self.name = obj, name

    @property
    def value(self):
        return getattr(self.obj, self.name)

    @value.setter
    def value(self, v) -> None:
        setattr(self.obj, self.name, v)


class _ItemRef:
    """A ByRef argument that is an array element."""

    __slots__ = ("array", "index")

    def __init__(self, array, index: tuple):
        self.array, self.index = array, index if len(index) > 1 else index[0]

    @property
    def value(self):
        return self.array[self.index]

    @value.setter
    def value(self, v) -> None:
        self.array[self.index] = v


class _Cell(Ref):
    """A variable given to a member that only the run time finds (expressions.py,
    untyped_call_with_refs): `passed` says whether the member took it ByRef."""

    __slots__ = ("passed",)

    def __init__(self, value):
        super().__init__(value)
        self.passed = False


def _by_position(args: tuple, byref: frozenset) -> tuple:
    """The arguments as the member takes them: a Ref at its ByRef positions, values elsewhere."""
    out = []
    for i, a in enumerate(args):
        if a.__class__ is _Cell:
            a.passed = i in byref
            out.append(a if a.passed else a.value)
        else:
            out.append(Ref(a) if i in byref else a)
    return tuple(out)


def _invoke(rt, delegate, args: tuple):
    if delegate is None:
        raise fail(NULL_OBJECT, "calling a Delegate that is Nothing")
    return (yield from delegate.run(rt, args))


def _w(result):
    """Run a member's result with `yield from` when it is a generator (a wait)."""
    if result.__class__ is types.GeneratorType:
        return (yield from result)
    return result
    yield  # noqa: unreachable; makes this a generator function


# ------------------------------------------------------------------ dynamic members
def _member_of(obj, key: str):
    if obj is None:
        raise fail(NULL_OBJECT, f"member {key} of Nothing")
    table = getattr(type(obj), "gpl_members", None)
    if table is None:
        raise fail(UNDEFINED_SYMBOL, f"member {key}")
    entry = table.get(key)
    if entry is None:
        raise fail(UNDEFINED_SYMBOL, f"{getattr(type(obj), 'gpl_name', type(obj).__name__)}.{key}")
    return entry


def _callm(rt, obj, key: str, args: tuple | None):
    """obj.key or obj.key(args) when the compiler did not know obj's class."""
    if obj is None:
        raise fail(NULL_OBJECT, f"member {key} of Nothing")
    if args:
        byref = _byref_positions(obj, key)
        args = _by_position(args, byref) if byref or any(a.__class__ is _Cell for a in args) else args
    if obj.__class__ is str:
        fn = builtins.STRING_MEMBERS.get(key)
        if fn is None:
            raise fail(UNDEFINED_SYMBOL, f"String member {key}")
        return fn[0](obj, *(args or ()))
    if obj.__class__ is values.GplArray:
        if key == "getupperbound":
            return obj.GetUpperBound(*(args or ()))
        if key in ("length", "rank"):
            return obj.Length if key == "length" else obj.Rank
        raise fail(UNDEFINED_SYMBOL, f"array member {key}")
    entry = _member_of(obj, key)
    if isinstance(entry, tuple):  # a user class: see GplSystem._class_members
        kind = entry[0]
        if kind == "field":
            value = getattr(obj, entry[1])
            return value[args if len(args) > 1 else args[0]] if args else value
        if kind == "shared":
            value = rt.system.namespace[entry[1]]
            return value[args if len(args) > 1 else args[0]] if args else value
        if kind == "method":
            if len(args or ()) != entry[4]:
                raise fail(WRONG_ARGUMENT_COUNT, f"{type(obj).gpl_name}.{key} takes {entry[4]} argument(s), "
                           f"{len(args or ())} given")
            return entry[1](rt, obj, *args) if entry[2] else entry[1](rt, *args)
        if kind == "property":
            return entry[1](rt, obj, *(args or ())) if entry[3] else entry[1](rt, *(args or ()))
        raise fail(UNDEFINED_SYMBOL, key)
    attr = entry
    raw = getattr(type(obj), attr)
    if isinstance(raw, property):
        value = getattr(obj, attr)
        return value[args if len(args) > 1 else args[0]] if args else value
    low, high = library_arity(type(obj), attr)
    if not low <= len(args or ()) <= high:
        raise fail(WRONG_ARGUMENT_COUNT, f"{type(obj).gpl_name}.{attr} takes {low}"
                   + (f" to {high}" if high != low and high < 99 else "") + f" argument(s), {len(args or ())} given")
    if getattr(raw, "gpl_shared", False):
        return getattr(obj, attr)(rt, *(args or ()))
    return getattr(obj, attr)(*(args or ()))


def _byref_positions(obj, key: str) -> frozenset:
    entry = getattr(type(obj), "gpl_members", {}).get(key)
    if isinstance(entry, tuple):  # a user class
        return entry[3] if entry[0] == "method" else frozenset()
    return library_byref(type(obj), entry) if entry is not None else frozenset()


def _setm(rt, obj, key: str, args: tuple | None, value):
    """obj.key = value (or obj.key(args) = value) when obj's class was not known."""
    entry = _member_of(obj, key)
    if isinstance(entry, tuple):
        kind = entry[0]
        if kind == "field":
            if args:
                getattr(obj, entry[1])[args if len(args) > 1 else args[0]] = value
            else:
                setattr(obj, entry[1], entry[2](value))
            return None
        if kind == "shared":
            rt.system.namespace[entry[1]] = entry[2](value)
            return None
        if kind == "property" and entry[2] is not None:
            return entry[2](rt, obj, *(args or ()), value) if entry[3] else entry[2](rt, *(args or ()), value)
        raise fail(INVALID_STATEMENT, f"cannot assign to {key}")
    if args:
        setter = library_member(type(obj), "set_" + entry)
        if setter is None:
            raise fail(INVALID_STATEMENT, f"{key} is read-only")
        return getattr(obj, setter)(*args, value)
    _setattr(obj, entry, value)
    return None


def _setattr(obj, attr: str, value) -> None:
    if obj is None:
        raise fail(NULL_OBJECT, f"setting {attr} of Nothing")
    try:
        setattr(obj, attr, value)
    except AttributeError:
        raise fail(INVALID_STATEMENT, f"{getattr(type(obj), 'gpl_name', '')}.{attr} is read-only") from None


def _call(rt, obj, args: tuple):
    """obj(args): an array element or a delegate call, found at run time."""
    if obj.__class__ is values.GplArray:
        return obj[tuple(values._ix(a) for a in args) if len(args) > 1 else values._ix(args[0])]
    if isinstance(obj, Delegate):
        return obj.run(rt, args)
    if obj is None:
        raise fail(NULL_OBJECT, "indexing or calling Nothing")
    raise fail(TYPE_MISMATCH, "not an array or a Delegate")


def _setindex(obj, args: tuple, value) -> None:
    if obj.__class__ is not values.GplArray:
        raise fail(TYPE_MISMATCH, "not an array")
    obj[tuple(values._ix(a) for a in args) if len(args) > 1 else values._ix(args[0])] = value


def _redim(array, dims: tuple, default, preserve: bool):
    if array is None:
        return values.GplArray(dims, default)
    array.redim(dims, preserve)
    return array


def _object(obj):
    if obj is None:
        raise fail(NULL_OBJECT, "calling a method of Nothing")
    return obj


def _case_value(v):
    return v if v.__class__ is str else values._num(v)


# ------------------------------------------------------------------ exceptions
def as_gpl_error(err: BaseException) -> GplError | None:
    """The GPL error a Python exception stands for, or None for a twin bug."""
    if isinstance(err, GplError):
        return err
    if isinstance(err, ProgramError):  # raised by the shared controller / I/O (V+ codes)
        mapped = mapped_from_controller(err)
        if mapped is not None:
            return mapped
        return GplError(err.code if err.code is not None else INVALID_ARGUMENT, err.message)
    if isinstance(err, ZeroDivisionError):
        return fail(DIVIDE_BY_ZERO)
    if isinstance(err, OverflowError):
        return fail(ARITHMETIC_OVERFLOW)
    if isinstance(err, RecursionError):
        return fail(STACK_OVERFLOW)
    if isinstance(err, MemoryError):
        return fail(OUT_OF_MEMORY)
    member = _library_member_of(err)
    if member is not None:
        return _argument_error(err, member)
    if not _raised_in_program(err):
        return None  # not the program's fault: a bug in twin, let it show
    if isinstance(err, (AttributeError, TypeError)) and "NoneType" in str(err):
        return fail(NULL_OBJECT)
    if isinstance(err, (TypeError, ValueError)):
        return fail(TYPE_MISMATCH, str(err))
    return None


_LIBRARY = str(Path(library_package.__file__).parent)
_ARGUMENT_ERRORS = (TypeError, ValueError, AttributeError, IndexError, KeyError)


def _library_member_of(err: BaseException) -> str | None:
    """The built-in member whose own code raised `err` while taking its arguments apart
    (`int("abc")`, `float(None)`, `loc.total()` of a Profile...), or None.  Only an
    argument error raised right in a member of twin/language/gpl/library counts: an error
    from deeper down (numpy, the controller) stays a twin bug."""
    if not isinstance(err, _ARGUMENT_ERRORS):
        return None
    if isinstance(err, AttributeError) and not _is_gpl_value(getattr(err, "obj", None)):
        return None  # an attribute missing on the twin's own objects (its controller...)
    frames = traceback.extract_tb(err.__traceback__)
    if not frames or not frames[-1].filename.startswith(_LIBRARY):
        return None
    return frames[-1].name


def _is_gpl_value(value) -> bool:
    """A value a GPL program can hold: a number, String, Nothing, array or object."""
    return value is None or isinstance(value, (int, float, str, values.GplArray, GplObject)) or \
        hasattr(type(value), "gpl_name")


def _argument_error(err: BaseException, member: str) -> GplError:
    """An argument a built-in member cannot use, as the GPL error: a String that is not a
    number -708, Nothing -705, any other value of the wrong kind -706."""
    text = str(err)
    if isinstance(err, ValueError) and ("could not convert string" in text or "invalid literal" in text):
        return fail(INVALID_NUMBER, f"a String that is not a number given to {member}")
    if "NoneType" in text:
        return fail(NULL_OBJECT, f"Nothing given to {member}")
    return fail(INVALID_ARGUMENT, f"a value of the wrong kind given to {member}")


def _raised_in_program(err: BaseException) -> bool:
    """Raised by generated code, the value operations or the run-time member
    lookup (a call with the wrong arguments fails there), not inside a library."""
    frames = traceback.extract_tb(err.__traceback__)
    return bool(frames) and (frames[-1].filename.startswith("<gpl:") or
                             frames[-1].filename in (values.__file__, __file__))


def _catch(rt, err: BaseException):
    gpl = as_gpl_error(err)
    if gpl is None:
        raise err
    rt.last_caught = gpl
    return builtins.GplException.from_error(gpl)


def _throw(exc) -> GplError:
    if exc is None:
        return fail(NULL_OBJECT, "Throw of Nothing")
    if not isinstance(exc, builtins.GplException):
        return fail(TYPE_MISMATCH, "Throw needs an Exception object")
    return exc.to_error()


def _rethrow(rt) -> GplError:
    if rt.last_caught is None:
        return fail(INVALID_STATEMENT, "Throw without an Exception outside a Catch")
    return rt.last_caught


# ------------------------------------------------------------------ the system
class GplSystem:
    """A loaded, compiled GPL project: its namespace, files and threads."""

    def __init__(self, robot, io, clock: Callable[[], float], scheduler=None, console: Console | None = None,
                 sandbox: Path | None = None, seed: int = 0):
        self.robot = robot
        self.io = io
        self.clock = clock
        self.scheduler = scheduler
        self.console = console or Console()
        self.sandbox = sandbox or Path.cwd()
        self.random = random.Random(seed)
        self.threads: list[GplThread] = []
        self.namespace: dict = {}
        self.sources: dict[str, list[str]] = {}
        self.compiled: CompiledProject | None = None
        self.start_procedure: str | None = None
        self.project_name = ""

    # ---- loading
    def load_project(self, folder: str | Path) -> str:
        """Load Project.gpr and its files; returns the start procedure's name."""
        project = read_project(Path(folder))
        self.project_name = project.name
        self.load_files(project.sources)
        self.start_procedure = project.start
        return project.start

    def load_files(self, paths: list[Path]) -> None:
        files = []
        for path in paths:
            files.append(parse_file(path))
            self.sources[str(path)] = Path(path).read_text(encoding="latin-1").splitlines()
        self._compile(files)

    def load_text(self, text: str, file: str = "<string>") -> None:
        """Load GPL source text (a whole project in one file), for tests and tools."""
        self.sources[file] = text.splitlines()
        self._compile([parse(text, file)])

    def _compile(self, files) -> None:
        try:
            compiled = ProjectCompiler(files).compile()
        except ProgramError as err:
            lines = self.sources.get(err.file or "", [])
            if err.line and 0 < err.line <= len(lines):
                err.located(text=lines[err.line - 1])
            raise
        self.compiled = compiled
        ns = self.namespace
        ns.update(_NAMESPACE)
        ns.update({f"L_{cls.gpl_name.lower()}": cls for cls in CLASSES.values()})
        ns.update(compiled.statics)
        for cls in compiled.classes:
            ns[cls.py] = type(cls.py, (GplObject,), {"gpl_name": cls.name})
        for module in compiled.modules:
            for var in module.vars.values():
                ns[var.py] = None
        for index, unit in enumerate(compiled.units):
            exec(self._python_code(unit, index), ns)
        for cls in compiled.classes:
            ns[cls.py].gpl_members = self._class_members(cls)

    def _python_code(self, unit, index: int):
        """The unit's generated Python, compiled.  Python's own limits (20 nested loops or
        Try blocks, 100 indentation levels, 200 nested parentheses) are GPL -2014 errors
        at the statement that goes beyond them."""
        try:
            return compile(unit.source, f"<gpl:{index}>", "exec")
        except (SyntaxError, RecursionError, MemoryError) as err:
            generated = getattr(err, "lineno", None) or 0
            lines = [n for n in unit.line_map if n <= generated] or sorted(unit.line_map)[:1]
            located = ProgramError(f"{message(TOO_DEEP)}: more than the controller can nest in {unit.name}",
                                   TOO_DEEP, file=unit.file, program=unit.name)
            if lines:
                line, column = unit.line_map[max(lines)]
                text = self.sources.get(unit.file, [])
                located.located(line=line, column=column, text=text[line - 1] if 0 < line <= len(text) else None)
            raise located from None

    def _class_members(self, cls) -> dict:
        """What run-time member lookup (_callm/_setm) needs about a user class."""
        ns = self.namespace
        table = {}
        for key, var in cls.fields.items():
            convert = ns.get(values.CONVERT.get(var.type.base, ""), lambda v: v) if not var.type.rank else (lambda v: v)
            table[key] = ("field" if var.kind == "field" else "shared", var.py, convert)
        for key, proc in cls.methods.items():
            table[key] = ("method", ns[proc.py], proc.instance, frozenset(proc.byref_positions), len(proc.params))
        for key, prop in cls.properties.items():
            table[key] = ("property", ns.get(prop.getter_py), ns.get(prop.setter_py), not prop.shared)
        return table

    def find_procedure(self, name: str, unknown: int = UNKNOWN_SYMBOL_AT_RUN_TIME):
        """A procedure by name at run time: "proc", "module.proc" or "class.proc" (ch. 10);
        an unknown name is the error `unknown`."""
        proc = self.compiled.public_procs.get(str(name).strip().lower())
        if proc is None:
            raise fail(unknown, str(name))
        return proc

    # ---- threads
    def start(self, procedure: str | None = None) -> "GplThread":
        """The main thread: module initialisation, then the start procedure."""
        name = procedure or self.start_procedure
        if name is None:
            raise ProgramError(message(NO_START_PROCEDURE), NO_START_PROCEDURE)
        proc = self.compiled.public_procs.get(name.lower())
        if proc is None or proc.params or proc.instance:
            raise ProgramError(f"{message(NO_START_PROCEDURE)}: {name}", NO_START_PROCEDURE)
        ns = self.namespace
        steps = [ns[py] for py in self.compiled.init_units] + [ns[py] for py in self.compiled.init_subs]
        steps.append(ns[proc.py])
        thread = GplThread(self, steps, proc.qualified, name="main")
        self._add(thread)
        return thread

    def start_thread(self, target, name: str = "") -> "GplThread":
        if isinstance(target, Delegate):
            if target.params:
                raise fail(INVALID_ARGUMENT, f"thread procedure {target.name} must have no parameters")
            fn, me, label = target.fn, target.me, target.name
            steps = [(lambda rt: fn(rt, me)) if me is not None else fn]
        else:
            proc = self.find_procedure(target, UNKNOWN_START_PROCEDURE)
            if proc.params:
                raise fail(INVALID_ARGUMENT, f"thread procedure {proc.name} must have no parameters")
            steps, label = [self.namespace[proc.py]], proc.qualified
        thread = GplThread(self, steps, label, name=name or label)
        self._add(thread)
        return thread

    def _add(self, thread: "GplThread") -> None:
        self.threads.append(thread)
        if self.scheduler is not None:
            self.scheduler.add(thread)

    # ---- errors
    def locate(self, err: GplError, tb, thread_procedure: str) -> ProgramError:
        """The error as a ProgramError at the innermost GPL statement."""
        located = ProgramError(err.message, err.code)
        for frame, lineno in reversed(list(traceback.walk_tb(tb))):
            filename = frame.f_code.co_filename
            if filename.startswith("<gpl:"):
                unit = self.compiled.units[int(filename[5:-1])]
                where = unit.line_map.get(lineno)
                if where is not None:
                    line, column = where
                    lines = self.sources.get(unit.file, [])
                    located.located(file=unit.file, line=line, column=column, program=unit.name,
                                    text=lines[line - 1] if 0 < line <= len(lines) else None)
                    break
        return located.located(program=thread_procedure)


class GplThread:
    """A GPL thread: a scheduler task, and the `rt` of the code it runs."""

    SLICE = SLICE

    def __init__(self, system: GplSystem, steps: list, procedure: str, name: str):
        self.system = system
        self.procedure = procedure
        self.name = name
        self.robot = system.robot
        self.io = system.io
        self.console = system.console
        self.sandbox = system.sandbox
        self.random = system.random
        self.last_random: float | None = None
        self.last_caught: GplError | None = None
        self.error: ProgramError | None = None
        self.finished = False
        self.suspended = False
        self.running = False
        self.generator = self._run(steps)

    # ---- the GplRuntime protocol
    def clock(self) -> float:
        return self.system.clock()

    def current_thread(self) -> "GplThread":
        return self

    def start_thread(self, target, name: str = "") -> "GplThread":
        return self.system.start_thread(target, name)

    @property
    def alive(self) -> bool:
        return not self.finished

    @property
    def label(self) -> str:
        return f"thread {self.name}"

    def current_location(self) -> dict | None:
        """Where the thread is, for the watchdog's message: procedure, file, line, source."""
        running = self.generator.gi_frame
        generator = running.f_locals.get("gen") if running is not None else None
        where = None
        while generator is not None:
            frame = getattr(generator, "gi_frame", None)
            if frame is not None and frame.f_code.co_filename.startswith("<gpl:"):
                unit = self.system.compiled.units[int(frame.f_code.co_filename[5:-1])]
                found = unit.line_map.get(frame.f_lineno)
                if found is not None:
                    lines = self.system.sources.get(unit.file, [])
                    line = found[0]
                    where = {"program": unit.name, "file": unit.file, "line": line,
                             "text": lines[line - 1] if 0 < line <= len(lines) else None}
            generator = getattr(generator, "gi_yieldfrom", None)
        return where

    def abort(self) -> None:
        self.finished = True
        if self.running:
            raise _Abort()
        self.generator.close()

    def suspend(self) -> None:
        self.suspended = True

    def resume(self) -> None:
        self.suspended = False

    def no_me(self):
        raise fail(ME_UNDEFINED)

    # ---- running
    def _run(self, steps: list) -> Iterator:
        try:
            for step in steps:
                gen = step(self)
                while True:
                    self.running = True
                    try:
                        wait = next(gen)
                    except StopIteration:
                        break
                    finally:
                        self.running = False
                    yield wait
                    while self.suspended:
                        yield lambda: not self.suspended
        except _Abort:
            pass
        except Exception as err:  # noqa: BLE001 - sorted out just below
            gpl = as_gpl_error(err)
            if gpl is None:
                raise
            self.error = self.system.locate(gpl, err.__traceback__, self.procedure)
        finally:
            self.finished = True


def _delegate_named(rt, name, kind: str, params: int) -> Delegate:
    """New Template("proc"): found when the New runs (ch. 10, AddressOf vs. String)."""
    proc = rt.system.find_procedure(values._cstr(name))
    if proc.kind != kind or len(proc.params) != params or proc.instance:
        raise fail(TYPE_MISMATCH, f"{proc.name} does not match the Delegate")
    return Delegate(rt.system.namespace[proc.py], None, proc.qualified, len(proc.params))


# The names generated code sees, besides L_<class> and the project's own.
_NAMESPACE = {
    "GplArray": values.GplArray,
    "_Jump": _Jump, "_Break": _Break, "_ExitTry": _ExitTry,
    "_Delegate": Delegate, "_invoke": _invoke, "_w": _w, "_callm": _callm, "_setm": _setm,
    "_setattr": _setattr, "_call": _call, "_setindex": _setindex, "_redim": _redim,
    "_case_value": _case_value, "_object": _object, "_catch": _catch, "_throw": _throw, "_rethrow": _rethrow, "_Ref": Ref, "_Cell": _Cell, "_GlobalRef": _GlobalRef, "_AttrRef": _AttrRef, "_ItemRef": _ItemRef,
    "_STRING": {k: v[0] for k, v in builtins.STRING_MEMBERS.items()},
    "_STRING_SHARED": builtins.STRING_SHARED,
    "_delegate_named": _delegate_named,
    **{f"F_{name}": fn for name, (fn, _rt) in builtins.FUNCTIONS.items()},
    **{name: getattr(values, name) for name in dir(values) if name.startswith("_") and not name.startswith("__")},
}
