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
Calls: `P_module__proc(rt, [me,] args...)`.  A ByRef parameter receives a
reference object whose `.value` is the caller's variable (a module variable,
field or array element where it lives; a caller's local through a cell copied
back after the call, as no other thread can see it).
GoTo: a statement list that holds labels is compiled as a dispatch loop over
its segments, and GoTo raises `_Jump(block, segment)` caught there.
Each generated line maps back to its GPL statement, for errors.

This module builds the symbol tables of a project (symbols.py) and drives
the per-procedure compiler: names and types in scope.py, expressions and
stores in expressions.py, statements in statements.py.
"""

from __future__ import annotations

from dataclasses import dataclass

from . import ast
from .errors import DUPLICATE_SYMBOL, INVALID_STATEMENT, TOO_DEEP
from .expressions import library_byref, library_names, library_waits
from .scope import Scope, _error, mangle
from .statements import CompiledUnit, ProcCompiler
from .symbols import ClassSym, DelegateSym, ModuleSym, ProcSym, PropSym, SType, VarSym


@dataclass
class _ConstNode:
    """Where a Const is declared, for the error of constants that need each other."""

    module: ModuleSym
    decl: ast.Declarator


@dataclass
class CompiledProject:
    units: list[CompiledUnit]
    modules: list[ModuleSym]
    classes: list[ClassSym]
    init_units: list[str]  # module initialisers (py names), in load order
    init_subs: list[str]  # user Init subs, in load order
    public_procs: dict[str, ProcSym]  # "proc", "module.proc", "class.proc" -> symbol
    statics: dict[str, object]  # global name -> initial value


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
        self.waiting = library_names(library_waits)  # member names whose call may wait: `yield from`
        self.byref_names = library_names(lambda cls, attr: bool(library_byref(cls, attr)))

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
            self.byref_names.update(key for key, proc in cls.methods.items() if proc.byref_positions)
        init_units, init_subs = self.compile_constants(), []
        for sym in self.module_order:
            init_units.extend(self.compile_module_init(sym))
        for cls in self.classes:
            self.compile_class_init(cls)
            # A class's `Shared Sub Init()` runs at start-up too, before the modules' (the TCP
            # Command Server 3.0's GpoFile class fills its Shared tables so: "Init routine
            # called automatically at startup"); the manual (ch. 10) names only modules'.
            init = cls.methods.get("init")
            if init is not None and init.kind == "sub" and not init.params and not init.instance:
                init_subs.append(init.py)
        for sym in self.module_order:
            init = sym.procs.get("init")
            if init is not None and init.kind == "sub" and not init.params:  # ch. 10 "Special Initialization"
                init_subs.append(init.py)
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
    def compile_constants(self) -> list[str]:
        """Every module and Shared class Const, each its own initialiser, run first and in
        the order their values need each other (a Const may use another module's member,
        whatever the order of the files in Project.gpr)."""
        units: dict[str, tuple[str, set[str]]] = {}
        owners = [(m, None, m.vars.values()) for m in self.module_order]
        owners += [(c.module, c, c.fields.values()) for c in self.classes]
        for module, cls, variables in owners:
            for var in variables:
                if var.const and var.kind in ("module", "shared"):
                    gen = ProcCompiler(self, module, None, cls, f"K_{var.py}", f"{(cls or module).name}.{var.name}")
                    gen.begin_init()
                    gen.init_variable(var, global_store=True)
                    gen.finish()
                    units[var.py] = (gen.py, gen.references)
        order: list[str] = []
        state: dict[str, str] = {}

        def visit(py: str, node) -> None:
            if state.get(py) == "done":
                return
            if state.get(py) == "open":
                raise _error(INVALID_STATEMENT, "constants defined in terms of each other", node.module.file, node.decl)
            state[py] = "open"
            for dep in sorted(units[py][1] & units.keys()):
                visit(dep, node)
            state[py] = "done"
            order.append(units[py][0])

        for module, cls, variables in owners:
            for var in variables:
                if var.py in units:
                    visit(var.py, _ConstNode(module, var.decl))
        return order

    def compile_module_init(self, module: ModuleSym) -> list[str]:
        """_Init: module variables in source order (ch. 10 "Special Initialization"), then
        each class's Shared fields (in the class's own scope: its Consts are names there)."""
        gen = ProcCompiler(self, module, None, None, f"I_{mangle(module.name)}", f"{module.name}._Init")
        gen.begin_init()
        for var in module.vars.values():
            if not var.const:
                gen.init_variable(var, global_store=True)
        gen.finish()
        units = [gen.py]
        for cls in self.classes:
            if cls.module is module and any(v.kind == "shared" and not v.const for v in cls.fields.values()):
                cgen = ProcCompiler(self, module, None, cls, f"I_{cls.py}", f"{cls.name}._Init")
                cgen.begin_init()
                for var in cls.fields.values():
                    if var.kind == "shared" and not var.const:
                        cgen.init_variable(var, global_store=True)
                cgen.finish()
                units.append(cgen.py)
        return units

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
        try:
            gen.compile_procedure()
        except RecursionError:  # the compiler walks statements and expressions recursively
            raise _error(TOO_DEEP, f"more than the compiler can nest in {proc.qualified}", proc.module.file,
                         gen.node or proc.node, proc.qualified) from None

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
