"""The V+ abstract syntax tree: plain dataclasses, in the spirit of CPython's `ast`.

The parser produces one `Statement` per source line; `structure.py` then nests
the block statements (IF, FOR, WHILE, DO, CASE) into their bodies.  Every
statement knows its file line, column and V+ step number (1 is the .PROGRAM
line, as the controller numbers steps) so run-time errors point at the source.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Union


# ------------------------------------------------------------------ expressions
@dataclass
class Num:
    value: float
    double: bool = False  # a ^D constant keeps double precision; others are single


@dataclass
class Str:
    value: str


@dataclass
class Var:
    """A variable reference.  `name` keeps its type prefix ($, #, %) and is
    lower case and truncated to the 15 significant characters V+ keeps.
    `indices` is None for a scalar, [] for a whole array (`a[]`)."""

    name: str
    indices: list["Expr"] | None = None
    # Written in parentheses, "(x)": passed to a CALL by value, not by reference.
    parenthesized: bool = False


@dataclass
class Call:
    """A function call (SIG(1001), $ERROR(-504), INVERSE(a)) or a bare
    function keyword that takes no arguments (TRUE, PI, HERE)."""

    name: str
    args: list["Expr | None"]


@dataclass
class ByCall:
    """The functions with a BY clause: SHIFT(loc BY dx, dy, dz), SCALE(loc BY k)."""

    name: str
    subject: "Expr"
    args: list["Expr"]


@dataclass
class Binary:
    op: str  # upper-case V+ operator: + - * / MOD AND OR XOR BAND BOR BXOR == <> < <= > >=
    left: "Expr"
    right: "Expr"


@dataclass
class Unary:
    op: str  # "-", "NOT", "COM"
    operand: "Expr"


@dataclass
class Compound:
    """Relative transformation `a:b` (b expressed in a's frame)."""

    left: "Expr"
    right: "Expr"


Expr = Union[Num, Str, Var, Call, ByCall, Binary, Unary, Compound]


# ------------------------------------------------------------------- statements
@dataclass
class Statement:
    line: int = field(default=0, kw_only=True)
    column: int = field(default=0, kw_only=True)
    step: int = field(default=0, kw_only=True)
    label: int | None = field(default=None, kw_only=True)


@dataclass
class Assign(Statement):
    target: Var
    value: Expr


@dataclass
class SetLocation(Statement):
    target: Var
    value: Expr


@dataclass
class Declare(Statement):
    scope: str  # AUTO, LOCAL, GLOBAL
    double: bool
    names: list[tuple[Var, list[Expr] | None]]  # (variable, declared dimensions)
    kind: str | None = None  # REAL, DOUBLE, LOC, or None when no type is written


@dataclass
class IfGoto(Statement):
    condition: Expr
    target: int


@dataclass
class Goto(Statement):
    target: int


@dataclass
class CallProgram(Statement):
    name: str | None  # None for CALLS, whose name is the `name_expr` string
    args: list[Expr | None]
    name_expr: Expr | None = None


@dataclass
class TypeOut(Statement):
    items: list["Expr | Format"]


@dataclass
class Format:
    """A TYPE/WRITE format specifier such as /I0, /C2, /F8.3, /S."""

    code: str  # upper-case letter
    width: int | None
    decimals: int | None


@dataclass
class Prompt(Statement):
    text: Expr
    targets: list[Var]  # one string variable, or real variables (maybe none)


@dataclass
class Parameter(Statement):
    name: str  # upper case
    index: Expr | None
    value: Expr


@dataclass
class Speed(Statement):
    value: Expr
    rotation: Expr | None
    modifiers: list[str]  # ALWAYS, MONITOR, MMPS, IPS


@dataclass
class ExecuteProgram(Statement):
    """EXECUTE [task] program(args)[, cycles[, step]]."""

    task: Expr | None
    name: str
    args: list[Expr | None]
    options: list[Expr | None]  # cycles, step


@dataclass
class Instruction(Statement):
    """Any other keyword statement: MOVE pick, APPRO pick, 25, OPENI, SIGNAL 1 ..."""

    name: str  # upper case
    args: list[Expr | None]
    always: bool = False  # ended with ALWAYS: DURATION 0.5 ALWAYS, CPON ALWAYS
    parenthesised: "Expr | None" = None  # ACCEL (profile) accel, decel; ALTON (lun) mode


# Block statements, as built by structure.py.
@dataclass
class If(Statement):
    condition: Expr
    body: list[Statement]
    orelse: list[Statement]


@dataclass
class For(Statement):
    target: Var
    start: Expr
    stop: Expr
    step_by: Expr | None
    body: list[Statement]


@dataclass
class While(Statement):
    condition: Expr
    body: list[Statement]


@dataclass
class DoUntil(Statement):
    body: list[Statement]
    condition: Expr
    until: Statement | None = None  # the UNTIL step, where an error in the condition is located


@dataclass
class Case(Statement):
    subject: Expr
    cases: list[tuple[list[Expr], list[Statement]]]
    default: list[Statement] | None


# Block delimiters, as the parser emits them (one per line) before nesting.
@dataclass
class IfThen(Statement):
    condition: Expr


@dataclass
class Else(Statement):
    pass


@dataclass
class End(Statement):
    pass


@dataclass
class ForHead(Statement):
    target: Var
    start: Expr
    stop: Expr
    step_by: Expr | None


@dataclass
class WhileHead(Statement):
    condition: Expr


@dataclass
class DoHead(Statement):
    pass


@dataclass
class UntilTail(Statement):
    condition: Expr


@dataclass
class CaseHead(Statement):
    subject: Expr


@dataclass
class ValueClause(Statement):
    values: list[Expr]


@dataclass
class AnyClause(Statement):
    pass


@dataclass
class LabelOnly(Statement):
    """A step that holds only a label (a GOTO target)."""


# ------------------------------------------------------------------ containers
@dataclass
class Program:
    name: str
    params: list[Var]
    body: list[Statement]
    file: str
    line: int


@dataclass
class DataSection:
    kind: str  # LOCATIONS, REALS, STRINGS, DOUBLES
    lines: list[tuple[int, str]]  # (file line, text)
    file: str


@dataclass
class Module:
    """Everything one source file holds."""

    file: str
    programs: list[Program]
    data: list[DataSection]
    lines: list[str] = field(default_factory=list)  # the source text, for error messages


# ---------------------------------------------------- I/O and keyed statements
# (lang-library: the V+ function and instruction library, issue #3)
@dataclass
class IoStatement(Statement):
    """An instruction on a logical unit: ATTACH (lun, 4) "DISK", READ (lun) $x,
    WRITE (lun) "text", /S, FOPENR (lun) $name, GTYPE (glun) x, y, $s."""

    name: str  # upper case
    unit: list[Expr | None]  # what the parentheses hold: lun[, mode, record...]
    items: list["Expr | Format"]


@dataclass
class MonitorCommand(Statement):
    """An "MC" line of a command program that is not also a program instruction:
    MC LOAD file, MC ZERO ... (`command` upper case, `text` the whole command)."""

    command: str
    text: str


@dataclass
class KeyedAssign(Statement):
    """An instruction that assigns what it names: BITS 1, 8 = 255,
    DECOMPOSE parts[] = loc, SWITCH CP = SIG(1001), TIMER 1 = 0.
    SOLVE.ANGLES has more values after "=": loc, seed[], flags."""

    name: str  # upper case
    args: list[Expr | None]
    value: Expr
    more: list[Expr] = field(default_factory=list)  # the values after the first
