"""GPL AST -> Python: every procedure becomes one Python generator function.

As for V+ (twin/language/vplus/compiler.py), generated Python runs several
times faster than a tree walker and Python generators make GPL threads
cooperative tasks: a member that waits (Move.WaitForEOM, Thread.Sleep) is run
with `yield from`, and so is every call of a GPL procedure.

Storage (User Manual ch. 4 and 10):
  * procedure locals (Dim) and parameters -> Python locals, all initialised
    when the procedure starts (a local's scope is the whole procedure);
  * module variables, Static locals and Shared class fields -> globals of the
    project's one Python namespace (`V_module__name`), shared by all threads;
  * object fields -> attributes `f_name` of the object.
Calls: `P_module__proc(rt, [me,] args...)`; a procedure with ByRef parameters
returns `(result, (final values of its ByRef parameters))` and the caller
writes those back (value-result: the same as passing a reference to a
program that does not share the variable with another thread in mid-call).
GoTo: a statement list that holds labels is compiled as a dispatch loop over
its segments, and GoTo raises `_Jump(block, segment)` caught there.
Each generated line maps back to its GPL statement, for errors.
"""

from __future__ import annotations

import inspect
from dataclasses import dataclass

from ...errors import ProgramError
from . import ast
from .builtins import FUNCTION_TYPES, FUNCTIONS, STRING_MEMBERS, STRING_SHARED
from .errors import (
    AMBIGUOUS_SYMBOL, CONSTANT_ASSIGNMENT, DUPLICATE_SYMBOL, ILLEGAL_GOTO, INVALID_STATEMENT,
    PRIVATE_SYMBOL, TYPE_MISMATCH, UNDEFINED_SYMBOL, UNSUPPORTED, WRONG_ARGUMENT_COUNT, message,
)
from .library import CLASSES, member as library_member
from .symbols import (
    BASIC, ClassSym, DelegateSym, ModuleSym, ProcSym, PropSym, SType, VarSym, is_public, ns,
)
from .values import CONVERT, DEFAULTS

SLICE_ITERATIONS = 1024  # loop iterations between time slices, as for V+ tasks

# Predefined constants (ch. 4, Table 4-4).
CONSTANTS = {
    "gpl_cr": ("'\\r'", "string"), "gpl_lf": ("'\\n'", "string"),
    "gpl_righty": ("1", "integer"), "gpl_lefty": ("2", "integer"), "gpl_above": ("4", "integer"),
    "gpl_below": ("8", "integer"), "gpl_flip": ("16", "integer"), "gpl_noflip": ("32", "integer"),
    "gpl_single": ("4096", "integer"),
}
UNSUPPORTED_TYPES = {"long", "int64", "decimal", "int16", "int32", "char", "variant", "date"}


def mangle(*parts: str) -> str:
    return "__".join(p.lower() for p in parts)


@dataclass
class CompiledUnit:
    """One generated Python function and where its lines came from."""

    name: str  # GPL name for messages: Module.Proc
    py: str
    source: str
    line_map: dict[int, tuple[int, int]]  # generated line -> (GPL line, column)
    file: str


@dataclass
class CompiledProject:
    units: list[CompiledUnit]
    modules: list[ModuleSym]
    classes: list[ClassSym]
    init_units: list[str]  # module initialisers (py names), in load order
    init_subs: list[str]  # user Init subs, in load order
    public_procs: dict[str, ProcSym]  # "proc", "module.proc", "class.proc" -> symbol
    statics: dict[str, object]  # global name -> initial value


def _error(code: int, detail: str, file: str, node, program: str | None = None) -> ProgramError:
    return ProgramError(
        f"{message(code)}: {detail}" if detail else message(code), code, file=file,
        line=getattr(node, "line", None) or None, column=getattr(node, "column", None) or None,
        program=program,
    )


def _library_kind(cls: type, attr: str) -> str:
    raw = inspect.getattr_static(cls, attr)
    if isinstance(raw, property):
        return "property"
    if isinstance(raw, staticmethod):
        return "shared"
    return "method"


def _library_function(cls: type, attr: str):
    raw = inspect.getattr_static(cls, attr)
    if isinstance(raw, (staticmethod, classmethod)):
        return raw.__func__
    if isinstance(raw, property):
        return raw.fget
    return raw


def library_waits(cls: type, attr: str) -> bool:
    return inspect.isgeneratorfunction(_library_function(cls, attr))


def library_byref(cls: type, attr: str) -> frozenset:
    return getattr(_library_function(cls, attr), "gpl_byref", frozenset())


def waiting_library_names() -> set[str]:
    names = set()
    for cls in CLASSES.values():
        for key, attr in cls.gpl_members.items():
            if library_waits(cls, attr):
                names.add(key)
    return names


class ProjectCompiler:
    """Builds the symbol tables of all files, then compiles every procedure."""

    def __init__(self, files: list[ast.SourceFile]):
        self.files = files
        self.modules: dict[str, ModuleSym] = {}
        self.module_order: list[ModuleSym] = []
        self.classes: list[ClassSym] = []
        self.units: list[CompiledUnit] = []
        self.statics: dict[str, object] = {}
        self.public_procs: dict[str, ProcSym] = {}
        self.waiting = waiting_library_names()

    # ------------------------------------------------------------ declaration pass
    def compile(self) -> CompiledProject:
        declared = {m.key for source in self.files for m in source.modules if not m.implicit}
        for source in self.files:
            for module in source.modules:
                while module.implicit and module.key in declared | set(self.modules):
                    module.name += "_"  # top-of-file items of Bench.gpl beside a Module Bench
                if module.key in self.modules:
                    raise _error(DUPLICATE_SYMBOL, f"module {module.name}", source.path, module)
                sym = ModuleSym(module.name, source.path, module)
                self.modules[module.key] = sym
                self.module_order.append(sym)
        for sym in self.module_order:
            self.declare_members(sym, None, sym.node.members)
        for sym in self.module_order:
            self.type_variables(sym)
        for cls in self.classes:
            self.waiting.update(cls.methods)
            self.waiting.update(cls.properties)
        init_units, init_subs = [], []
        for sym in self.module_order:
            init_units.append(self.compile_module_init(sym))
            init = sym.procs.get("init")
            if init is not None:
                init_subs.append(init.py)
        for cls in self.classes:
            self.compile_class_init(cls)
        for sym in self.module_order:
            for proc in sym.procs.values():
                self.compile_procedure(proc)
        for cls in self.classes:
            for proc in [*cls.methods.values(), *cls.constructors]:
                self.compile_procedure(proc)
            for prop in cls.properties.values():
                self.compile_property(prop)
        return CompiledProject(
            self.units, self.module_order, self.classes, init_units, init_subs, self.public_procs, self.statics,
        )

    def declare_members(self, module: ModuleSym, cls: ClassSym | None, members: list) -> None:
        owner = cls or module
        prefix = cls.py if cls else mangle(module.name)
        file = module.file

        def check_new(key: str, node) -> None:
            if owner.member(key) is not None and key != "new":
                raise _error(DUPLICATE_SYMBOL, node.name if hasattr(node, "name") else key, file, node)

        for m in members:
            mods = getattr(m, "modifiers", [])
            # Items written at the top of a file, outside any Module (as the
            # manual's examples do), are Public: `Sub Main()` can start a project.
            public = "public" in mods or (module.node.implicit and cls is None and "private" not in mods)
            shared = "shared" in mods
            if isinstance(m, ast.Declare):
                for d in m.items:
                    check_new(d.key, d)
                    const = "const" in m.modifiers
                    if cls is not None and not shared and not const:
                        var = VarSym(d.name, SType("nothing"), "field", f"f_{d.key}", const, public, decl=d, owner=cls)
                        cls.fields[d.key] = var
                    else:
                        kind = "shared" if cls is not None else "module"
                        var = VarSym(d.name, SType("nothing"), kind, f"V_{prefix}__{d.key}", const, public,
                                     decl=d, owner=owner)
                        (cls.fields if cls else module.vars)[d.key] = var
            elif isinstance(m, ast.Procedure):
                if m.key in ("_init", "_new"):
                    raise _error(DUPLICATE_SYMBOL, f"{m.name} is reserved", file, m)
                if cls is not None and m.key == "new":
                    proc = ProcSym(m.name, "sub", m.params, [], None,
                                   f"P_{prefix}__new{len(cls.constructors)}", module, cls, False, True, m)
                    cls.constructors.append(proc)
                    continue
                check_new(m.key, m)
                proc = ProcSym(m.name, m.kind, m.params, [], None, f"P_{prefix}__{m.key}", module, cls,
                               shared, public, m)
                if cls is not None:
                    cls.methods[m.key] = proc
                    if shared and public and cls.parent is None:
                        self.public_procs[f"{cls.key}.{m.key}"] = proc
                        self.public_procs.setdefault(m.key, proc)
                else:
                    module.procs[m.key] = proc
                    if public:
                        self.public_procs[f"{module.key}.{m.key}"] = proc
                        self.public_procs.setdefault(m.key, proc)
            elif isinstance(m, ast.Property):
                if cls is None:
                    raise _error(INVALID_STATEMENT, "a Property must be inside a Class", file, m)
                check_new(m.key, m)
                cls.properties[m.key] = PropSym(
                    m.name, SType("nothing"), m.params,
                    f"G_{prefix}__{m.key}" if m.getter is not None else None,
                    f"S_{prefix}__{m.key}" if m.setter is not None else None,
                    cls, shared, public, m,
                )
            elif isinstance(m, ast.ClassDecl):
                check_new(m.key, m)
                sub = ClassSym(m.name, module, f"C_{prefix}__{m.key}", public, m, parent=cls)
                (cls.classes if cls else module.classes)[m.key] = sub
                self.classes.append(sub)
                self.declare_members(module, sub, m.members)
            elif isinstance(m, ast.DelegateDecl):
                check_new(m.key, m)
                (cls.delegates if cls else module.delegates)[m.key] = DelegateSym(
                    m.name, m.kind, m.params, m.return_type, module, public)

    def type_variables(self, module: ModuleSym) -> None:
        """Resolve declared types once every class is known."""
        scope = Scope(self, module, None)
        self._type_table(scope, module.vars.values())
        for proc in module.procs.values():
            self._type_proc(scope, proc)
        for cls in self.classes:
            if cls.module is module:
                cscope = Scope(self, module, cls)
                self._type_table(cscope, cls.fields.values())
                for proc in [*cls.methods.values(), *cls.constructors]:
                    self._type_proc(cscope, proc)
                for prop in cls.properties.values():
                    prop.type = cscope.resolve_type(prop.node.type, prop.node)

    def _type_table(self, scope: "Scope", variables) -> None:
        for var in variables:
            var.type = scope.declarator_type(var.decl)

    def _type_proc(self, scope: "Scope", proc: ProcSym) -> None:
        node = proc.node
        proc.param_types = [scope.param_type(p, node) for p in proc.params]
        if proc.kind == "function":
            proc.return_type = scope.resolve_type(node.return_type, node) if node.return_type else SType("double")

    # ------------------------------------------------------------ generation
    def compile_module_init(self, module: ModuleSym) -> str:
        """_Init: module variables in source order (ch. 10 "Special Initialization")."""
        gen = ProcCompiler(self, module, None, None, f"I_{mangle(module.name)}", f"{module.name}._Init")
        gen.begin_init()
        for var in module.vars.values():
            gen.init_variable(var, global_store=True)
        for cls in self.classes:
            if cls.module is module:
                for var in cls.fields.values():
                    if var.kind == "shared":
                        gen.init_variable(var, global_store=True)
        gen.finish()
        return gen.py

    def compile_class_init(self, cls: ClassSym) -> None:
        """_New: the fields of a new object, then the matching constructor."""
        gen = ProcCompiler(self, cls.module, None, cls, f"N_{cls.py}", f"{cls.name}._New")
        gen.begin_new_object()
        for var in cls.fields.values():
            if var.kind == "field":
                gen.init_variable(var, global_store=False)
        gen.finish_new_object()

    def compile_procedure(self, proc: ProcSym) -> None:
        gen = ProcCompiler(self, proc.module, proc, proc.cls, proc.py, proc.qualified)
        gen.compile_procedure()

    def compile_property(self, prop: PropSym) -> None:
        node = prop.node
        for accessor in ("get", "set"):
            body = node.getter if accessor == "get" else node.setter
            if body is None:
                continue
            params = list(node.params)
            if accessor == "set":
                params.append(node.setter_param or ast.Param("value", False, node.type))
            fake = ProcSym(
                prop.name, "function" if accessor == "get" else "sub", params, [], prop.type if accessor == "get" else None,
                prop.getter_py if accessor == "get" else prop.setter_py, prop.cls.module, prop.cls, prop.shared,
                prop.public, ast.Procedure("function" if accessor == "get" else "sub", prop.name, params,
                                           node.type, body, node.modifiers, node.line, node.column),
            )
            scope = Scope(self, prop.cls.module, prop.cls)
            fake.param_types = [scope.param_type(p, node) for p in params]
            gen = ProcCompiler(self, prop.cls.module, fake, prop.cls, fake.py, f"{prop.cls.name}.{prop.name}")
            gen.compile_procedure()


class Scope:
    """Name and type resolution from one place in the project."""

    def __init__(self, project: ProjectCompiler, module: ModuleSym, cls: ClassSym | None):
        self.project = project
        self.module = module
        self.cls = cls

    def fail(self, code: int, detail: str, node) -> ProgramError:
        return _error(code, detail, self.module.file, node)

    # ---- types
    def resolve_type(self, ref: ast.TypeRef | None, node) -> SType:
        if ref is None:
            raise self.fail(TYPE_MISMATCH, "the data type must be specified (As type)", node)
        key = ref.key
        if key in BASIC:
            return SType(key, None, ref.rank)
        if key == "object":
            raise self.fail(UNSUPPORTED, "As Object: every object needs an explicit class (ch. 5)", node)
        if key in UNSUPPORTED_TYPES:
            raise self.fail(UNSUPPORTED, f"data type {ref.parts[-1]} (ch. 4, Table 4-2)", node)
        target = self.lookup_path([p.lower() for p in ref.parts], node, types_only=True)
        if isinstance(target, ClassSym):
            return SType("user", target, ref.rank)
        if isinstance(target, DelegateSym):
            return SType("delegate", target, ref.rank)
        if isinstance(target, type):
            return SType("lib", target, ref.rank)
        raise self.fail(UNDEFINED_SYMBOL, f"type {'.'.join(ref.parts)}", node)

    def declarator_type(self, d: ast.Declarator) -> SType:
        if d.type is None:
            raise self.fail(TYPE_MISMATCH, f"{d.name}: the data type must be specified (As type)", d)
        base = self.resolve_type(d.type, d)
        rank = len(d.bounds) if d.bounds is not None else 0
        return SType(base.base, base.ref, rank)

    def param_type(self, p: ast.Param, node) -> SType:
        if p.type is None:
            raise self.fail(TYPE_MISMATCH, f"parameter {p.name}: the data type must be specified", node)
        return self.resolve_type(p.type, node)

    # ---- names
    def lookup_path(self, parts: list[str], node, types_only: bool = False):
        first = self.lookup(parts[0], node, types_only)
        for part in parts[1:]:
            first = self.member_of_namespace(first, part, node)
        return first

    def lookup(self, key: str, node, types_only: bool = False):
        """A name seen from this scope (ch. 4 "Scope of Names"), or None."""
        cls = self.cls
        while cls is not None:
            found = cls.member(key)
            if found is not None and not (types_only and not isinstance(found, (ClassSym, DelegateSym))):
                return found
            if key == cls.key:
                return cls
            cls = cls.parent
        found = self.module.member(key)
        if found is not None:
            return found
        if key in self.project.modules:
            return self.project.modules[key]
        candidates = [m.member(key) for m in self.project.module_order if m is not self.module]
        candidates = [c for c in candidates if c is not None and is_public(c)]
        if len(candidates) > 1:
            raise self.fail(AMBIGUOUS_SYMBOL, key, node)
        if candidates:
            return candidates[0]
        for module in self.project.module_order:  # a public class's classes, by name
            for c in module.classes.values():
                if c.key == key and (c.public or module is self.module):
                    return c
        if key in CLASSES:
            return CLASSES[key]
        return None

    def member_of_namespace(self, owner, key: str, node):
        if isinstance(owner, (ModuleSym, ClassSym)):
            found = owner.member(key)
            if found is None:
                raise self.fail(UNDEFINED_SYMBOL, f"{owner.name}.{key}", node)
            if not is_public(found) and not self.inside(owner):
                raise self.fail(PRIVATE_SYMBOL, f"{owner.name}.{found.name}", node)
            return found
        raise self.fail(UNDEFINED_SYMBOL, key, node)

    def inside(self, owner) -> bool:
        if isinstance(owner, ModuleSym):
            return owner is self.module
        cls = self.cls
        while cls is not None:
            if cls is owner:
                return True
            cls = cls.parent
        return False


@dataclass
class _Block:
    """A statement list with labels: compiled as a dispatch loop."""

    ident: int
    labels: dict[str, int]  # label -> segment
    boundary: bool = False  # a Try/Catch/Finally edge: GoTo may not cross it


@dataclass
class _Loop:
    kind: str  # "for", "while", "do", "select", "dispatch"
    ident: int
    step: tuple | None = None  # For: (var node, step name) for Continue For


def _has_labels(body: list[ast.Statement]) -> bool:
    return any(isinstance(s, ast.Label) for s in body)


def _contains(body: list, kinds: tuple) -> bool:
    """Whether any statement at any depth is one of `kinds`."""
    for s in body:
        if isinstance(s, kinds):
            return True
        for attr in ("body", "orelse", "catch_body", "finally_body", "default"):
            inner = getattr(s, attr, None)
            if isinstance(inner, list) and _contains(inner, kinds):
                return True
        if isinstance(s, ast.If) and any(_contains(b, kinds) for _, b in s.branches):
            return True
        if isinstance(s, ast.Select) and any(_contains(b, kinds) for _, b in s.cases):
            return True
    return False


class ProcCompiler(Scope):
    """Generates one Python function."""

    def __init__(self, project: ProjectCompiler, module: ModuleSym, proc: ProcSym | None,
                 cls: ClassSym | None, py: str, gpl_name: str):
        super().__init__(project, module, cls)
        self.proc = proc
        self.py = py
        self.gpl_name = gpl_name
        self.lines: list[str] = []
        self.line_map: dict[int, tuple[int, int]] = {}
        self.locals: dict[str, VarSym] = {}
        self.globals_assigned: set[str] = set()
        self.temp = 0
        self.node = None  # the statement being compiled
        self.blocks: list[_Block | None] = []
        self.loops: list[_Loop] = []
        self.try_depth = 0
        self.me_available = proc is not None and proc.instance
        self.depth = 1  # where hoisted code (ByRef write-backs) goes

    # ------------------------------------------------------------ output
    def emit(self, depth: int, text: str) -> None:
        self.lines.append("    " * depth + text)
        if self.node is not None and getattr(self.node, "line", 0):
            self.line_map[len(self.lines)] = (self.node.line, self.node.column)

    def fresh(self, stem: str) -> str:
        self.temp += 1
        return f"_{stem}{self.temp}"

    def fail(self, code: int, detail: str, node=None) -> ProgramError:
        return _error(code, detail, self.module.file, node or self.node, self.gpl_name)

    def finish(self, header_end: int = 1) -> None:
        if self.globals_assigned:
            self.lines.insert(header_end, "    global " + ", ".join(sorted(self.globals_assigned)))
            self.line_map = {(k + 1 if k > header_end else k): v for k, v in self.line_map.items()}
        self.project.units.append(CompiledUnit(self.gpl_name, self.py, "\n".join(self.lines) + "\n",
                                           self.line_map, self.module.file))

    # ------------------------------------------------------------ initialisers
    def begin_init(self) -> None:
        self.emit(0, f"def {self.py}(rt):")
        self.emit(1, "if False: yield")

    def begin_new_object(self) -> None:
        self.emit(0, f"def {self.py}(rt, _ctor, *_args):")
        self.emit(1, "if False: yield")
        self.emit(1, f"me = {self.cls.py}()")
        self.me_available = True

    def finish_new_object(self) -> None:
        self.emit(1, "if _ctor is not None:")
        self.emit(2, "yield from _ctor(rt, me, *_args)")
        self.emit(1, "return me")
        self.finish()

    def init_variable(self, var: VarSym, global_store: bool) -> None:
        d = var.decl
        self.node = d
        target = var.py if global_store else f"me.{var.py}"
        if global_store:
            self.globals_assigned.add(var.py)
        self.emit(1, f"{target} = {self.initial_value(var, d)}")

    def initial_value(self, var: VarSym, d: ast.Declarator) -> str:
        t = var.type
        if d.bounds is not None and any(b is not None for b in d.bounds):
            if d.init is not None:
                raise self.fail(UNSUPPORTED, "array initialisers (ch. 4, Data Type Arrays)", d)
            dims = ", ".join(self.index_code(b) if b is not None else "0" for b in d.bounds)
            return f"GplArray(({dims},), {self.default(t.element)!r})"
        if d.bounds is not None and d.init is None:
            return "None"
        if d.new:
            if d.init is not None:
                raise self.fail(INVALID_STATEMENT, "New may not appear both after As and after =", d)
            return self.new_object(ast.New(d.type, d.ctor_args, d.line, d.column))[0]
        if d.init is not None:
            code, vt = self.expr(d.init)
            return self.convert(code, vt, t)
        return repr(self.default(t))

    @staticmethod
    def default(t: SType):
        if t.rank:
            return None
        return DEFAULTS.get(t.base)

    # ------------------------------------------------------------ procedures
    def compile_procedure(self) -> None:
        proc = self.proc
        node = proc.node
        params = ["rt"] + (["me"] if proc.instance else [])
        for p, t in zip(proc.params, proc.param_types):
            var = VarSym(p.name, t, "param", f"a_{p.key}", byref=p.byref)
            if p.key in self.locals:
                raise self.fail(DUPLICATE_SYMBOL, p.name, node)
            self.locals[p.key] = var
            params.append(var.py)
        self.collect_locals(node.body)
        self.node = node
        self.emit(0, f"def {self.py}({', '.join(params)}):")
        self.emit(1, "if False: yield")
        for var, t in zip(params[len(params) - len(proc.params):], proc.param_types):
            if t.base in CONVERT and not t.rank:
                self.emit(1, f"{var} = {CONVERT[t.base]}({var})")
        for var in self.locals.values():
            if var.kind == "local":
                self.emit(1, f"{var.py} = {self.default(var.type)!r}")
        if proc.kind == "function":
            self.emit(1, f"_result = {self.default(proc.return_type)!r}")
        self.emit(1, "_slice = 0")
        self.block(node.body, 1)
        self.node = None
        self.emit(1, self.return_code(None))
        self.finish()

    def collect_locals(self, body: list[ast.Statement]) -> None:
        """Declarations are allowed at the outermost level only (ch. 4) and their
        scope is the whole procedure."""
        for s in body:
            if isinstance(s, ast.Declare):
                self.declare_locals(s)
            else:
                for inner in _nested_bodies(s):
                    if any(isinstance(x, ast.Declare) for x in inner):
                        bad = next(x for x in inner if isinstance(x, ast.Declare))
                        raise self.fail(INVALID_STATEMENT, "variables can only be declared in the outermost "
                                        "level of a procedure (ch. 4)", bad)

    def declare_locals(self, s: ast.Declare) -> None:
        for d in s.items:
            if d.key in self.locals:
                raise self.fail(DUPLICATE_SYMBOL, d.name, d)
            t = self.declarator_type(d)
            if "static" in s.modifiers:
                py = f"T_{mangle(self.py, d.key)}"
                self.project.statics[py] = None if t.rank else self.default(t)
                var = VarSym(d.name, t, "static", py, decl=d)
            else:
                var = VarSym(d.name, t, "local", f"l_{d.key}", const="const" in s.modifiers, decl=d)
            self.locals[d.key] = var

    def return_code(self, value: str | None) -> str:
        proc = self.proc
        result = value if value is not None else ("_result" if proc.kind == "function" else "None")
        byref = proc.byref_positions
        if byref:
            finals = ", ".join(f"a_{proc.params[i].key}" for i in byref)
            return f"return ({result}, ({finals},))"
        return f"return {result}" if result != "None" else "return"

    # ------------------------------------------------------------ statements
    def block(self, body: list[ast.Statement], depth: int, dispatch_var: str | None = None,
              boundary: bool = False) -> None:
        """A statement list; with labels, a dispatch loop (see the module docstring)."""
        if not _has_labels(body):
            self.blocks.append(_Block(-1, {}, boundary))
            if not any(not isinstance(s, (ast.Declare,)) for s in body):
                self.emit(depth, "pass")
            for s in body:
                self.statement(s, depth)
            self.blocks.pop()
            return
        segments: list[list[ast.Statement]] = [[]]
        labels: dict[str, int] = {}
        for s in body:
            if isinstance(s, ast.Label):
                if s.name in labels:
                    raise self.fail(DUPLICATE_SYMBOL, f"label {s.name}", s)
                segments.append([])
                labels[s.name] = len(segments) - 1
            segments[-1].append(s)
        ident = self.temp = self.temp + 1
        pc = dispatch_var or f"_pc{ident}"
        if dispatch_var is None:
            self.emit(depth, f"{pc} = 0")
        self.blocks.append(_Block(ident, labels, boundary))
        self.loops.append(_Loop("dispatch", ident))
        self.emit(depth, "while True:")
        self.emit(depth + 1, "try:")
        for i, segment in enumerate(segments):
            self.emit(depth + 2, f"if {pc} <= {i}:")
            self.emit(depth + 3, "pass")
            for s in segment:
                self.statement(s, depth + 3)
        self.emit(depth + 1, "except _Jump as _j:")
        self.emit(depth + 2, f"if _j.block != {ident}: raise")
        self.emit(depth + 2, f"{pc} = _j.segment")
        self.slice_check(depth + 2)
        self.emit(depth + 2, "continue")
        self.emit(depth + 1, "break")
        self.loops.pop()
        self.blocks.pop()

    def statement(self, s: ast.Statement, depth: int) -> None:
        self.node = s
        self.depth = depth
        handler = getattr(self, "s_" + type(s).__name__)
        handler(s, depth)

    def s_Label(self, s: ast.Label, depth: int) -> None:
        pass

    def s_Declare(self, s: ast.Declare, depth: int) -> None:
        for d in s.items:
            var = self.locals[d.key]
            if var.kind == "static":
                if d.init is not None or d.new or (d.bounds and any(b is not None for b in d.bounds)):
                    self.globals_assigned.add(var.py)
                    self.emit(depth, f"if {var.py} is None:" if var.type.rank or var.type.base not in BASIC
                              else "if False:")
                    self.emit(depth + 1, f"{var.py} = {self.initial_value(var, d)}")
                continue
            if d.init is None and not d.new and not (d.bounds and any(b is not None for b in d.bounds)):
                continue
            self.emit(depth, f"{var.py} = {self.initial_value(var, d)}")

    def s_Assign(self, s: ast.Assign, depth: int) -> None:
        value = s.value
        if s.op != "=":
            op = {"^=": "^", "*=": "*", "/=": "/", "\\=": "\\", "+=": "+", "-=": "-", "<<=": "<<",
                  ">>=": ">>", "&=": "&"}[s.op]
            value = ast.Binary(op, s.target, s.value)
            value.line, value.column = s.line, s.column
        code, vt = self.expr(value)
        self.store(s.target, code, vt, depth)

    def s_CallStatement(self, s: ast.CallStatement, depth: int) -> None:
        e = s.expr
        if isinstance(e, ast.Call):
            code, _ = self.call(e, statement=True)
        elif isinstance(e, (ast.Name, ast.Member)):
            code, _ = self.call(ast.Call(e, [], e.line, e.column), statement=True)
        else:
            raise self.fail(INVALID_STATEMENT, "an expression is not a statement", s)
        self.emit(depth, code)

    def s_If(self, s: ast.If, depth: int) -> None:
        keyword = "if"
        for cond, body in s.branches:
            self.node = s
            self.emit(depth, f"{keyword} {self.condition(cond)}:")
            self.block(body, depth + 1)
            keyword = "elif"
        if s.orelse:
            self.node = s
            self.emit(depth, "else:")
            self.block(s.orelse, depth + 1)

    def condition(self, e: ast.Expr) -> str:
        code, t = self.expr(e)
        if t is not None and t.is_bool:
            return code
        if t is not None and t.is_number:
            return f"({code} != 0)"
        return f"_truth({code})"

    def slice_check(self, depth: int) -> None:
        """Give the CPU back now and then, as the controller time-slices threads."""
        self.emit(depth, "_slice += 1")
        self.emit(depth, f"if _slice >= {SLICE_ITERATIONS}:")
        self.emit(depth + 1, "_slice = 0")
        self.emit(depth + 1, "yield rt.SLICE")

    def loop_body(self, s, kind: str, body: list, depth: int, step=None) -> _Loop:
        loop = _Loop(kind, id(s), step=step)
        self.loops.append(loop)
        self.block(body, depth)
        self.loops.pop()
        return loop

    def s_For(self, s: ast.For, depth: int) -> None:
        var_code, var_type = self.expr(s.var)
        if var_type is not None and not var_type.is_number:
            raise self.fail(TYPE_MISMATCH, "a For variable must be numeric", s)
        stop, step = self.fresh("stop"), self.fresh("step")
        stop_code, _ = self.expr(s.stop)
        self.emit(depth, f"{stop} = _num({stop_code})")
        if s.step is None:
            step_value = 1
            self.emit(depth, f"{step} = 1")
        else:
            step_code, _ = self.expr(s.step)
            step_value = s.step.value if isinstance(s.step, ast.Literal) else None
            self.emit(depth, f"{step} = _num({step_code})")
        start_code, start_type = self.expr(s.start)
        self.store(s.var, start_code, start_type, depth)
        if step_value is None:
            test = f"(({var_code}) <= {stop} if {step} >= 0 else ({var_code}) >= {stop})"
        else:
            test = f"{var_code} {'<=' if step_value >= 0 else '>='} {stop}"
        self.emit(depth, f"while {test}:")
        self.with_exit_catch(s, depth + 1, lambda d: self.for_body(s, var_code, step, d))

    def for_body(self, s: ast.For, var_code: str, step: str, depth: int) -> None:
        self.loop_body(s, "for", s.body, depth, step=(s.var, step))
        self.node = s
        self.store(s.var, f"{var_code} + {step}", None, depth)
        self.slice_check(depth)

    def with_exit_catch(self, s, depth: int, emit_body) -> None:
        """A loop whose body has labels or a Select is left with `_Break` (a `break`
        would only leave the dispatch loop or the Select's loop)."""
        if not _contains(s.body, (ast.Label, ast.Select)):
            emit_body(depth)
            return
        self.emit(depth, "try:")
        emit_body(depth + 1)
        self.emit(depth, "except _Break as _b:")
        self.emit(depth + 1, f"if _b.loop != {id(s)}: raise")
        self.emit(depth + 1, "break")

    def s_While(self, s: ast.While, depth: int) -> None:
        self.emit(depth, f"while {self.condition(s.condition)}:")

        def body(d):
            self.loop_body(s, "while", s.body, d)
            self.slice_check(d)

        self.with_exit_catch(s, depth + 1, body)

    def s_Do(self, s: ast.Do, depth: int) -> None:
        if s.pre is not None:
            kind, cond = s.pre
            test = self.condition(cond)
            self.emit(depth, f"while {test if kind == 'while' else f'not {test}'}:")
        else:
            self.emit(depth, "while True:")

        def body(d):
            self.loop_body(s, "do", s.body, d)
            if s.post is not None:
                self.node = s
                kind, cond = s.post
                test = self.condition(cond)
                self.emit(d, f"if {f'not {test}' if kind == 'while' else test}: break")
            self.slice_check(d)

        self.with_exit_catch(s, depth + 1, body)

    def s_Select(self, s: ast.Select, depth: int) -> None:
        subject, st = self.expr(s.subject)
        value = self.fresh("case")
        self.emit(depth, f"{value} = {subject}")
        bodies = [c for _, b in s.cases for c in b] + (s.default or [])
        exits = _contains(bodies, (ast.Exit,))
        inner = depth
        if exits:
            if _contains(bodies, (ast.Label, ast.Select)):
                self.emit(depth, "try:")
                depth += 1
            self.emit(depth, "while True:")
            inner = depth + 1
            self.loops.append(_Loop("select", id(s)))
        keyword = "if"
        for tests, body in s.cases:
            self.node = s
            self.emit(inner, f"{keyword} {' or '.join(self.case_test(value, st, t) for t in tests)}:")
            self.block(body, inner + 1)
            keyword = "elif"
        if s.default is not None:
            self.node = s
            self.emit(inner, "else:" if s.cases else "if True:")
            self.block(s.default, inner + 1)
        if exits:
            self.emit(inner, "break")
            self.loops.pop()
            if _contains(bodies, (ast.Label, ast.Select)):
                self.emit(depth - 1, "except _Break as _b:")
                self.emit(depth, f"if _b.loop != {id(s)}: raise")

    def case_test(self, value: str, st: SType | None, t: ast.CaseTest) -> str:
        """Case values are converted to the type of the Select value (ch. 9)."""
        def as_subject(e):
            code, ct = self.expr(e)
            if st is not None and st.is_string:
                return self.convert(code, ct, st)
            return code if ct is not None and ct.is_number else f"_num({code})"

        subject = value if st is not None and (st.is_string or st.is_number) else f"_case_value({value})"
        if t.kind == "range":
            return f"({as_subject(t.low)} <= {subject} <= {as_subject(t.high)})"
        op = {"=": "==", "<>": "!="}.get(t.op, t.op)
        return f"({subject} {op} {as_subject(t.low)})"

    def s_Try(self, s: ast.Try, depth: int) -> None:
        if s.catch_body is None and s.finally_body is None:
            raise self.fail(INVALID_STATEMENT, "a Try needs a Catch or a Finally", s)
        catch_var = None
        if s.catch_var is not None:
            catch_var = self.lookup_value(s.catch_var.lower(), s)
            if not isinstance(catch_var, VarSym) or catch_var.type.base != "lib" or \
                    catch_var.type.ref is not CLASSES.get("exception"):
                raise self.fail(TYPE_MISMATCH, f"Catch {s.catch_var}: not an Exception variable", s)
        d = depth
        flag = None
        if s.finally_body is not None:
            flag = self.fresh("fx")
            self.emit(d, f"{flag} = None")
            self.emit(d, "try:")
            d += 1
        self.emit(d, "try:")
        retry = s.catch_body is not None and _has_labels(s.body) and _contains(s.catch_body, (ast.Goto,))
        pc = None
        body_ident = None
        if retry:
            body_ident = self.temp + 1
            pc = f"_pc{body_ident}"
            self.emit(d + 1, f"{pc} = 0")
            self.emit(d + 1, "while True:")
            inner = d + 2
        else:
            inner = d + 1
        self.try_depth += 1
        if s.catch_body is not None:
            self.emit(inner, "try:")
            self.block(s.body, inner + 1, dispatch_var=pc, boundary=True)
            self.node = s
            self.emit(inner, "except _CONTROL: raise")
            self.emit(inner, "except Exception as _e:")
            if catch_var is not None:
                self.assign_var(catch_var, "_catch(rt, _e)", inner + 1)
            else:
                self.emit(inner + 1, "_catch(rt, _e)")
            try_block = self.blocks_for_catch(s, body_ident)
            if retry:
                self.emit(inner + 1, "try:")
                self.blocks.append(try_block)
                self.block(s.catch_body, inner + 2, boundary=False)
                self.blocks.pop()
                self.emit(inner + 1, "except _Jump as _j:")
                self.emit(inner + 2, f"if _j.block != {body_ident}: raise")
                self.emit(inner + 2, f"{pc} = _j.segment")
                self.slice_check(inner + 2)
                self.emit(inner + 2, "continue")
                self.emit(inner, "break")
            else:
                self.blocks.append(_Block(-1, {}, True))
                self.block(s.catch_body, inner + 1)
                self.blocks.pop()
        else:
            self.block(s.body, inner, boundary=True)
            if retry:
                self.emit(inner, "break")
        self.try_depth -= 1
        self.node = s
        self.emit(d, "except _ExitTry: pass")
        if s.finally_body is not None:
            self.emit(depth, "except GeneratorExit:")
            self.emit(depth + 1, f"{flag} = True")
            self.emit(depth + 1, "raise")
            self.emit(depth, "finally:")
            self.emit(depth + 1, f"if {flag} is None:")
            self.blocks.append(_Block(-1, {}, True))
            self.block(s.finally_body, depth + 2)
            self.blocks.pop()

    def blocks_for_catch(self, s: ast.Try, body_ident: int | None) -> _Block:
        labels = {}
        if body_ident is not None:
            segment = 0
            for st in s.body:
                if isinstance(st, ast.Label):
                    segment += 1
                    labels[st.name] = segment
        return _Block(body_ident if body_ident is not None else -1, labels, True)

    def s_Goto(self, s: ast.Goto, depth: int) -> None:
        for block in reversed(self.blocks):
            if block is None:
                continue
            if s.label in block.labels:
                self.emit(depth, f"raise _Jump({block.ident}, {block.labels[s.label]})")
                return
            if block.boundary:
                break
        if self.label_exists(s.label):
            raise self.fail(ILLEGAL_GOTO, f"GoTo {s.label}", s)
        raise self.fail(UNDEFINED_SYMBOL, f"label {s.label}", s)

    def label_exists(self, label: str) -> bool:
        body = self.proc.node.body if self.proc is not None else []
        return _contains(body, (ast.Label,)) and any(
            isinstance(x, ast.Label) and x.name == label for x in _walk(body))

    def s_Exit(self, s: ast.Exit, depth: int) -> None:
        kind = s.kind
        if kind in ("sub", "function", "property"):
            if self.proc is None:
                raise self.fail(INVALID_STATEMENT, f"Exit {kind}", s)
            self.emit(depth, self.return_code(None))
            return
        if kind == "try":
            if self.try_depth == 0:
                raise self.fail(INVALID_STATEMENT, "Exit Try outside a Try or Catch block", s)
            self.emit(depth, "raise _ExitTry()")
            return
        for i in range(len(self.loops) - 1, -1, -1):
            loop = self.loops[i]
            if loop.kind == kind:
                direct = all(l.kind not in ("dispatch", "select") for l in self.loops[i + 1:])
                self.emit(depth, "break" if direct else f"raise _Break({loop.ident})")
                return
        raise self.fail(INVALID_STATEMENT, f"Exit {kind.capitalize()} outside a {kind.capitalize()} block", s)

    def s_Continue(self, s: ast.Continue, depth: int) -> None:
        for i in range(len(self.loops) - 1, -1, -1):
            loop = self.loops[i]
            if loop.kind == s.kind:
                if any(l.kind == "dispatch" for l in self.loops[i + 1:]):
                    raise self.fail(UNSUPPORTED, "Continue from a block with labels", s)
                if loop.step is not None:
                    var, step = loop.step
                    code, _ = self.expr(var)
                    self.store(var, f"{code} + {step}", None, depth)
                self.emit(depth, "continue")
                return
        raise self.fail(INVALID_STATEMENT, f"Continue {s.kind.capitalize()} outside a loop", s)

    def s_Return(self, s: ast.Return, depth: int) -> None:
        if self.proc is None:
            raise self.fail(INVALID_STATEMENT, "Return outside a procedure", s)
        if s.value is None:
            self.emit(depth, self.return_code(None))
            return
        if self.proc.kind != "function":
            raise self.fail(INVALID_STATEMENT, "Return with a value in a Sub", s)
        code, t = self.expr(s.value)
        self.emit(depth, self.return_code(self.convert(code, t, self.proc.return_type)))

    def s_Throw(self, s: ast.Throw, depth: int) -> None:
        if s.value is None:
            self.emit(depth, "raise _rethrow(rt)")
            return
        code, _ = self.expr(s.value)
        self.emit(depth, f"raise _throw({code})")

    def s_ReDim(self, s: ast.ReDim, depth: int) -> None:
        for target in s.targets:
            if not isinstance(target, ast.Call):
                raise self.fail(INVALID_STATEMENT, "ReDim needs new bounds: ReDim a(9)", s)
            code, t = self.expr(target.func)
            if t is not None and not t.is_array:
                raise self.fail(TYPE_MISMATCH, "ReDim of a variable that is not an array", s)
            dims = ", ".join(self.index_code(a) for a in target.args)
            default = self.default(t.element) if t is not None else None
            if t is not None and len(target.args) != t.rank:
                raise self.fail(INVALID_STATEMENT, "ReDim cannot change the rank of an array", s)
            self.store(target.func, f"_redim({code}, ({dims},), {default!r})", t, depth)

    # ------------------------------------------------------------ stores
    def assign_var(self, var: VarSym, code: str, depth: int) -> None:
        if var.kind in ("module", "shared", "static"):
            self.globals_assigned.add(var.py)
            self.emit(depth, f"{var.py} = {code}")
        elif var.kind == "field":
            self.emit(depth, f"{self.me_code()}.{var.py} = {code}")
        else:
            self.emit(depth, f"{var.py} = {code}")

    def store(self, target: ast.Expr, code: str, vt: SType | None, depth: int) -> None:
        if isinstance(target, ast.Name):
            sym = self.lookup_value(target.key, target)
            if isinstance(sym, VarSym):
                if sym.const:
                    raise self.fail(CONSTANT_ASSIGNMENT, sym.name, target)
                self.assign_var(sym, self.convert(code, vt, sym.type), depth)
                return
            if isinstance(sym, ProcSym) and self.proc is not None and sym is self.proc:
                self.emit(depth, f"_result = {self.convert(code, vt, self.proc.return_type)}")
                return
            if isinstance(sym, PropSym):
                self.store(ast.Member(ast.Me(), target.name, target.line, target.column), code, vt, depth)
                return
            if self.proc is not None and self.proc.kind == "function" and target.key == self.proc.key:
                self.emit(depth, f"_result = {self.convert(code, vt, self.proc.return_type)}")
                return
            raise self.fail(UNDEFINED_SYMBOL if sym is None else INVALID_STATEMENT, target.name, target)
        if isinstance(target, ast.Call):
            func = target.func
            fcode, ft = self.expr_or_ns(func)
            if ft is not None and ft.is_array:
                if len(target.args) != ft.rank:
                    raise self.fail(INVALID_STATEMENT, f"{len(target.args)} indices for a rank {ft.rank} array")
                self.emit(depth, f"{fcode}[{self.indices(target.args)}] = {self.convert(code, vt, ft.element)}")
                return
            if isinstance(func, ast.Member):
                self.store_member(func, target.args, code, vt, depth)
                return
            if ft is None:
                args = ", ".join(self.expr(a)[0] for a in target.args)
                self.emit(depth, f"_setindex({fcode}, ({args},), {code})")
                return
            raise self.fail(INVALID_STATEMENT, "cannot assign to this expression", target)
        if isinstance(target, ast.Member):
            self.store_member(target, None, code, vt, depth)
            return
        raise self.fail(INVALID_STATEMENT, "cannot assign to this expression", target)

    def store_member(self, target: ast.Member, args: list | None, code: str, vt, depth: int) -> None:
        ocode, ot = self.expr_or_ns(target.obj)
        key = target.key
        arg_codes = [self.expr(a)[0] for a in (args or [])]
        if ot is not None and ot.base == "ns":
            owner = ot.ref
            if isinstance(owner, type):  # a built-in class: a shared property
                attr = self.library_attr(owner, key, target)
                setter = library_member(owner, "set_" + attr)
                if setter is None:
                    raise self.fail(INVALID_STATEMENT, f"{owner.gpl_name}.{target.name} is read-only", target)
                self.emit(depth, f"L_{owner.gpl_name.lower()}.{setter}(rt, {', '.join(arg_codes + [code])})")
                return
            sym = self.member_of_namespace(owner, key, target)
            if isinstance(sym, VarSym):
                if args:
                    t = sym.type
                    self.emit(depth, f"{sym.py}[{self.indices(args)}] = {self.convert(code, vt, t.element)}")
                    return
                if sym.const:
                    raise self.fail(CONSTANT_ASSIGNMENT, sym.name, target)
                self.assign_var(sym, self.convert(code, vt, sym.type), depth)
                return
            if isinstance(sym, PropSym) and sym.shared:
                self.emit(depth, f"yield from {self.setter_of(sym, target)}(rt, {', '.join(arg_codes + [code])})")
                return
            raise self.fail(INVALID_STATEMENT, f"cannot assign to {target.name}", target)
        if ot is not None and ot.base == "user" and not ot.rank:
            sym = self.class_member(ot.ref, key, target)
            if isinstance(sym, VarSym):
                value = self.convert(code, vt, sym.type.element if args else sym.type)
                where = sym.py if sym.kind == "shared" else f"{ocode}.{sym.py}"
                if sym.kind == "shared":
                    self.globals_assigned.add(sym.py)
                if sym.const:
                    raise self.fail(CONSTANT_ASSIGNMENT, sym.name, target)
                self.emit(depth, f"{where}[{self.indices(args)}] = {value}" if args else f"{where} = {value}")
                return
            if isinstance(sym, PropSym):
                value = self.convert(code, vt, sym.type)
                who = [] if sym.shared else [ocode]
                self.emit(depth, f"yield from {self.setter_of(sym, target)}(rt, {', '.join(who + arg_codes + [value])})")
                return
            raise self.fail(INVALID_STATEMENT, f"cannot assign to {target.name}", target)
        if ot is not None and ot.base == "lib" and not ot.rank:
            cls = ot.ref
            attr = self.library_attr(cls, key, target)
            if args:
                setter = library_member(cls, "set_" + attr)
                if setter is None:
                    raise self.fail(INVALID_STATEMENT, f"{cls.gpl_name}.{target.name} is read-only", target)
                self.emit(depth, f"{ocode}.{setter}({', '.join(arg_codes + [code])})")
            else:
                self.emit(depth, f"_setattr({ocode}, {attr!r}, {code})")
            return
        call_args = f"({', '.join(arg_codes)},)" if args else "None"
        self.emit(depth, f"yield from _w(_setm(rt, {ocode}, {key!r}, {call_args}, {code}))")

    def setter_of(self, prop: PropSym, node) -> str:
        if prop.setter_py is None:
            raise self.fail(INVALID_STATEMENT, f"property {prop.name} is read-only", node)
        return prop.setter_py

    # ------------------------------------------------------------ conversions
    def convert(self, code: str, vt: SType | None, target: SType | None) -> str:
        """Code converting a value to the target type on assignment (ch. 8)."""
        if target is None or target.rank:
            return code
        base = target.base
        if base in CONVERT:
            if vt is not None and not vt.rank and vt.base == base:
                return code
            if base == "double" and vt is not None and vt.is_number and vt.base != "single":
                return code if vt.base == "double" else f"float({code})"
            if vt is not None and vt.base in ("user", "lib", "delegate", "nothing") and not vt.rank:
                raise self.fail(TYPE_MISMATCH, f"{vt} assigned to a {target}")
            return f"{CONVERT[base]}({code})"
        if vt is not None and vt.base in BASIC and not vt.rank:
            raise self.fail(TYPE_MISMATCH, f"{vt} assigned to a {target}")
        return code

    # ------------------------------------------------------------ expressions
    def lookup_value(self, key: str, node):
        if key in self.locals:
            return self.locals[key]
        return self.lookup(key, node)

    def me_code(self) -> str:
        return "me" if self.me_available else "rt.no_me()"

    def expr_or_ns(self, e: ast.Expr) -> tuple[str, SType | None]:
        """Like expr, but a module, class or built-in class name gives a namespace."""
        if isinstance(e, ast.Name):
            sym = self.lookup_value(e.key, e)
            if isinstance(sym, (ModuleSym, ClassSym, DelegateSym)) or isinstance(sym, type):
                return "", ns(sym)
            if sym is None and e.key == "string":
                return "", ns("string")
        if isinstance(e, ast.Member):
            ocode, ot = self.expr_or_ns(e.obj)
            if ot is not None and ot.base == "ns" and isinstance(ot.ref, (ModuleSym, ClassSym)):
                sym = self.member_of_namespace(ot.ref, e.key, e)
                if isinstance(sym, (ClassSym, DelegateSym)):
                    return "", ns(sym)
        return self.expr(e)

    def expr(self, e: ast.Expr) -> tuple[str, SType | None]:
        method = getattr(self, "e_" + type(e).__name__)
        return method(e)

    def e_Literal(self, e: ast.Literal):
        v = e.value
        if isinstance(v, bool):
            return repr(v), SType("boolean")
        if isinstance(v, int):
            return repr(v), SType("integer")
        if isinstance(v, float):
            return repr(v), SType("double")
        return repr(v), SType("string")

    def e_Nothing(self, e):
        return "None", SType("nothing")

    def e_Me(self, e):
        if not self.me_available:
            return "rt.no_me()", None
        return "me", SType("user", self.cls)

    def e_Name(self, e: ast.Name):
        sym = self.lookup_value(e.key, e)
        if isinstance(sym, VarSym):
            return self.var_code(sym), sym.type
        if sym is None:
            if e.key in CONSTANTS:
                code, t = CONSTANTS[e.key]
                return code, SType(t)
            if e.key in FUNCTIONS:
                return self.call(ast.Call(e, [], e.line, e.column))
            if self.proc is not None and self.proc.kind == "function" and e.key == self.proc.key:
                return "_result", self.proc.return_type
            raise self.fail(UNDEFINED_SYMBOL, e.name, e)
        if isinstance(sym, (ProcSym, PropSym)):
            return self.call(ast.Call(e, [], e.line, e.column))
        raise self.fail(TYPE_MISMATCH, f"{e.name} is not a value", e)

    def var_code(self, var: VarSym) -> str:
        if var.kind == "field":
            return f"{self.me_code()}.{var.py}"
        return var.py

    def e_Member(self, e: ast.Member):
        return self.call(ast.Call(e, [], e.line, e.column), no_parens=True)

    def e_Call(self, e: ast.Call):
        return self.call(e)

    def e_AddressOf(self, e: ast.AddressOf):
        """AddressOf outside a Delegate's New (`New Thread(AddressOf Worker)`, as in
        VB.NET): a delegate of the procedure's own signature."""
        return self.address_of(e, None), None

    def e_New(self, e: ast.New):
        return self.new_object(e)

    def new_object(self, e: ast.New) -> tuple[str, SType]:
        t = self.resolve_type(e.type, e)
        args = e.args or []
        if t.base == "user":
            cls = t.ref
            ctors = [c for c in cls.constructors if len(c.params) == len(args)]
            if not ctors and (cls.constructors or args):
                raise self.fail(WRONG_ARGUMENT_COUNT, f"no New of {cls.name} takes {len(args)} arguments", e)
            ctor = ctors[0].py if ctors else "None"
            codes = [self.convert(*self.expr(a), pt) for a, pt in zip(args, ctors[0].param_types)] if ctors else []
            return f"(yield from N_{cls.py}(rt, {', '.join([ctor] + codes)}))", SType("user", cls)
        if t.base == "lib":
            codes = [self.expr(a)[0] for a in args]
            return f"L_{t.ref.gpl_name.lower()}({', '.join(['rt'] + codes)})", SType("lib", t.ref)
        if t.base == "delegate":
            return self.new_delegate(e, t.ref), SType("delegate", t.ref)
        if t.base == "string":
            raise self.fail(UNSUPPORTED, "New String (ch. 7: Strings need no New)", e)
        raise self.fail(TYPE_MISMATCH, f"New {t}", e)

    def new_delegate(self, e: ast.New, dsym: DelegateSym) -> str:
        args = e.args or []
        if len(args) != 1:
            raise self.fail(WRONG_ARGUMENT_COUNT, f"New {dsym.name} takes one procedure", e)
        arg = args[0]
        if isinstance(arg, ast.AddressOf):
            return self.address_of(arg, dsym)
        code, _ = self.expr(arg)
        return f"_delegate_named(rt, {code}, {dsym.kind!r}, {len(dsym.params)})"

    def address_of(self, e: ast.AddressOf, dsym: DelegateSym | None) -> str:
        """A Delegate object for AddressOf proc / AddressOf object.method (ch. 10):
        the object is bound when the delegate is made."""
        target = e.target
        me = "None"
        if isinstance(target, ast.Member):
            ocode, ot = self.expr_or_ns(target.obj)
            if ot is not None and ot.base == "ns":
                proc = self.member_of_namespace(ot.ref, target.key, target)
            elif ot is not None and ot.base == "user":
                proc = self.class_member(ot.ref, target.key, target)
                me = ocode
            else:
                raise self.fail(TYPE_MISMATCH, "AddressOf needs a procedure", e)
        elif isinstance(target, ast.Name):
            proc = self.lookup_value(target.key, target)
            if isinstance(proc, ProcSym) and proc.instance and self.me_available:
                me = "me"
        else:
            raise self.fail(TYPE_MISMATCH, "AddressOf needs a procedure", e)
        if not isinstance(proc, ProcSym):
            raise self.fail(TYPE_MISMATCH, "AddressOf needs a Sub or Function", e)
        if dsym is not None:
            self.check_delegate_signature(dsym, proc, e)
        if proc.instance and me == "None":
            raise self.fail(INVALID_STATEMENT, f"AddressOf {proc.name} needs an object", e)
        return f"_Delegate({proc.py}, {me if proc.instance else 'None'}, {proc.qualified!r}, " \
               f"{bool(proc.byref_positions)})"

    def check_delegate_signature(self, dsym: DelegateSym, proc: ProcSym, node) -> None:
        """The procedure must match the Delegate statement exactly (ch. 10)."""
        scope = Scope(self.project, dsym.module, None)
        ok = proc.kind == dsym.kind and len(proc.params) == len(dsym.params)
        if ok:
            for p, dp, pt in zip(proc.params, dsym.params, proc.param_types):
                if p.byref != dp.byref or scope.param_type(dp, node) != pt:
                    ok = False
        if ok and dsym.kind == "function":
            ok = scope.resolve_type(dsym.return_type, node) == proc.return_type if dsym.return_type else True
        if not ok:
            raise self.fail(TYPE_MISMATCH, f"{proc.name} does not match Delegate {dsym.name}", node)

    # ---- operators
    def e_Unary(self, e: ast.Unary):
        code, t = self.expr(e.operand)
        if e.op == "-":
            if t is not None and t.is_number:
                return f"(-{code})", t
            return f"_neg({code})", SType("double")
        if t is not None and t.is_bool:
            return f"(not {code})", t
        if t is not None and t.is_integral:
            return f"(~{code})", t
        return f"_not({code})", None

    def e_Binary(self, e: ast.Binary):
        op = e.op
        if op in ("andalso", "orelse"):
            a = self.condition(e.left)
            b = self.condition(e.right)
            return f"({a} {'and' if op == 'andalso' else 'or'} {b})", SType("boolean")
        a, at = self.expr(e.left)
        b, bt = self.expr(e.right)
        nums = at is not None and bt is not None and at.is_number and bt.is_number
        ints = nums and at.is_integral and bt.is_integral
        result = SType("integer") if ints else SType("double")
        if op == "+":
            if at is not None and bt is not None and at.is_string and bt.is_string:
                return f"({a} + {b})", SType("string")
            return (f"({a} + {b})", result) if nums else (f"_add({a}, {b})", None)
        if op in ("-", "*"):
            return (f"({a} {op} {b})", result) if nums else (f"(_num({a}) {op} _num({b}))", SType("double"))
        if op == "/":
            return f"_div({a}, {b})", SType("double")
        if op == "\\":
            return f"_idiv({a}, {b})", SType("integer")
        if op == "mod":
            return f"_mod({a}, {b})", result
        if op == "^":
            return f"_pow({a}, {b})", SType("double")
        if op == "<<":
            return f"_shl({a}, {b})", SType("integer")
        if op == ">>":
            return f"_shr({a}, {b})", SType("integer")
        if op == "&":
            if at is not None and bt is not None and at.is_string and bt.is_string:
                return f"({a} + {b})", SType("string")
            return f"_concat({a}, {b})", SType("string")
        if op in ("=", "<>", "<", ">", "<=", ">="):
            strings = at is not None and bt is not None and at.is_string and bt.is_string
            if nums or strings:
                py = {"=": "==", "<>": "!="}.get(op, op)
                return f"({a} {py} {b})", SType("boolean")
            return f"_cmp({a}, {b}, {op!r})", SType("boolean")
        if op == "is":
            return f"({a} is {b})", SType("boolean")
        if op in ("and", "or", "xor"):
            bools = at is not None and bt is not None and at.is_bool and bt.is_bool
            if bools or ints:
                py = {"and": "&", "or": "|", "xor": "^"}[op]
                return f"({a} {py} {b})", at
            return f"_{op}({a}, {b})", None
        raise self.fail(INVALID_STATEMENT, f"operator {op}", e)

    # ---- calls and members
    def index_code(self, e: ast.Expr) -> str:
        code, t = self.expr(e)
        return code if t is not None and t.is_integral else f"_ix({code})"

    def indices(self, args: list[ast.Expr]) -> str:
        return ", ".join(self.index_code(a) for a in args)

    def call(self, e: ast.Call, statement: bool = False, no_parens: bool = False) -> tuple[str, SType | None]:
        """A call, an array element, a member (with or without arguments)."""
        func, args = e.func, e.args
        if isinstance(func, ast.Name):
            sym = self.lookup_value(func.key, func)
            if isinstance(sym, ProcSym):
                return self.call_proc(sym, "me" if sym.instance else None, args, e, statement)
            if isinstance(sym, PropSym):
                return self.get_property(sym, "me" if not sym.shared else None, args, e)
            if sym is None and func.key in FUNCTIONS:
                return self.call_builtin(func.key, args, e)
            if sym is None and self.proc is not None and self.proc.kind == "function" and func.key == self.proc.key \
                    and not args:
                return "_result", self.proc.return_type
        if isinstance(func, ast.Member):
            ocode, ot = self.expr_or_ns(func.obj)
            return self.call_member(ocode, ot, func, args, e, statement, no_parens)
        code, t = self.expr(func)
        if t is not None and t.is_array:
            if not args:
                return code, t
            if len(args) != t.rank:
                raise self.fail(INVALID_STATEMENT, f"{len(args)} indices for a rank {t.rank} array", e)
            return f"{code}[{self.indices(args)}]", t.element
        if t is not None and t.base == "delegate":
            return self.invoke_delegate(code, t.ref, args, e)
        if not args and not isinstance(e.func, ast.Call) and statement:
            raise self.fail(INVALID_STATEMENT, "a variable is not a statement", e)
        if not args and not statement:
            return code, t
        arg_codes = ", ".join(self.expr(a)[0] for a in args)
        return f"(yield from _w(_call(rt, {code}, ({arg_codes}{',' if args else ''}))))", None

    def invoke_delegate(self, code: str, dsym: DelegateSym, args, e) -> tuple[str, SType | None]:
        if len(args) != len(dsym.params):
            raise self.fail(WRONG_ARGUMENT_COUNT, f"Delegate {dsym.name} takes {len(dsym.params)}", e)
        scope = Scope(self.project, dsym.module, None)
        codes = [self.convert(*self.expr(a), scope.param_type(p, e)) for a, p in zip(args, dsym.params)]
        rtype = scope.resolve_type(dsym.return_type, e) if dsym.kind == "function" and dsym.return_type else None
        return f"(yield from _invoke(rt, {code}, ({', '.join(codes)}{',' if codes else ''})))", rtype

    def call_builtin(self, key: str, args, e) -> tuple[str, SType | None]:
        fn, takes_rt = FUNCTIONS[key]
        codes = [self.expr(a)[0] for a in args]
        if takes_rt:
            codes.insert(0, "rt")
        rtype = FUNCTION_TYPES.get(key)
        return f"F_{key}({', '.join(codes)})", SType(rtype) if rtype else None

    def call_proc(self, proc: ProcSym, me: str | None, args, e, statement: bool) -> tuple[str, SType | None]:
        if proc.kind == "sub" and not statement:
            raise self.fail(TYPE_MISMATCH, f"Sub {proc.name} has no value", e)
        if len(args) != len(proc.params):
            raise self.fail(WRONG_ARGUMENT_COUNT,
                            f"{proc.name} takes {len(proc.params)} argument(s), {len(args)} given", e)
        if proc.instance and me is None:
            raise self.fail(INVALID_STATEMENT, f"{proc.name} needs an object: object.{proc.name}", e)
        codes = ([self.me_code() if me == "me" else me] if proc.instance else [])
        codes += [self.expr(a)[0] for a in args]
        call = f"(yield from {proc.py}({', '.join(['rt'] + codes)}))"
        if not proc.byref_positions:
            return call, proc.return_type
        # Value-result (see the module docstring): the call runs first, then the
        # final values of the ByRef parameters go back to the caller's variables.
        temp = self.fresh("r")
        self.emit(self.depth, f"{temp} = {call}")
        for k, i in enumerate(proc.byref_positions):
            if _is_variable(args[i]):
                self.store(args[i], f"{temp}[1][{k}]", proc.param_types[i], self.depth)
        return f"{temp}[0]", proc.return_type

    def call_member(self, ocode: str, ot: SType | None, func: ast.Member, args, e, statement: bool,
                    no_parens: bool) -> tuple[str, SType | None]:
        key = func.key
        codes = [self.expr(a)[0] for a in args]
        if ot is not None and ot.base == "ns":
            owner = ot.ref
            if owner == "string":
                if key not in STRING_SHARED:
                    raise self.fail(UNDEFINED_SYMBOL, f"String.{func.name}", func)
                return f"_STRING_SHARED[{key!r}]({', '.join(codes)})", SType("integer")
            if isinstance(owner, type):
                return self.library_call(f"L_{owner.gpl_name.lower()}", owner, key, args, codes, func, shared=True)
            sym = self.member_of_namespace(owner, key, func)
            if isinstance(sym, ProcSym):
                if sym.instance:
                    raise self.fail(INVALID_STATEMENT, f"{sym.name} is not Shared: call it on an object", func)
                return self.call_proc(sym, None, args, e, statement)
            if isinstance(sym, VarSym):
                t = sym.type
                if args:
                    return f"{sym.py}[{self.indices(args)}]", t.element
                return sym.py, t
            if isinstance(sym, PropSym):
                return self.get_property(sym, None, args, e)
            raise self.fail(TYPE_MISMATCH, f"{func.name} is not a value", func)
        if ot is not None and ot.is_array:
            return self.array_member(ocode, ot, key, codes, func)
        if ot is not None and ot.is_string:
            if key not in STRING_MEMBERS:
                raise self.fail(UNDEFINED_SYMBOL, f"String member {func.name}", func)
            _, is_property, rtype = STRING_MEMBERS[key]
            code = f"_STRING[{key!r}]({', '.join([ocode] + codes)})"
            return code, SType(rtype) if rtype else (SType("string", None, 1) if key == "split" else None)
        if ot is not None and ot.base == "user":
            sym = self.class_member(ot.ref, key, func)
            if isinstance(sym, VarSym):
                where = sym.py if sym.kind == "shared" else f"{ocode}.{sym.py}"
                if args:
                    if sym.type.is_array:
                        return f"{where}[{self.indices(args)}]", sym.type.element
                    raise self.fail(TYPE_MISMATCH, f"{func.name} is not an array", func)
                return where, sym.type
            if isinstance(sym, ProcSym):
                return self.call_proc(sym, ocode if sym.instance else None, args, e, statement)
            if isinstance(sym, PropSym):
                return self.get_property(sym, None if sym.shared else ocode, args, e)
            raise self.fail(TYPE_MISMATCH, f"{func.name} is not a value", func)
        if ot is not None and ot.base == "lib" and not ot.rank:
            return self.library_call(ocode, ot.ref, key, args, codes, func, shared=False)
        if ot is not None and ot.base in BASIC and not ot.rank:
            raise self.fail(UNDEFINED_SYMBOL, f"{ot} has no member {func.name}", func)
        call_args = f"({', '.join(codes)}{',' if codes else ''})" if (args or not no_parens) else "None"
        call = f"_callm(rt, {ocode}, {key!r}, {call_args})"
        if key in self.project.waiting:
            return f"(yield from _w({call}))", None
        return call, None

    def array_member(self, ocode: str, ot: SType, key: str, codes, func) -> tuple[str, SType | None]:
        if key == "length":
            return f"{ocode}.Length", SType("integer")
        if key == "rank":
            return f"{ocode}.Rank", SType("integer")
        if key == "getupperbound":
            return f"{ocode}.GetUpperBound({', '.join(codes)})", SType("integer")
        raise self.fail(UNDEFINED_SYMBOL, f"array member {func.name}", func)

    def class_member(self, cls: ClassSym, key: str, node):
        sym = cls.member(key)
        if sym is None:
            raise self.fail(UNDEFINED_SYMBOL, f"{cls.name}.{key}", node)
        if not is_public(sym) and not self.inside(cls):
            raise self.fail(PRIVATE_SYMBOL, f"{cls.name}.{sym.name}", node)
        return sym

    def get_property(self, prop: PropSym, who: str | None, args, e) -> tuple[str, SType]:
        if prop.getter_py is None:
            raise self.fail(INVALID_STATEMENT, f"property {prop.name} is write-only", e)
        codes = ([] if prop.shared else [who if who != "me" else self.me_code()]) + [self.expr(a)[0] for a in args]
        return f"(yield from {prop.getter_py}({', '.join(['rt'] + codes)}))", prop.type

    def library_attr(self, cls: type, key: str, node) -> str:
        attr = library_member(cls, key)
        if attr is None:
            raise self.fail(UNDEFINED_SYMBOL, f"{cls.gpl_name}.{key}", node)
        return attr

    def library_call(self, owner_code: str, cls: type, key: str, args, codes, func, shared: bool):
        attr = self.library_attr(cls, key, func)
        kind = _library_kind(cls, attr)
        if shared and kind != "shared":
            raise self.fail(INVALID_STATEMENT, f"{cls.gpl_name}.{func.name} needs an object", func)
        if kind == "property":
            if args:
                raise self.fail(TYPE_MISMATCH, f"{cls.gpl_name}.{func.name} takes no arguments", func)
            return f"{owner_code}.{attr}", None
        byref = library_byref(cls, attr)
        call_codes = list(codes)
        refs = []
        for i in sorted(byref):
            if i < len(args):
                ref = self.fresh("ref")
                refs.append((ref, args[i]))
                call_codes[i] = ref
        prefix = ["rt"] if kind == "shared" else []
        call = f"{owner_code}.{attr}({', '.join(prefix + call_codes)})"
        if library_waits(cls, attr):
            call = f"(yield from {call})"
        if refs:
            return self.with_refs(call, refs)
        return call, None

    def with_refs(self, call: str, refs) -> tuple[str, None]:
        """ByRef arguments of a built-in: a Ref made before the call, its value
        written back to the caller's variable after it."""
        for ref, arg in refs:
            self.emit(self.depth, f"{ref} = _Ref({self.expr(arg)[0]})")
        temp = self.fresh("v")
        self.emit(self.depth, f"{temp} = {call}")
        for ref, arg in refs:
            if _is_variable(arg):
                self.store(arg, f"{ref}.value", None, self.depth)
        return temp, None


def _is_variable(e: ast.Expr) -> bool:
    """Only variables (and elements, fields) can be passed ByRef (ch. 10)."""
    return isinstance(e, (ast.Name, ast.Member, ast.Call))


def _nested_bodies(s) -> list[list]:
    out = []
    for attr in ("body", "orelse", "catch_body", "finally_body", "default"):
        inner = getattr(s, attr, None)
        if isinstance(inner, list):
            out.append(inner)
    if isinstance(s, ast.If):
        out.extend(b for _, b in s.branches)
    if isinstance(s, ast.Select):
        out.extend(b for _, b in s.cases)
    return out


def _walk(body: list):
    for s in body:
        yield s
        for inner in _nested_bodies(s):
            yield from _walk(inner)
