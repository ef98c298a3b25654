"""AST -> Python: each V+ program becomes one Python generator function.

Why compile: a tree-walking interpreter in Python runs a few hundred thousand
statements a second; generated Python runs several times faster, and Python's
own generators give us cooperative tasks for free: an instruction that must
wait (a motion, CLOSEI, WAIT, a time slice) `yield`s a wait condition to the
scheduler, and a CALL is a `yield from`.

Storage of variables (V+ guide v17, "Variable Classes"):
  * GLOBAL  -> `G["name"]`, the controller's global dictionary;
  * LOCAL   -> `L["name"]`, one dictionary per program, shared by its calls;
  * AUTO and parameters -> Python locals of the generated function.
Arrays are `VArray` dictionaries stored under "name[]".  Reading a name that
was never assigned raises KeyError/NameError, which the task turns into V+'s
"*Undefined value*" at the right step.

Parameters are passed by value-result: the callee returns its final parameter
values and the caller writes them back into the variables it passed, which is
what V+'s by-reference passing looks like to a program (an argument that is an
expression, `(x)`, `loc:NULL` or `$s+""`, is not written back).

Every generated line is mapped back to the V+ statement it came from
(`CompiledProgram.line_map`), so errors report file, line and step.

GOTO: Python has no jump, so a program that uses GOTO (or a multi-level
EXIT/NEXT) is lowered to a jump table: its body is cut into basic blocks at
the labels GOTO targets and at the joins of the blocks it lowers, and runs as
`while True:` around a binary dispatch on the block number `_pc`.  Only the
IF/FOR/WHILE/DO/CASE blocks that hold a GOTO, a GOTO target or a multi-level
EXIT are lowered to jumps; the others stay structured Python inside their
basic block, and programs without GOTO keep the structured form entirely.
"""

from __future__ import annotations

import inspect
import math
from dataclasses import dataclass, field

from ...errors import ProgramError
from . import ast
from . import messages as msg
from .compile_library import ERROR_OUTPUT, LIBRARY_CALLS, LibraryStatements
from .keywords import FUNCTIONS, INSTRUCTIONS, STRING_FUNCTIONS, argument_check, arity, called_bare
from .values import single
from .parser import normalize_name

# A time slice: loops hand the CPU back to the scheduler every this many
# iterations, as the V+ scheduler preempts a task at the end of its slice.
SLICE_ITERATIONS = 1024
MAX_DIMENSIONS = 3  # arrays have one to three dimensions ([000] L3987-4045)

# Program-interrupt and task instructions, carried out by the task itself
# (tasking.TaskControl): keyword -> (method of rt, whether it may wait,
# fewest and most arguments).
_TASK_INSTRUCTIONS = {
    "LOCK": ("lock", True, 1, 1), "IGNORE": ("ignore", False, 1, 1), "ABORT": ("abort", False, 0, 1),
    "KILL": ("kill", False, 1, 1), "CYCLE.END": ("cycle_end", False, 0, 1), "PAUSE": ("pause", True, 0, 0),
    "SET.EVENT": ("set_event", False, 0, 1), "CLEAR.EVENT": ("clear_event", False, 0, 1),
    "WAIT.EVENT": ("wait_event", True, 0, 2), "RELEASE": ("release", True, 0, 1),
    "RUNSIG": ("runsig", False, 1, 1),
}
# keyword -> (method of rt, fewest and most arguments)
_TASK_FUNCTIONS = {"PRIORITY": ("priority", 0, 0), "TASK": ("task_info", 0, 2), "GET.EVENT": ("get_event", 0, 1)}
# Block statements and steps that only steer the flow are not wrapped for the
# error trap (REACTE): an error trap resumes at the step after a failing one.
_UNTRAPPED = (ast.If, ast.For, ast.While, ast.DoUntil, ast.Case, ast.Declare, ast.LabelOnly)

_FLOW = {"RETURN", "RETURNE", "EXIT", "NEXT", "STOP", "HALT"}
# Instructions the compiler carries out itself (besides the keyword table).
_INSTRUCTION_NAMES = {*_FLOW, *_TASK_INSTRUCTIONS, "WAIT", "REACT", "REACTI", "REACTE"}

# What each argument check expects, for the load-time message.
_EXPECTED = {"_real": "a real value", "_location": "a location", "_point": "a location", "_str": "a string"}

_RELATIONAL = {"==": "==", "<>": "!=", "<": "<", "<=": "<=", ">": ">", ">=": ">="}
_ARITH = {"+": "+", "-": "-", "*": "*", "/": "/"}


def mangle(name: str) -> str:
    """A V+ name as a Python identifier (V+ names hold '.', '$', '#', '%')."""
    return (
        name.replace("_", "__").replace(".", "_d").replace("$", "S_").replace("#", "P_").replace("%", "B_")
    )


@dataclass
class CompiledProgram:
    name: str
    source: str
    line_map: dict[int, ast.Statement]  # generated line -> V+ statement
    file: str
    params: list[ast.Var]
    function: object = None  # the generator function, set by the loader
    statement_count: int = 0
    frame_bytes: int = 20  # stack bytes of a call besides its arguments: 20 and the AUTO variables
    line: int = 0  # the .PROGRAM line


def is_string(expr: ast.Expr) -> bool:
    """Static type of an expression: V+ marks strings with '$'."""
    if isinstance(expr, ast.Str):
        return True
    if isinstance(expr, ast.Var):
        return expr.name.startswith("$")
    if isinstance(expr, ast.Call):
        return expr.name.startswith("$")
    if isinstance(expr, ast.Binary) and expr.op == "+":
        return is_string(expr.left) or is_string(expr.right)
    return False


def _bodies(s: ast.Statement) -> list[list[ast.Statement]]:
    if isinstance(s, ast.If):
        return [s.body, s.orelse]
    if isinstance(s, (ast.For, ast.While, ast.DoUntil)):
        return [s.body]
    if isinstance(s, ast.Case):
        return [body for _, body in s.cases] + ([s.default] if s.default is not None else [])
    return []


def _walk(body: list[ast.Statement]):
    for s in body:
        yield s
        for inner in _bodies(s):
            yield from _walk(inner)


def _loop_control(s: ast.Statement) -> tuple[str, int] | None:
    """("EXIT" | "NEXT", levels) for EXIT [n] and NEXT [n], else None."""
    if not isinstance(s, ast.Instruction) or s.name not in ("EXIT", "NEXT"):
        return None
    if not s.args:
        return s.name, 1
    level = s.args[0]
    if len(s.args) > 1 or not isinstance(level, ast.Num) or level.value < 1 or not float(level.value).is_integer():
        raise ProgramError(f"{msg.message(msg.INVALID_ARGUMENT)} {s.name} level", msg.INVALID_ARGUMENT,
                           line=s.line, column=s.column, step=s.step)
    return s.name, int(level.value)


def _forces_jumps(s: ast.Statement, targets: set[int]) -> bool:
    """A statement that only the jump-table form can run."""
    control = _loop_control(s)
    return (isinstance(s, (ast.Goto, ast.IfGoto)) or s.label in targets
            or (control is not None and control[1] > 1))


@dataclass
class _Op:
    """One step of a lowered program: a statement compiled as usual, a block
    boundary, a jump, or a conditional jump on a Python condition."""

    kind: str  # "stmt", "mark", "jump", "branch", "code"
    statement: ast.Statement | None = None
    target: int = -1  # mark id
    condition: str = ""  # for "branch": jump when this Python condition holds
    waits_on: ast.Expr | None = None  # for "branch": the V+ condition, for its GETCs
    emit: object = None  # for "code": callable(depth) that emits lines
    loops: tuple = ()  # the loop stack a "stmt" is compiled under


@dataclass
class _Scope:
    auto: set[str] = field(default_factory=set)  # names kept as Python locals
    local: set[str] = field(default_factory=set)  # names kept in L
    doubles: set[str] = field(default_factory=set)
    types: dict[str, str] = field(default_factory=dict)  # declared REAL (REAL, DOUBLE) or LOC


class ProgramCompiler(LibraryStatements):
    def __init__(self, program: ast.Program, flat: bool = False):
        self.program = program
        self.flat = flat  # every block lowered to jumps (see compile_program)
        self.lines: list[str] = []
        self.line_map: dict[int, ast.Statement] = {}
        self.scope = _Scope()
        self.temp = 0
        self.current: ast.Statement | None = None
        self.count = 0
        # Enclosing loops for EXIT/NEXT: ("py", tail emitter) for a Python
        # loop, ("jump", exit mark, next mark) for a lowered one.
        self.loops: list[tuple] = []
        self.targets: set[int] = set()
        self.marks = 0
        self.block_of: dict[int, int] = {}  # mark id -> basic block index
        self.for_temps: list[str] = []  # limit and step of the lowered FOR loops

    # ----------------------------------------------------------------- output
    def emit(self, depth: int, text: str) -> None:
        self.lines.append("    " * depth + text)
        if self.current is not None:
            self.line_map[len(self.lines)] = self.current

    def fresh(self, stem: str) -> str:
        self.temp += 1
        return f"_{stem}{self.temp}"

    def error(self, statement: ast.Statement, code: int, detail: str = "") -> ProgramError:
        text = msg.message(code) + (f" {detail}" if detail else "")
        return ProgramError(
            text, code, file=self.program.file, line=statement.line, column=statement.column,
            step=statement.step, program=self.program.name,
        )

    # ---------------------------------------------------------------- program
    def compile(self) -> CompiledProgram:
        p = self.program
        header = ast.Statement(line=p.line, column=1, step=1)
        for param in p.params:
            self.check_name(param, header)
            if self.key(param) in self.scope.auto:
                raise self.error(header, msg.SYNTAX_ERROR, f"parameter {param.name} named twice")
            self.scope.auto.add(self.key(param))
        self.collect_declarations(p.body)
        self.emit(0, "def program(rt, _args):")
        self.emit(1, "if False:  # every program is a generator, even one that never waits")
        self.emit(2, "yield")
        self.emit(1, "G = rt.globals")
        self.emit(1, f"L = rt.program_locals({p.name!r})")
        self.emit(1, "_slice = 0")
        self.emit(1, f"if len(_args) > {len(p.params)}:")
        self.emit(2, f"rt.too_many_arguments({p.name!r}, len(_args))")
        for i, param in enumerate(p.params):
            local = self.pyname(param)
            # Arguments "must match ... in number of arguments and data type" ([001] L510).
            kind = "string" if param.name.startswith("$") else "array" if param.indices is not None else "value"
            self.emit(1, f"if len(_args) > {i} and _args[{i}] is not None:")
            self.emit(2, f"{local} = _argument(_args[{i}], {kind!r}, {param.name!r})")
        self.targets = self.goto_targets(p.body)
        if self.flat or any(_forces_jumps(t, self.targets) for t in _walk(p.body)):
            self.jump_table(p.body, 1)
        else:
            self.block(p.body, 1)
            self.emit_return(1)
        return CompiledProgram(p.name, "\n".join(self.lines) + "\n", self.line_map, p.file, p.params,
                               statement_count=self.count, frame_bytes=20 + self.auto_bytes(p.body), line=p.line)

    def auto_bytes(self, body: list[ast.Statement]) -> int:
        """Stack bytes of the AUTO variables ([000] "Stack Space Required by a Subroutine"):
        a real 4, a DOUBLE 8, a LOC 48 (a precision point 4 per joint, 6 here), a string 132,
        an array that many times its elements (constant sizes; others count one element)."""
        total = 0
        for statement in body:
            if not isinstance(statement, ast.Declare) or statement.scope != "AUTO":
                continue
            for var, dims in statement.names:
                prefix = var.name[0]
                size = (132 if prefix == "$" else 24 if prefix == "#" else 8 if statement.double
                        else 48 if statement.kind == "LOC" else 4)
                for d in dims or []:  # an absurd size is simply more than any stack holds
                    size *= int(min(d.value, 1e9)) + 1 if isinstance(d, ast.Num) and d.value >= 0 else 1
                total += size
        return total

    def collect_declarations(self, body: list[ast.Statement]) -> None:
        # Declarations come before any executable step: only comments, blank
        # lines and other declarations may precede them ([000] L859-864).
        executable = next((s for s in body if not isinstance(s, (ast.Declare, ast.LabelOnly))), None)
        for statement in _walk(body):
            if isinstance(statement, ast.Declare) and executable is not None and statement.line > executable.line:
                raise self.error(statement, msg.SYNTAX_ERROR,
                                 f"{statement.scope} after the first executable step (line {executable.line})")
        for statement in body:
            if isinstance(statement, ast.Declare):
                for var, _dims in statement.names:
                    self.check_name(var, statement)
                    key = self.key(var if _dims is None else ast.Var(var.name, []))
                    if statement.scope == "AUTO":
                        self.scope.auto.add(key)
                    elif statement.scope == "LOCAL":
                        self.scope.local.add(key)
                    if statement.double:
                        self.scope.doubles.add(key)
                    if statement.kind is not None:
                        self.declare_type(var, key, statement)

    def declare_type(self, var: ast.Var, key: str, statement: ast.Declare) -> None:
        """AUTO REAL x, AUTO LOC spot: a string cannot be typed, a precision point (#) is a
        LOC; the type then holds for the variable in this program."""
        prefix = var.name[0]
        if prefix == "$" or (prefix == "#" and statement.kind != "LOC"):
            raise self.error(statement, msg.WRONG_TYPE, f"{var.name} cannot be {statement.kind}")
        self.scope.types[key] = "LOC" if statement.kind == "LOC" else "REAL"

    def check_kind(self, target: ast.Var, kind: str) -> None:
        """Assigning a real (=) to a LOC variable, or a location (SET) to a REAL or DOUBLE one."""
        declared = self.scope.types.get(self.key(target))
        if declared is not None and declared != kind:
            raise self.error(self.current, msg.WRONG_TYPE, f"{target.name} is declared {declared}")

    def emit_return(self, depth: int) -> None:
        if not self.program.params:
            self.emit(depth, "return ()")
            return
        names = ", ".join(repr(self.pyname(p)) for p in self.program.params)
        self.emit(depth, f"return rt.results(locals(), ({names},))")

    # ------------------------------------------------------------- variables
    @staticmethod
    def key(var: ast.Var) -> str:
        return var.name + "[]" if var.indices is not None else var.name

    def pyname(self, var: ast.Var) -> str:
        return ("A_" if var.indices is not None else "a_") + mangle(var.name)

    def storage(self, var: ast.Var) -> str:
        """The Python expression that holds the variable (or whole array)."""
        key = self.key(var)
        if key in self.scope.auto:
            return self.pyname(var)
        if key in self.scope.local:
            return f"L[{key!r}]"
        return f"G[{key!r}]"

    def index(self, indices: list[ast.Expr]) -> str:
        if len(indices) > MAX_DIMENSIONS:
            raise self.error(self.current, msg.ILLEGAL_ARRAY_INDEX, f"{len(indices)} dimensions (at most 3)")
        parts = []
        for e in indices:
            if isinstance(e, ast.Num):  # rounded now, as _ix rounds at run time
                index = math.floor(e.value + 0.5)
                if index < 0:
                    raise self.error(self.current, msg.ILLEGAL_ARRAY_INDEX, str(index))
                parts.append(str(index))
            else:
                parts.append(f"_ix({self.expr(e)})")
        return parts[0] if len(parts) == 1 else "(" + ", ".join(parts) + ")"

    def read(self, var: ast.Var) -> str:
        if var.indices:
            return f"{self.storage(var)}[{self.index(var.indices)}]"
        if var.indices is not None:
            return self.storage(var)  # a whole array, a[]
        return self.storage(var)

    @staticmethod
    def reserved(var: ast.Var) -> bool:
        """A function keyword written without arguments: V+ rejects it as a
        variable name ("pi (reserved word)", [000] L3778-3800)."""
        name = var.name.upper()
        return called_bare(name) or _TASK_FUNCTIONS.get(name, (None, 1))[1] == 0

    def check_name(self, var: ast.Var, statement: ast.Statement | None) -> None:
        if self.reserved(var):
            raise self.error(statement or self.current, msg.SYNTAX_ERROR, f"{var.name} is a reserved word")

    def assign(self, var: ast.Var, value: str, depth: int) -> None:
        self.check_name(var, None)
        if var.indices:
            key = self.key(var)
            store = self.storage(var)
            if key in self.scope.auto:
                # An AUTO array must exist (declared with a size) before use.
                self.emit(depth, f"{store}[{self.index(var.indices)}] = {value}")
            else:
                table = "L" if key in self.scope.local else "G"
                self.emit(depth, f"_array({table}, {key!r})[{self.index(var.indices)}] = {value}")
        else:
            self.emit(depth, f"{self.storage(var)} = {value}")

    # ----------------------------------------------------------- expressions
    def expr(self, e: ast.Expr) -> str:
        if isinstance(e, ast.Num):
            # A constant is a single-precision real unless written ^D ([000] L3895-3910).
            if e.double:
                return repr(float(e.value))
            try:
                return repr(single(e.value))
            except OverflowError:
                raise self.error(self.current, msg.OVERFLOW, f"{e.value:g} is beyond single precision") from None
        if isinstance(e, ast.Str):
            return repr(e.value)
        if isinstance(e, ast.Var):
            if e.indices is None and self.reserved(e):  # PI, TRUE, HERE, #PHERE, TASK...
                return self.call(ast.Call(e.name.upper(), []))
            return self.read(e)
        if isinstance(e, ast.Call):
            return self.call(e)
        if isinstance(e, ast.ByCall):
            return f"F[{e.name!r}](rt, {self.checked_arguments(e.name, FUNCTIONS[e.name], [e.subject, *e.args])})"
        if isinstance(e, ast.Compound):
            return f"_compound({self.expr(e.left)}, {self.expr(e.right)})"
        if isinstance(e, ast.Unary):
            if e.op == "-":
                return f"(-{self.expr(e.operand)})"
            if e.op == "NOT":
                return f"(-1.0 if {self.condition(e)} else 0.0)"
            return f"_com({self.expr(e.operand)})"
        if isinstance(e, ast.Binary):
            return self.binary(e)
        raise TypeError(f"unknown expression {e!r}")

    def binary(self, e: ast.Binary) -> str:
        left, right = self.expr(e.left), self.expr(e.right)
        op = e.op
        if op in _RELATIONAL:
            return f"(-1.0 if {self.relation(e)} else 0.0)"
        if op in ("AND", "OR", "XOR"):
            return f"(-1.0 if {self.condition(e)} else 0.0)"
        if op in _ARITH:
            if op == "/":
                return f"_div({left}, {right})"
            return f"({left} {_ARITH[op]} {right})"
        if op == "MOD":
            return f"_mod({left}, {right})"
        if op in ("BAND", "BOR", "BXOR"):
            return f"_bitwise({op!r}, {left}, {right})"
        raise TypeError(op)

    def relation(self, e: ast.Binary) -> str:
        left, right = self.expr(e.left), self.expr(e.right)
        if is_string(e.left) or is_string(e.right):
            return f"_strcmp(rt, {left}, {right}, {e.op!r})"
        return f"({left} {_RELATIONAL[e.op]} {right})"

    def condition(self, e: ast.Expr) -> str:
        """An expression as a Python truth value (V+: nonzero is true)."""
        if is_string(e):  # IF $s THEN, NOT "a": a string is not a truth value
            raise self.error(self.current, msg.WRONG_TYPE, "a string where a condition is needed")
        if isinstance(e, ast.Binary):
            if e.op in _RELATIONAL:
                return self.relation(e)
            if e.op == "AND":
                return f"({self.condition(e.left)} and {self.condition(e.right)})"
            if e.op == "OR":
                return f"({self.condition(e.left)} or {self.condition(e.right)})"
            if e.op == "XOR":
                return f"(bool({self.condition(e.left)}) != bool({self.condition(e.right)}))"
        if isinstance(e, ast.Unary) and e.op == "NOT":
            return f"(not {self.condition(e.operand)})"
        if isinstance(e, ast.Num):
            return f"({self.expr(e)} != 0)"
        return f"(_real({self.expr(e)}) != 0)"  # a location is no truth value: *Wrong data type*

    def call(self, e: ast.Call) -> str:
        if e.name == "DEFINED":
            return self.defined(e)
        if e.name in _TASK_FUNCTIONS:
            method, fewest, most = _TASK_FUNCTIONS[e.name]
            self.argument_count(e.name, e.args, fewest, most)
            return f"rt.{method}({self.arguments(e.args)})"
        if e.name in LIBRARY_CALLS:
            return self.library_call(e)  # $DECODE, TAS, PARAMETER(name): see compile_library.py
        table = STRING_FUNCTIONS if e.name.startswith("$") else FUNCTIONS
        if e.name not in table:
            raise self.error(self.current, msg.UNDEFINED_PROGRAM, e.name)
        fewest, most = arity(table[e.name])
        self.argument_count(e.name, e.args, fewest, most)
        error_var = self.error_output(e.name, e.args)
        if error_var is not None:  # DEVICE(0, unit, error, select): `error` receives the status
            args = ", ".join(self.peek(a) if i == ERROR_OUTPUT[e.name]
                             else self.checked(a, argument_check(table[e.name], i), e.name)
                             for i, a in enumerate(e.args))
            result = self.fresh("dev")
            return f"({result} := F[{e.name!r}](rt, {args}), {self.assign_expr(error_var, '0.0')})[0]"
        args = self.checked_arguments(e.name, table[e.name], e.args)
        return f"F[{e.name!r}](rt{', ' if args else ''}{args})"

    def checked(self, arg: ast.Expr | None, check: str | None, name: str) -> str:
        """An argument with the check its parameter's kind asks for (keywords/__init__.py):
        a string constant or $ expression where another kind belongs, or a number where a
        string belongs, is a load-time *Wrong data type*; a real constant needs no check."""
        if arg is None:
            return "None"
        if check is None:
            return self.expr(arg)
        text = is_string(arg)
        if (check == "_str") != text and (text or isinstance(arg, ast.Num)):
            raise self.error(self.current, msg.WRONG_TYPE,
                             f"{name}: {'a string' if text else 'a number'} where {_EXPECTED[check]} belongs")
        if (check == "_real" and isinstance(arg, ast.Num)) or (check == "_str" and isinstance(arg, ast.Str)):
            return self.expr(arg)
        return f"{check}({self.expr(arg)})"

    def checked_arguments(self, name: str, function, args: list) -> str:
        return ", ".join(self.checked(a, argument_check(function, i), name) for i, a in enumerate(args))

    def defined(self, e: ast.Call) -> str:
        if len(e.args) != 1 or not isinstance(e.args[0], ast.Var):
            raise self.error(self.current, msg.INVALID_ARGUMENT, "DEFINED takes one variable")
        var = e.args[0]
        key = self.key(var)
        if key in self.scope.auto:
            if var.indices:  # the AUTO array exists from its declaration; is the element set?
                return f"(-1.0 if {self.index(var.indices)} in {self.pyname(var)} else 0.0)"
            return f"(-1.0 if {self.pyname(var)!r} in locals() else 0.0)"
        table = "L" if key in self.scope.local else "G"
        if var.indices:
            return f"_defined_element({table}, {key!r}, {self.index(var.indices)})"
        return f"(-1.0 if {key!r} in {table} else 0.0)"

    # ------------------------------------------------------------ statements
    def block(self, body: list[ast.Statement], depth: int) -> None:
        if not any(not isinstance(s, (ast.Declare, ast.LabelOnly)) for s in body):
            self.emit(depth, "pass")
        for statement in body:
            self.statement(statement, depth)

    def statement(self, s: ast.Statement, depth: int) -> None:
        self.current = s
        self.count += 1
        handler = getattr(self, "s_" + type(s).__name__, None)
        if handler is None:
            raise self.error(s, msg.UNKNOWN_KEYWORD, type(s).__name__)
        if isinstance(s, _UNTRAPPED) or (isinstance(s, ast.Instruction) and s.name in _FLOW):
            handler(s, depth)
            return
        # A step's error goes to the task's REACTE routine, if it has one; the
        # try costs nothing until something raises (Python 3.11).
        self.emit(depth, "try:")
        self.wait_for_input(s, depth + 1)  # GETC in wait mode: see compile_library.py
        handler(s, depth + 1)
        self.current = s
        self.emit(depth, "except _TRAPPED as _error:")
        self.emit(depth + 1, "yield from rt.trap(_error)")

    def s_Assign(self, s: ast.Assign, depth: int) -> None:
        self.check_kind(s.target, "REAL")
        if s.target.name.startswith("$") != is_string(s.value) and not isinstance(s.value, ast.Call):
            raise self.error(s, msg.WRONG_TYPE)
        value = self.expr(s.value)
        if s.target.name.startswith("$"):
            value = f"_str({value})"
        elif isinstance(s.value, ast.Num) and (not s.value.double or self.key(s.target) in self.scope.doubles):
            pass  # a constant is stored as it was compiled
        else:
            value = self.real(s.target, value)
        self.assign(s.target, value, depth)

    def real(self, target: ast.Var, value: str) -> str:
        """The Python expression that stores `value` into a real variable:
        DOUBLE variables keep 64 bits, the others are single precision."""
        key = self.key(target)
        return f"_real({value})" if key in self.scope.doubles else f"_single({value})"

    def s_SetLocation(self, s: ast.SetLocation, depth: int) -> None:
        self.check_kind(s.target, "LOC")
        check = "_precision_point" if s.target.name.startswith("#") else "_location"
        self.assign(s.target, f"{check}({self.expr(s.value)})", depth)

    def s_Declare(self, s: ast.Declare, depth: int) -> None:
        for var, dims in s.names:
            if dims is None:
                continue
            target = ast.Var(var.name, [])
            if self.key(target) in self.scope.auto:
                if len(dims) > MAX_DIMENSIONS:
                    raise self.error(s, msg.ILLEGAL_ARRAY_INDEX, f"{len(dims)} dimensions (at most 3)")
                limits = ", ".join(f"_ix({self.expr(d)})" for d in dims)
                self.emit(depth, f"{self.pyname(target)} = _auto_array(({limits},))")
            else:
                table = "L" if s.scope == "LOCAL" else "G"
                self.emit(depth, f"_array({table}, {self.key(target)!r})")
        if s.scope == "GLOBAL" or not any(d for _, d in s.names):
            self.count -= 1  # declarations are not executable steps

    def s_LabelOnly(self, s: ast.LabelOnly, depth: int) -> None:
        self.count -= 1

    def s_If(self, s: ast.If, depth: int) -> None:
        self.wait_for_input(s.condition, depth)
        self.emit(depth, f"if {self.condition(s.condition)}:")
        self.block(s.body, depth + 1)
        if s.orelse:
            self.current = s
            self.emit(depth, "else:")
            self.block(s.orelse, depth + 1)

    def slice_check(self, depth: int) -> None:
        """Give the CPU back now and then: V+ time-slices tasks."""
        self.emit(depth, "_slice += 1")
        self.emit(depth, f"if _slice >= {SLICE_ITERATIONS}:")
        self.emit(depth + 1, "_slice = 0")
        self.emit(depth + 1, "yield rt.SLICE")

    def for_start(self, s: ast.For, stop: str, step: str, depth: int) -> None:
        """FOR evaluates its limit and step once, before the first pass."""
        self.emit(depth, f"{stop} = _real({self.expr(s.stop)})")
        self.emit(depth, f"{step} = {self.expr(s.step_by) if s.step_by else '1.0'}")
        self.emit(depth, f"if {step} == 0: rt.zero_step()")
        self.assign(s.target, self.real(s.target, self.expr(s.start)), depth)

    def for_test(self, s: ast.For, stop: str, step: str) -> str:
        current = self.read(s.target)
        return f"(({current} <= {stop}) if {step} > 0 else ({current} >= {stop}))"

    def loop_body(self, body: list[ast.Statement], tail, depth: int) -> None:
        """A Python loop's body, then its tail (what NEXT runs before `continue`)."""
        self.loops.append(("py", tail))
        self.block(body, depth)
        self.loops.pop()
        tail(depth)

    def s_For(self, s: ast.For, depth: int) -> None:
        stop, step = self.fresh("stop"), self.fresh("step")
        self.for_start(s, stop, step, depth)
        self.emit(depth, f"while {self.for_test(s, stop, step)}:")

        def tail(d: int) -> None:
            self.current = s
            self.assign(s.target, self.real(s.target, f"{self.read(s.target)} + {step}"), d)
            self.slice_check(d)

        self.loop_body(s.body, tail, depth + 1)

    def s_While(self, s: ast.While, depth: int) -> None:
        # The test is the loop's first step, where a GETC in it waits.
        self.emit(depth, "while True:")
        self.wait_for_input(s.condition, depth + 1)
        self.emit(depth + 1, f"if not {self.condition(s.condition)}: break")

        def tail(d: int) -> None:
            self.current = s
            self.slice_check(d)

        self.loop_body(s.body, tail, depth + 1)

    def s_DoUntil(self, s: ast.DoUntil, depth: int) -> None:
        self.emit(depth, "while True:")

        def tail(d: int) -> None:
            self.current = s.until or s
            self.wait_for_input(s.condition, d)
            self.emit(d, f"if {self.condition(s.condition)}: break")
            self.slice_check(d)

        self.loop_body(s.body, tail, depth + 1)

    def loop_control(self, s: ast.Instruction, depth: int) -> None:
        """EXIT leaves the innermost loop, NEXT starts its next pass ([000] L5043, L5106)."""
        name, level = _loop_control(s)
        if not self.loops:
            raise self.error(s, msg.CONTROL_STRUCTURE, f"{name} outside a loop")
        loop = self.loops[-1]  # a multi-level EXIT/NEXT always goes to the jump table
        if loop[0] == "jump":
            self.emit(depth, f"_pc = {self.block_of[loop[1] if name == 'EXIT' else loop[2]]}")
            self.emit(depth, "continue")
        elif name == "EXIT":
            self.emit(depth, "break")
        else:
            loop[1](depth)
            self.emit(depth, "continue")

    def case_subject(self, s: ast.Case, subject: str, depth: int) -> None:
        self.wait_for_input(s.subject, depth)
        self.emit(depth, f"{subject} = _real({self.expr(s.subject)})")  # CASE takes a real ([000] L4775)

    def s_Case(self, s: ast.Case, depth: int) -> None:
        subject = self.fresh("case")
        self.case_subject(s, subject, depth)
        keyword = "if"
        for values, body in s.cases:
            tests = " or ".join(f"{subject} == {self.expr(v)}" for v in values)
            self.emit(depth, f"{keyword} {tests}:")
            self.block(body, depth + 1)
            self.current = s
            keyword = "elif"
        if s.default is not None:
            self.emit(depth, "else:" if s.cases else "if True:")
            self.block(s.default, depth + 1)

    # ------------------------------------------------------------ GOTO
    def goto_targets(self, body: list[ast.Statement]) -> set[int]:
        """The labels some GOTO names; a missing or doubled label is a load error."""
        labels: dict[int, ast.Statement] = {}
        for t in _walk(body):
            if t.label is not None:
                if t.label in labels:
                    raise self.error(t, msg.CONTROL_STRUCTURE, f"label {t.label} used twice")
                labels[t.label] = t
        targets = set()
        for t in _walk(body):
            if isinstance(t, (ast.Goto, ast.IfGoto)):
                if t.target not in labels:
                    raise self.error(t, msg.UNDEFINED_LABEL, str(t.target))
                targets.add(t.target)
        return targets

    def needs_jumps(self, s: ast.Statement) -> bool:
        """Does a block statement hold something only jumps can express?"""
        if self.flat:
            return bool(_bodies(s))
        return any(_forces_jumps(t, self.targets) for body in _bodies(s) for t in _walk(body))

    def mark(self) -> int:
        self.marks += 1
        return self.marks

    def lower(self, body: list[ast.Statement], ops: list[_Op]) -> None:
        """Append the ops of `body`: statements, marks and jumps."""
        for s in body:
            self.current = s  # what a compile error met while lowering names
            if s.label in self.targets:
                ops.append(_Op("mark", s, target=self.label_mark(s.label)))
            if isinstance(s, ast.Goto):
                ops.append(_Op("jump", s, target=self.label_mark(s.target)))
            elif isinstance(s, ast.IfGoto):
                ops.append(_Op("branch", s, target=self.label_mark(s.target), condition=self.condition(s.condition),
                               waits_on=s.condition))
            elif _loop_control(s) is not None:
                ops.append(self.loop_jump(s))
            elif self.needs_jumps(s):
                getattr(self, "lower_" + type(s).__name__)(s, ops)
            elif not isinstance(s, ast.LabelOnly):
                ops.append(_Op("stmt", s, loops=tuple(self.loops)))

    def label_mark(self, label: int) -> int:
        return -label - 1  # label marks are negative, generated marks positive

    def loop_jump(self, s: ast.Instruction) -> _Op:
        name, level = _loop_control(s)
        if level > len(self.loops):
            raise self.error(s, msg.CONTROL_STRUCTURE, f"{name} outside a loop")
        loop = self.loops[-level]
        if loop[0] != "jump":  # only a multi-level EXIT reaches here; it lowers every loop it crosses
            raise self.error(s, msg.CONTROL_STRUCTURE, f"{name} {level}")
        return _Op("jump", s, target=loop[1] if name == "EXIT" else loop[2])

    def lower_If(self, s: ast.If, ops: list[_Op]) -> None:
        orelse, end = self.mark(), self.mark()
        ops.append(_Op("branch", s, target=orelse, condition=f"not {self.condition(s.condition)}",
                       waits_on=s.condition))
        self.lower(s.body, ops)
        ops.append(_Op("jump", s, target=end))
        ops.append(_Op("mark", s, target=orelse))
        self.lower(s.orelse, ops)
        ops.append(_Op("mark", s, target=end))

    def lower_loop(self, s: ast.Statement, ops: list[_Op], next_: int, end: int) -> None:
        self.loops.append(("jump", end, next_))
        self.lower(s.body, ops)
        self.loops.pop()
        ops.append(_Op("mark", s, target=next_))

    def lower_While(self, s: ast.While, ops: list[_Op]) -> None:
        top, next_, end = self.mark(), self.mark(), self.mark()
        ops.append(_Op("mark", s, target=top))
        ops.append(_Op("branch", s, target=end, condition=f"not {self.condition(s.condition)}",
                       waits_on=s.condition))
        self.lower_loop(s, ops, next_, end)
        ops.append(_Op("jump", s, target=top))
        ops.append(_Op("mark", s, target=end))

    def lower_DoUntil(self, s: ast.DoUntil, ops: list[_Op]) -> None:
        top, test, end = self.mark(), self.mark(), self.mark()
        ops.append(_Op("mark", s, target=top))
        self.lower_loop(s, ops, test, end)
        ops.append(_Op("branch", s.until or s, target=top, condition=f"not {self.condition(s.condition)}",
                       waits_on=s.condition))
        ops.append(_Op("mark", s, target=end))

    def lower_For(self, s: ast.For, ops: list[_Op]) -> None:
        top, next_, end = self.mark(), self.mark(), self.mark()
        stop, step = self.fresh("stop"), self.fresh("step")
        self.for_temps += [stop, step]
        ops.append(_Op("code", s, emit=lambda depth: self.for_start(s, stop, step, depth)))
        ops.append(_Op("mark", s, target=top))
        ops.append(_Op("branch", s, target=end, condition=f"not {self.for_test(s, stop, step)}"))
        self.lower_loop(s, ops, next_, end)

        def next_pass(depth: int) -> None:
            self.emit(depth, f"if {step} is None: rt.loop_not_started()")  # a GOTO into the body
            self.assign(s.target, self.real(s.target, f"{self.read(s.target)} + {step}"), depth)

        ops.append(_Op("code", s, emit=next_pass))
        ops.append(_Op("jump", s, target=top))
        ops.append(_Op("mark", s, target=end))

    def lower_Case(self, s: ast.Case, ops: list[_Op]) -> None:
        subject, end = self.fresh("case"), self.mark()
        ops.append(_Op("code", s, emit=lambda depth: self.case_subject(s, subject, depth)))
        entries = []
        for values, body in s.cases:
            entry = self.mark()
            tests = " or ".join(f"{subject} == {self.expr(v)}" for v in values)
            ops.append(_Op("branch", s, target=entry, condition=f"({tests})"))
            entries.append((entry, body))
        if s.default is not None:
            entry = self.mark()
            ops.append(_Op("jump", s, target=entry))
            entries.append((entry, s.default))
        else:
            ops.append(_Op("jump", s, target=end))
        for entry, body in entries:
            ops.append(_Op("mark", s, target=entry))
            self.lower(body, ops)
            ops.append(_Op("jump", s, target=end))
        ops.append(_Op("mark", s, target=end))

    def jump_table(self, body: list[ast.Statement], depth: int) -> None:
        """Compile `body` as basic blocks run by a dispatch loop on `_pc`."""
        ops: list[_Op] = []
        self.lower(body, ops)
        blocks: list[list[_Op]] = [[]]
        for op in ops:
            if op.kind == "mark":
                if blocks[-1]:
                    blocks.append([])
                self.block_of[op.target] = len(blocks) - 1
            else:
                blocks[-1].append(op)
        if self.for_temps:
            self.emit(depth, f"{' = '.join(self.for_temps)} = None")
        self.emit(depth, "_pc = 0")
        self.emit(depth, "while True:")
        self.dispatch(blocks, 0, len(blocks), depth + 1)

    def dispatch(self, blocks: list[list[_Op]], low: int, high: int, depth: int) -> None:
        """A binary search on `_pc`: a jump costs log2(blocks) comparisons."""
        if high - low == 1:
            self.basic_block(blocks, low, depth)
            return
        middle = (low + high) // 2
        self.emit(depth, f"if _pc < {middle}:")
        self.dispatch(blocks, low, middle, depth + 1)
        self.emit(depth, "else:")
        self.dispatch(blocks, middle, high, depth + 1)

    def basic_block(self, blocks: list[list[_Op]], index: int, depth: int) -> None:
        ops = blocks[index]
        for op in ops:
            self.current = op.statement
            if op.kind == "stmt":
                saved, self.loops = self.loops, list(op.loops)
                self.statement(op.statement, depth)
                self.loops = saved
            elif op.kind == "code":
                op.emit(depth)
            elif op.kind == "jump":
                self.jump(index, op.target, depth)
                return
            else:
                self.wait_for_input(op.waits_on, depth)
                self.emit(depth, f"if {op.condition}:")
                self.jump(index, op.target, depth + 1)
        if index + 1 < len(blocks):
            self.emit(depth, f"_pc = {index + 1}")
        else:
            self.emit_return(depth)

    def jump(self, here: int, mark: int, depth: int) -> None:
        target = self.block_of[mark]
        self.emit(depth, f"_pc = {target}")
        if target <= here:  # a backward jump closes a loop: time-slice it
            self.slice_check(depth)
        self.emit(depth, "continue")


    def by_reference(self, arg: ast.Expr | None) -> bool:
        """A CALL argument the callee writes back: a variable or an array
        element, not `(x)` or another expression ([000] L1169-1200); a whole
        array `a[]` is passed as the array itself."""
        return (isinstance(arg, ast.Var) and not arg.parenthesized and (arg.indices is None or arg.indices)
                and not self.reserved(arg))  # TRUE, PI...: a value, not a variable

    def s_CallProgram(self, s: ast.CallProgram, depth: int) -> None:
        # A variable passed by reference may still be undefined: the callee
        # sees an undefined parameter (DEFINED() is false) and may define it.
        args = ", ".join("None" if a is None else self.peek(a) if self.by_reference(a) else self.expr(a)
                         for a in s.args)
        if s.name is not None:
            target = repr(s.name)
        else:
            target = f"_program_name({self.expr(s.name_expr)})"
        results = self.fresh("ret")
        self.emit(depth, f"{results} = yield from rt.call({target}, [{args}])")
        for i, arg in enumerate(s.args):
            if self.by_reference(arg):
                self.emit(depth, f"if {results}[{i}] is not None:")
                self.assign(arg, f"{results}[{i}]", depth + 1)

    def s_TypeOut(self, s: ast.TypeOut, depth: int) -> None:
        items = [self.io_item(item) for item in s.items]
        self.emit(depth, f"rt.type_out(({', '.join(items)}{',' if len(items) == 1 else ''}))")

    def s_Prompt(self, s: ast.Prompt, depth: int) -> None:
        """PROMPT text, $s takes the typed line; PROMPT text, x, y, ... the
        numbers typed, separated by commas or spaces (docs/vplus.md)."""
        text = self.fresh("in")
        self.emit(depth, f"{text} = rt.prompt({self.expr(s.text)})")
        if any(t.name.startswith("$") for t in s.targets):
            if len(s.targets) > 1:
                raise self.error(s, msg.WRONG_TYPE, "PROMPT takes one string variable or real variables")
            self.assign(s.targets[0], text, depth)
            return
        if not s.targets:
            return
        numbers = self.fresh("num")
        self.emit(depth, f"{numbers} = rt.prompt_numbers({text}, {len(s.targets)})")
        for i, target in enumerate(s.targets):
            self.emit(depth, f"if {numbers}[{i}] is not None:")
            self.assign(target, self.real(target, f"{numbers}[{i}]"), depth + 1)

    def s_Parameter(self, s: ast.Parameter, depth: int) -> None:
        index, value = self.checked(s.index, "_real", "PARAMETER"), self.checked(s.value, "_real", "PARAMETER")
        self.emit(depth, f"rt.set_parameter({s.name!r}, {index}, {value})")

    def s_Speed(self, s: ast.Speed, depth: int) -> None:
        value, rotation = self.checked(s.value, "_real", "SPEED"), self.checked(s.rotation, "_real", "SPEED")
        self.emit(depth, f"rt.set_speed({value}, {rotation}, {tuple(s.modifiers)!r})")

    def argument_count(self, name: str, args: list, fewest: int, most: int) -> None:
        if not fewest <= len(args) <= most or any(a is None for a in args[:fewest]):
            raise self.error(self.current, msg.INVALID_ARGUMENT,
                             f"{name} takes {fewest}{'' if most == fewest else f' to {most}'} argument(s)")

    def arguments(self, args: list) -> str:
        return ", ".join("None" if a is None else self.expr(a) for a in args)

    def s_Instruction(self, s: ast.Instruction, depth: int) -> None:
        name = s.name = self.keyword(s)
        if name in ("RETURN", "RETURNE"):  # RETURNE: an error trap goes on after the failed step
            self.emit_return(depth)
            return
        if name in ("EXIT", "NEXT"):
            self.loop_control(s, depth)
            return
        if name == "WAIT":
            if not s.args:  # sleep until the next major cycle ([000] L1435-1437)
                self.emit(depth, "yield rt.NEXT_CYCLE")
                return
            # WAIT expr: "a release to anyone if the expression is FALSE" ([000] L1437-1438).
            self.emit(depth, f"while not {self.condition(s.args[0])}:")
            self.emit(depth + 1, "yield rt.RELEASE")
            return
        if name in ("REACT", "REACTI", "REACTE"):
            self.reaction(s, depth)
            return
        if name in _TASK_INSTRUCTIONS:
            method, waits, fewest, most = _TASK_INSTRUCTIONS[name]
            self.argument_count(name, s.args, fewest, most)
            call = f"rt.{method}({self.arguments(s.args)})"
            self.emit(depth, f"yield from {call}" if waits else call)
            return
        spec = INSTRUCTIONS.get(name)
        if spec is None:
            raise self.error(s, msg.UNKNOWN_KEYWORD, name)
        if not spec.names:
            fewest, most = arity(spec.function)
            self.argument_count(name, s.args, fewest, most)
            if s.always and "always" not in inspect.signature(spec.function).parameters:
                raise self.error(s, msg.INVALID_ARGUMENT, f"{name} does not take ALWAYS")
        if spec.names:  # CPON ALWAYS: ALWAYS is one of the names
            args = ", ".join([*(repr(a.name.upper()) for a in s.args if isinstance(a, ast.Var)),
                              *(["'ALWAYS'"] if s.always else [])])
        else:  # DURATION 0.5 ALWAYS, ACCEL (1) 50, 50
            args = ", ".join(([self.checked_arguments(name, spec.function, s.args)] if s.args else [])
                             + (["always=True"] if s.always else [])
                             + ([self.parenthesised(s, spec.function)] if s.parenthesised is not None else []))
        call = f"I[{name!r}](rt{', ' if args else ''}{args})"
        self.emit(depth, f"yield from {call}" if spec.waits else call)


    def parenthesised(self, s: ast.Instruction, function) -> str:
        """ACCEL (profile) ..., ALTON (lun) ...: the parenthesised argument goes to the
        keyword's keyword-only parameter besides ALWAYS (a real)."""
        names = [p.name for p in inspect.signature(function).parameters.values()
                 if p.kind is p.KEYWORD_ONLY and p.name != "always"]
        if not names:
            raise self.error(s, msg.SYNTAX_ERROR, f"{s.name} takes no parenthesised argument")
        return f"{names[0]}={self.checked(s.parenthesised, '_real', s.name)}"

    def keyword(self, s: ast.Instruction) -> str:
        """An instruction's full name.  Like the V+ editor, which expands
        abbreviations when it closes a line ([000] L2583, L2593), a unique
        beginning of an instruction keyword (at least two letters) stands
        for it: SIGN 1 is SIGNAL 1."""
        if s.name in _INSTRUCTION_NAMES or s.name in INSTRUCTIONS or len(s.name) < 2:
            return s.name
        matches = sorted({n for n in [*_INSTRUCTION_NAMES, *INSTRUCTIONS] if n.startswith(s.name)})
        if len(matches) == 1:
            return matches[0]
        detail = f"{s.name} (could be {', '.join(matches)})" if matches else s.name
        raise self.error(s, msg.UNKNOWN_KEYWORD, detail)

    def reaction(self, s: ast.Instruction, depth: int) -> None:
        """REACT[I] signal, program(args)[, priority] and REACTE program: the
        program is named, not evaluated; its arguments are passed by value."""
        position = 0 if s.name == "REACTE" else 1
        if len(s.args) <= position or s.args[position] is None:
            if s.name == "REACTE":  # REACTE alone: no error trap any more
                self.emit(depth, "rt.react_error(None)")
                return
            if s.name == "REACTI" and s.args and s.args[0] is not None:
                # REACTI signal alone: the robot stops when the signal changes; no routine is called.
                priority = "None" if len(s.args) < 3 or s.args[2] is None else self.expr(s.args[2])
                self.emit(depth, f"rt.react({self.expr(s.args[0])}, None, [], {priority}, immediate=True)")
                return
            raise self.error(s, msg.INVALID_ARGUMENT, f"{s.name} needs a program")
        target = s.args[position]
        if isinstance(target, ast.Var) and target.indices is None:
            name, args = target.name, []
        elif isinstance(target, ast.Call):
            name, args = normalize_name(target.name), target.args
        else:
            raise self.error(s, msg.INVALID_ARGUMENT, f"{s.name} needs a program name")
        if s.name == "REACTE":
            self.emit(depth, f"rt.react_error({name!r})")
            return
        rest = s.args[2:]
        priority = "None" if not rest or rest[0] is None else self.expr(rest[0])
        signal = self.expr(s.args[0]) if s.args[0] is not None else "None"
        self.emit(depth, f"rt.react({signal}, {name!r}, [{self.arguments(args)}], {priority}, "
                         f"immediate={s.name == 'REACTI'})")

    def s_MonitorCommand(self, s: ast.MonitorCommand, depth: int) -> None:
        self.emit(depth, f"rt.monitor_command({s.command!r}, {s.text!r})")

    def s_ExecuteProgram(self, s: ast.ExecuteProgram, depth: int) -> None:
        """EXECUTE [task] program(args)[, cycles[, step]]: arguments by value."""
        task = "None" if s.task is None else self.expr(s.task)
        options = self.arguments(s.options)
        self.emit(depth, f"rt.execute({task}, {s.name!r}, [{self.arguments(s.args)}]"
                         f"{', ' if options else ''}{options})")


def compile_program(program: ast.Program, flat: bool = False) -> CompiledProgram:
    """`flat`: lower every IF/FOR/WHILE/DO/CASE to jumps, for programs whose
    loops nest deeper than Python allows its own blocks (20, try included)."""
    compiler = ProgramCompiler(program, flat)
    try:
        return compiler.compile()
    except RecursionError:  # an expression nested deeper than this compiler recurses
        raise compiler.error(compiler.current, msg.SYNTAX_ERROR, "expression too complicated") from None
