"""The symbol tables of a GPL project: modules, classes, procedures, variables,
delegates, and the static types the compiler tracks.

GPL is strongly typed (User Manual ch. 4: every variable is declared with its
type), so the compiler knows the type of most expressions and resolves member
access and conversions at compile time; where it cannot (the result of a
built-in method whose class the library does not declare), generated code
looks the member up at run time.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from . import ast

BASIC = ("integer", "short", "byte", "single", "double", "boolean", "string")
INTEGRAL = ("integer", "short", "byte")
NUMBERS = ("integer", "short", "byte", "single", "double")


@dataclass(frozen=True)
class SType:
    """A static type: a basic type, a user class, a built-in class, a delegate
    class, Nothing or a namespace (a module or class name used as a prefix)."""

    base: str  # a BASIC name, "user", "lib", "delegate", "nothing", "ns"
    ref: object = None  # ClassSym, library class, DelegateSym, or the namespace symbol
    rank: int = 0

    @property
    def element(self) -> "SType":
        return SType(self.base, self.ref, 0)

    @property
    def is_array(self) -> bool:
        return self.rank > 0

    @property
    def is_number(self) -> bool:
        return self.rank == 0 and self.base in NUMBERS

    @property
    def is_integral(self) -> bool:
        return self.rank == 0 and self.base in INTEGRAL

    @property
    def is_bool(self) -> bool:
        return self.rank == 0 and self.base == "boolean"

    @property
    def is_string(self) -> bool:
        return self.rank == 0 and self.base == "string"

    def __str__(self) -> str:
        name = {"user": lambda: self.ref.name, "lib": lambda: self.ref.gpl_name,
                "delegate": lambda: self.ref.name}.get(self.base, lambda: self.base.capitalize())()
        return name + ("()" if self.rank else "")


def ns(symbol) -> SType:
    return SType("ns", symbol)


@dataclass
class VarSym:
    name: str
    type: SType
    kind: str  # "module", "shared", "field", "local", "static", "param"
    py: str  # the Python name (global, local or attribute)
    const: bool = False
    public: bool = False
    byref: bool = False
    decl: ast.Declarator | None = None
    owner: object = None  # ModuleSym or ClassSym

    @property
    def key(self) -> str:
        return self.name.lower()


@dataclass
class ProcSym:
    name: str
    kind: str  # "sub", "function"
    params: list[ast.Param]
    param_types: list[SType]
    return_type: SType | None
    py: str
    module: "ModuleSym"
    cls: "ClassSym | None"
    shared: bool
    public: bool
    node: ast.Procedure | None

    @property
    def key(self) -> str:
        return self.name.lower()

    @property
    def byref_positions(self) -> list[int]:
        """ByRef parameters receive a reference object (`.value`), see expressions.reference."""
        return [i for i, p in enumerate(self.params) if p.byref]

    @property
    def instance(self) -> bool:
        return self.cls is not None and not self.shared

    @property
    def qualified(self) -> str:
        owner = self.cls.name if self.cls else self.module.name
        return f"{owner}.{self.name}"


@dataclass
class PropSym:
    name: str
    type: SType
    params: list[ast.Param]
    getter_py: str | None
    setter_py: str | None
    cls: "ClassSym"
    shared: bool
    public: bool
    node: ast.Property

    @property
    def key(self) -> str:
        return self.name.lower()


@dataclass
class DelegateSym:
    name: str
    kind: str
    params: list[ast.Param]
    return_type: ast.TypeRef | None
    module: "ModuleSym"
    public: bool

    @property
    def key(self) -> str:
        return self.name.lower()


@dataclass
class ClassSym:
    name: str
    module: "ModuleSym"
    py: str
    public: bool
    node: ast.ClassDecl
    parent: "ClassSym | None" = None
    fields: dict[str, VarSym] = field(default_factory=dict)
    methods: dict[str, ProcSym] = field(default_factory=dict)
    constructors: list[ProcSym] = field(default_factory=list)
    properties: dict[str, PropSym] = field(default_factory=dict)
    classes: dict[str, "ClassSym"] = field(default_factory=dict)
    delegates: dict[str, DelegateSym] = field(default_factory=dict)

    @property
    def key(self) -> str:
        return self.name.lower()

    def member(self, key: str):
        for table in (self.fields, self.methods, self.properties, self.classes, self.delegates):
            if key in table:
                return table[key]
        return None


@dataclass
class ModuleSym:
    name: str
    file: str
    node: ast.Module
    vars: dict[str, VarSym] = field(default_factory=dict)
    procs: dict[str, ProcSym] = field(default_factory=dict)
    classes: dict[str, ClassSym] = field(default_factory=dict)
    delegates: dict[str, DelegateSym] = field(default_factory=dict)

    @property
    def key(self) -> str:
        return self.name.lower()

    def member(self, key: str):
        for table in (self.vars, self.procs, self.classes, self.delegates):
            if key in table:
                return table[key]
        return None


def is_public(symbol) -> bool:
    return getattr(symbol, "public", True)
