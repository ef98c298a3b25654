"""GPL abstract syntax: plain dataclasses made by parser.py from the lark tree.

Names keep their spelling for messages; lookups use `.key` (lower case), since
GPL names are case-insensitive (User Manual ch. 4, "Variable Declarations").
"""

from __future__ import annotations

from dataclasses import dataclass, field


class Named:
    """A node with a `name`: `key` is the name as lookups compare it."""

    name: str

    @property
    def key(self) -> str:
        return self.name.lower()


# ----------------------------------------------------------------- expressions
class Expr:
    line: int = 0
    column: int = 0


@dataclass
class Literal(Expr):
    value: object  # int, float, str, bool


@dataclass
class Nothing(Expr):
    pass


@dataclass
class Evaluated(Expr):
    """Made by the compiler, not the parser: a value already computed into a Python
    temporary (`a(f()) += 1` evaluates f() once)."""

    code: str = ""
    type: object = None


@dataclass
class Me(Expr):
    pass


@dataclass
class Name(Expr, Named):
    name: str
    line: int = 0
    column: int = 0


@dataclass
class Member(Expr, Named):
    obj: Expr
    name: str
    line: int = 0
    column: int = 0


@dataclass
class Call(Expr):
    func: Expr
    args: list[Expr]
    line: int = 0
    column: int = 0


@dataclass
class New(Expr):
    type: "TypeRef"
    args: list[Expr] | None
    line: int = 0
    column: int = 0


@dataclass
class Omitted(Expr):
    """An argument left out, `New Thread("Worker", , "w1")`: a built-in member's optional one."""

    line: int = 0
    column: int = 0


@dataclass
class AddressOf(Expr):
    target: Expr
    line: int = 0
    column: int = 0


@dataclass
class Binary(Expr):
    op: str  # lower case: + - * / \ mod ^ << >> & = <> < > <= >= is and andalso or orelse xor
    left: Expr
    right: Expr


@dataclass
class Unary(Expr):
    op: str  # "-" or "not"
    operand: Expr


# ------------------------------------------------------------------- types
@dataclass
class TypeRef:
    parts: list[str]  # ["Integer"], ["MyMod", "My_class"]
    rank: int = 0  # 0: scalar; n: an n-dimensional array

    @property
    def key(self) -> str:
        return ".".join(p.lower() for p in self.parts)

    def __str__(self) -> str:
        return ".".join(self.parts) + ("(" + "," * (self.rank - 1) + ")" if self.rank else "")


# -------------------------------------------------------------- statements
@dataclass
class Statement:
    line: int
    column: int


@dataclass
class Declarator(Named):
    name: str
    bounds: list[Expr | None] | None  # None: not an array; [None, None]: Dim a(,)
    type: TypeRef | None
    new: bool
    ctor_args: list[Expr] | None
    init: Expr | None
    line: int = 0
    column: int = 0


@dataclass
class Declare(Statement):
    modifiers: list[str]  # lower case: dim static const public private shared
    items: list[Declarator]


@dataclass
class Assign(Statement):
    target: Expr
    op: str  # "=" or a compound operator "+=" ...
    value: Expr


@dataclass
class CallStatement(Statement):
    expr: Expr


@dataclass
class Label(Statement):
    name: str  # lower case


@dataclass
class Goto(Statement):
    label: str  # lower case


@dataclass
class Exit(Statement):
    kind: str  # sub function for while do select try property


@dataclass
class Continue(Statement):
    kind: str


@dataclass
class Return(Statement):
    value: Expr | None


@dataclass
class Throw(Statement):
    value: Expr | None


@dataclass
class ReDim(Statement):
    targets: list[Expr]
    preserve: bool = False


@dataclass
class If(Statement):
    branches: list[tuple[Expr, list[Statement]]]
    orelse: list[Statement] | None


@dataclass
class For(Statement):
    var: Expr
    start: Expr
    stop: Expr
    step: Expr | None
    body: list[Statement]
    var_type: TypeRef | None = None  # VB.NET's `For i As Integer = ...` declares i


@dataclass
class While(Statement):
    condition: Expr
    body: list[Statement]


@dataclass
class Do(Statement):
    pre: tuple[str, Expr] | None  # ("while"|"until", condition) after Do
    post: tuple[str, Expr] | None  # after Loop
    body: list[Statement]


@dataclass
class CaseTest:
    kind: str  # "value", "range", "is"
    op: str
    low: Expr
    high: Expr | None = None


@dataclass
class Select(Statement):
    subject: Expr
    cases: list[tuple[list[CaseTest], list[Statement]]]
    default: list[Statement] | None


@dataclass
class Try(Statement):
    body: list[Statement]
    catch_var: str | None
    catch_body: list[Statement] | None
    finally_body: list[Statement] | None
    catch_type: TypeRef | None = None  # VB.NET's `Catch e As Exception` declares e


# ----------------------------------------------------------------- members
@dataclass
class Param(Named):
    name: str
    byref: bool
    type: TypeRef | None


@dataclass
class Procedure(Named):
    kind: str  # "sub" or "function"
    name: str
    params: list[Param]
    return_type: TypeRef | None
    body: list[Statement]
    modifiers: list[str]
    line: int
    column: int = 1


@dataclass
class Property(Named):
    name: str
    params: list[Param]
    type: TypeRef
    getter: list[Statement] | None
    setter_param: Param | None
    setter: list[Statement] | None
    modifiers: list[str]
    line: int
    column: int = 1


@dataclass
class DelegateDecl(Named):
    kind: str
    name: str
    params: list[Param]
    return_type: TypeRef | None
    modifiers: list[str]
    line: int
    column: int = 1


@dataclass
class ClassDecl(Named):
    name: str
    modifiers: list[str]
    members: list
    line: int
    column: int = 1


@dataclass
class Module(Named):
    name: str
    members: list
    file: str
    line: int = 1
    implicit: bool = False  # members found at the top of a file, outside any Module


@dataclass
class SourceFile:
    path: str
    modules: list[Module] = field(default_factory=list)
