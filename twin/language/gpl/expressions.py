"""Expressions, calls, member access and stores of the GPL compiler.

`ExpressionCompiler` turns an expression into Python source and its static
type (None when only the run time knows).  Strong typing (ch. 4) lets most
member accesses be resolved here: a field is an attribute, a built-in
property a Python property, a procedure call `yield from P(rt, ...)`; the
rest goes through the run-time lookups of runtime.py (`_callm`, `_setm`).
Conversions on assignment (ch. 8) are inserted where the types differ.
Stores live here too: a ByRef argument is written back right after its call.
"""

from __future__ import annotations

import inspect
from typing import TYPE_CHECKING

from ...errors import ProgramError
from . import ast
from .builtins import FUNCTION_TYPES, FUNCTIONS, STRING_MEMBERS, STRING_SHARED
from .errors import (
    SYNTAX_ERROR, CONSTANT_ASSIGNMENT, INVALID_STATEMENT, PRIVATE_SYMBOL, TYPE_MISMATCH,
    UNDEFINED_SYMBOL, UNSUPPORTED, WRONG_ARGUMENT_COUNT,
)
from .library import CLASSES, member as library_member
from .parser import keywords
from .scope import Scope, _error
from .symbols import BASIC, ClassSym, DelegateSym, ModuleSym, ProcSym, PropSym, SType, VarSym, is_public, ns
from .values import CONVERT

if TYPE_CHECKING:
    from .compiler import ProjectCompiler

# Predefined constants (ch. 4, Table 4-4).
CONSTANTS = {
    "gpl_cr": ("13", "integer"), "gpl_lf": ("10", "integer"),  # character codes: Chr(GPL_CR)
    "gpl_righty": ("1", "integer"), "gpl_lefty": ("2", "integer"), "gpl_above": ("4", "integer"),
    "gpl_below": ("8", "integer"), "gpl_flip": ("16", "integer"), "gpl_noflip": ("32", "integer"),
    "gpl_single": ("4096", "integer"),
}

# Stores of an operator's result in an Integer or a Double check its range inline (a call
# costs more): out of range is -708 *Value infinite or NAN* for an Integer, -710 *Arithmetic
# overflow* for a Double (L1156; codes of the Brooks error list).
_RANGE_CHECKS = {
    "integer": "(_v if -2147483648 <= (_v := {0}) <= 2147483647 else _overflow(_v, 'Integer'))",
    "double": "(_v if -1.7976931348623157e308 <= (_v := {0}) <= 1.7976931348623157e308 else _overflow(_v, 'Double'))",
}

# Operators done by a helper of values.py, and the type of their result (Table 6-1).
_OPERATOR_HELPERS = {
    "/": ("_div", "double"), "\\": ("_idiv", "integer"), "^": ("_pow", "double"),
    "<<": ("_shl", "integer"), ">>": ("_shr", "integer"),
}


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


def library_has_instances(cls: type) -> bool:
    """A class of only Shared members (Controller, Move, Signal...) defines no constructor."""
    return cls.__init__ is not object.__init__


def library_arity(cls: type, attr: str) -> tuple[int, int]:
    """How many GPL arguments a built-in method takes (not counting self / rt)."""
    return arity(_library_function(cls, attr), 1)


def arity(fn, skip: int) -> tuple[int, int]:
    """How many arguments a Python function takes after its first `skip` (self, rt)."""
    params = list(inspect.signature(fn).parameters.values())[skip:]
    if any(p.kind is p.VAR_POSITIONAL for p in params):
        return sum(p.default is p.empty and p.kind is p.POSITIONAL_OR_KEYWORD for p in params), 99
    return sum(p.default is p.empty for p in params), len(params)


def library_names(test) -> set[str]:
    """The member names (lower case) of built-in classes for which test(cls, attr) holds."""
    return {key for cls in CLASSES.values() for key, attr in cls.gpl_members.items() if test(cls, attr)}


def _is_variable(e: ast.Expr) -> bool:
    """Only variables (and elements, fields) can be passed ByRef (ch. 10)."""
    return isinstance(e, (ast.Name, ast.Member, ast.Call))


class ExpressionCompiler(Scope):
    """The expression half of one procedure's compiler (statements.py has the rest)."""

    def __init__(self, project: "ProjectCompiler", module: ModuleSym, proc: ProcSym | None,
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
        self.blocks: list = []  # statements._Block: statement lists, innermost last
        self.loops: list = []  # statements._Loop: the Python loops around this point
        self.try_depth = 0
        self.me_available = proc is not None and proc.instance
        self.depth = 1  # where hoisted code (ByRef write-backs) goes
        self.references: set[str] = set()  # module and Shared variables read (Const order)
        self.arithmetic: set[str] = set()  # codes of operator results, range-checked when stored

    # ------------------------------------------------------------ output
    def emit(self, depth: int, text: str) -> None:
        self.lines.append("    " * depth + text)
        if self.node is not None and getattr(self.node, "line", 0):
            self.line_map[len(self.lines)] = (self.node.line, self.node.column)

    def fresh(self, stem: str) -> str:
        self.temp += 1
        return f"_{stem}{self.temp}"

    def fail(self, code: int, detail: str, node=None) -> ProgramError:
        if code == UNDEFINED_SYMBOL and isinstance(node, ast.Name) and node.key in keywords():
            # a keyword where no statement takes it (`Next` without `For`) reads as a name
            code, detail = SYNTAX_ERROR, f"unexpected {node.name!r}"
        return _error(code, detail, self.module.file, node or self.node, self.gpl_name)

    def condition(self, e: ast.Expr) -> str:
        code, t = self.expr(e)
        if t is not None and t.is_bool:
            return code
        if t is not None and t.is_number:
            return f"({code} != 0)"
        return f"_truth({code})"

    # ------------------------------------------------------------ stores
    def assign_var(self, var: VarSym, code: str, depth: int) -> None:
        if var.kind in ("module", "shared", "static"):
            self.globals_assigned.add(var.py)
            self.emit(depth, f"{var.py} = {code}")
        elif var.kind == "field":
            self.emit(depth, f"{self.me_code()}.{var.py} = {code}")
        elif var.byref:
            self.emit(depth, f"{var.py}.value = {code}")
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
            if isinstance(func, ast.Member):  # obj.arr(i) = v, obj.Prop(i) = v
                self.store_member(func, target.args, code, vt, depth)
                return
            fcode, ft = self.expr_or_ns(func)
            if ft is not None and ft.is_array:
                if len(target.args) != ft.rank:
                    raise self.fail(INVALID_STATEMENT, f"{len(target.args)} indices for a rank {ft.rank} array")
                self.emit(depth, f"{fcode}[{self.indices(target.args)}] = {self.convert(code, vt, ft.element)}")
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
        ocode, ot = self.expr_or_ns(target.obj, target.key)
        key = target.key
        arg_codes = [self.expr(a)[0] for a in (args or [])]
        if ot is not None and ot.base == "ns":
            owner = ot.ref
            if isinstance(owner, type):  # a built-in class: a shared property (maybe write-only)
                setter = library_member(owner, "set_" + key)
                if setter is None:
                    self.library_attr(owner, key, target)
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
                if code in self.arithmetic and base in _RANGE_CHECKS:
                    return _RANGE_CHECKS[base].format(code)  # Integer overflow -708 / Double overflow -710
                return code
            if base == "double" and vt is not None and vt.is_number and vt.base != "single":
                if vt.base == "double":
                    return _RANGE_CHECKS["double"].format(code) if code in self.arithmetic else code
                return f"float({code})"
            if vt is not None and vt.base in ("user", "lib", "delegate") and not vt.rank:
                raise self.fail(TYPE_MISMATCH, f"{vt} assigned to a {target}")
            return f"{CONVERT[base]}({code})"
        if vt is not None and not vt.rank and (vt.base in BASIC or (
                vt.base in ("user", "lib", "delegate") and (vt.base, vt.ref) != (base, target.ref))):
            raise self.fail(TYPE_MISMATCH, f"{vt} assigned to a {target}")
        return code

    # ------------------------------------------------------------ expressions
    def lookup_value(self, key: str, node):
        if key in self.locals:
            return self.locals[key]
        return self.lookup(key, node)

    def me_code(self) -> str:
        return "me" if self.me_available else "rt.no_me()"

    def expr_or_ns(self, e: ast.Expr, member: str | None = None) -> tuple[str, SType | None]:
        """Like expr, but a module, class or built-in class name gives a namespace
        (`member`: the member that follows, when known)."""
        if isinstance(e, ast.Name):
            sym = self.module_or_variable(self.lookup_value(e.key, e), e.key, member)
            if isinstance(sym, (ModuleSym, ClassSym, DelegateSym)) or isinstance(sym, type):
                return "", ns(sym)
            if sym is None and e.key == "string":
                return "", ns("string")
        if isinstance(e, ast.Member):
            ocode, ot = self.expr_or_ns(e.obj, e.key)
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

    def e_Evaluated(self, e: ast.Evaluated):
        return e.code, e.type

    def e_Me(self, e):
        if not self.me_available:
            return "rt.no_me()", None
        return "me", SType("user", self.cls)

    def module_or_variable(self, sym, key: str, member: str | None):
        """A name that is a module and also a module's only Public variable of that name
        (`Public tray As RefFrame` in Module Tray; names are case-insensitive): the
        module where it has the member that follows, else the variable."""
        if not isinstance(sym, ModuleSym) or (member is not None and sym.member(member) is not None):
            return sym
        found = [m.member(key) for m in self.project.module_order]
        found = [v for v in found if isinstance(v, VarSym) and is_public(v)]
        return found[0] if len(found) == 1 else sym

    def e_Name(self, e: ast.Name):
        sym = self.module_or_variable(self.lookup_value(e.key, e), e.key, None)
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
        if var.kind in ("module", "shared"):
            self.references.add(var.py)
        if var.kind == "field":
            return f"{self.me_code()}.{var.py}"
        if var.byref:
            return f"{var.py}.value"
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
            if not library_has_instances(t.ref):
                raise self.fail(INVALID_STATEMENT, f"{t.ref.gpl_name} has no objects: use its Shared members, "
                                f"{t.ref.gpl_name}.Member", e)
            low, high = arity(t.ref.__init__, 2)
            self.check_count(f"New {t.ref.gpl_name}", low, high, len(args), e)
            codes = self.library_arguments(t.ref.__init__, args, 2, {}, e)
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
                if isinstance(ot.ref, (ModuleSym, ClassSym)) and ot.ref.member(target.key) is None:
                    raise self.fail(UNDEFINED_SYMBOL, f"{ot.ref.name}.{target.name}", target)
                proc = self.member_of_namespace(ot.ref, target.key, target)
            elif ot is not None and ot.base == "user":
                proc = self.class_member(ot.ref, target.key, target)
                me = ocode
            else:
                raise self.fail(TYPE_MISMATCH, "AddressOf needs a procedure", e)
        elif isinstance(target, ast.Name):
            proc = self.lookup_value(target.key, target)
            if proc is None:
                raise self.fail(UNDEFINED_SYMBOL, target.name, target)
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
        return f"_Delegate({proc.py}, {me if proc.instance else 'None'}, {proc.qualified!r}, {len(proc.params)})"

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
    def unchecked(self, code: str) -> str:
        """An operator's result, which may be out of its type's range: checked when stored."""
        self.arithmetic.add(code)
        return code

    def e_Unary(self, e: ast.Unary):
        code, t = self.expr(e.operand)
        if e.op == "-":
            if t is not None and t.is_number:
                return self.unchecked(f"(-{code})"), t
            return f"_neg({code})", SType("double")
        # Not is logical on any value (Table 6-1): False (0) -> True (-1), True (<> 0) -> False
        if t is not None and t.is_bool:
            return f"(not {code})", t
        if t is not None and t.is_number:
            return f"(-1 if {code} == 0 else 0)", SType("integer")
        return f"_not({code})", None

    def e_Binary(self, e: ast.Binary):
        op = e.op
        if op in ("andalso", "orelse"):
            a = self.condition(e.left)
            mark = len(self.lines)
            b = self.condition(e.right)
            if len(self.lines) == mark:
                return f"({a} {'and' if op == 'andalso' else 'or'} {b})", SType("boolean")
            # The right side needed statements first (a ByRef call): run them only
            # when the left side does not decide (short-circuit, Table 6-1).
            first = self.lines[mark:]
            del self.lines[mark:]
            self.line_map = {k: v for k, v in self.line_map.items() if k <= mark}
            temp = self.fresh("sc")
            self.emit(self.depth, f"{temp} = {a}")
            self.emit(self.depth, f"if {'' if op == 'andalso' else 'not '}{temp}:")
            for line in first:
                self.emit(self.depth + 1, line[len("    " * self.depth):])
            self.emit(self.depth + 1, f"{temp} = {b}")
            return temp, SType("boolean")
        a, at = self.expr(e.left)
        b, bt = self.expr(e.right)
        nums = at is not None and bt is not None and at.is_number and bt.is_number
        ints = nums and at.is_integral and bt.is_integral
        result = SType("integer") if ints else SType("double")
        if op == "+":
            if at is not None and bt is not None and at.is_string and bt.is_string:
                return self.unchecked(f"_cat({a}, {b})"), SType("string")
            return self.unchecked(f"({a} + {b})") if nums else self.unchecked(f"_add({a}, {b})"), \
                result if nums else None
        if op in ("-", "*"):
            return self.unchecked(f"({a} {op} {b})" if nums else f"(_num({a}) {op} _num({b}))"), \
                result if nums else SType("double")
        if op in _OPERATOR_HELPERS:
            helper, rtype = _OPERATOR_HELPERS[op]
            code = f"{helper}({a}, {b})"  # / and ^ check their own range; \ gives any int
            return self.unchecked(code) if op == "\\" else code, SType(rtype)
        if op == "mod":
            return f"_mod({a}, {b})", result
        if op == "&":
            if at is not None and bt is not None and at.is_string and bt.is_string:
                return f"_cat({a}, {b})", SType("string")
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
            ocode, ot = self.expr_or_ns(func.obj, func.key)
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
        codes, write_back = [], []
        for a, p in zip(args, dsym.params):
            t = scope.param_type(p, e)
            codes.append(self.reference(a, t, write_back) if p.byref else self.convert(*self.expr(a), t))
        rtype = scope.resolve_type(dsym.return_type, e) if dsym.kind == "function" and dsym.return_type else None
        call = f"(yield from _invoke(rt, {code}, ({', '.join(codes)}{',' if codes else ''})))"
        return self.finish_call(call, write_back), rtype

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
        # obj.Method on Nothing fails here, at the call, not inside the method
        codes = ([self.me_code() if me == "me" else f"_object({me})"] if proc.instance else [])
        write_back: list = []
        for a, p, t in zip(args, proc.params, proc.param_types):
            codes.append(self.reference(a, t, write_back) if p.byref else self.expr(a)[0])
        return self.finish_call(f"(yield from {proc.py}({', '.join(['rt'] + codes)}))", write_back), proc.return_type

    def reference(self, arg: ast.Expr, t: SType, write_back: list) -> str:
        """A ByRef argument (ch. 10): a reference to the caller's variable, so the
        callee reads and writes it where it lives (module variables, fields and
        array elements are shared with other threads: acquire_sem(ByRef lock)
        of ch. 18 needs a real reference).  A local of the caller, which no
        other thread sees, goes in a cell that is copied back after the call."""
        if isinstance(arg, ast.Name):
            sym = self.lookup_value(arg.key, arg)
            if isinstance(sym, VarSym) and not sym.const:
                if sym.byref:
                    return sym.py  # pass the caller's reference on
                if sym.kind in ("module", "shared", "static"):
                    return f"_GlobalRef(globals(), {sym.py!r})"
                if sym.kind == "field":
                    return f"_AttrRef({self.me_code()}, {sym.py!r})"
                for passed, cell, _ in write_back:
                    if isinstance(passed, ast.Name) and passed.key == arg.key:
                        return cell  # f(x, x): both parameters are the one variable
                cell = self.fresh("ref")
                self.emit(self.depth, f"{cell} = _Ref({sym.py})")
                write_back.append((arg, cell, t))
                return cell
        if isinstance(arg, ast.Member):
            ocode, ot = self.expr_or_ns(arg.obj)
            sym = None
            if ot is not None and ot.base == "user" and not ot.rank:
                sym = self.class_member(ot.ref, arg.key, arg)
            elif ot is not None and ot.base == "ns" and isinstance(ot.ref, (ModuleSym, ClassSym)):
                sym = self.member_of_namespace(ot.ref, arg.key, arg)
            if isinstance(sym, VarSym) and not sym.const:
                if sym.kind in ("module", "shared"):
                    return f"_GlobalRef(globals(), {sym.py!r})"
                return f"_AttrRef(_object({ocode}), {sym.py!r})"
        if isinstance(arg, ast.Call):
            fcode, ft = self.expr_or_ns(arg.func)
            if ft is not None and ft.is_array and len(arg.args) == ft.rank:
                index = self.indices(arg.args)
                return f"_ItemRef({fcode}, ({index}{',' if len(arg.args) == 1 else ''}))"
        return f"_Ref({self.expr(arg)[0]})"  # an expression: nothing to write back

    def finish_call(self, call: str, write_back: list) -> str:
        """A call whose ByRef cells must be copied back runs before the statement."""
        if not write_back:
            return call
        temp = self.fresh("r")
        self.emit(self.depth, "try:")
        self.emit(self.depth + 1, f"{temp} = {call}")
        self.emit(self.depth, "finally:  # the callee's writes are the caller's even when it throws")
        for arg, cell, t in write_back:
            self.store(arg, f"{cell}.value", t, self.depth + 1)
        return temp

    def call_member(self, ocode: str, ot: SType | None, func: ast.Member, args, e, statement: bool,
                    no_parens: bool) -> tuple[str, SType | None]:
        key = func.key
        if ot is not None and ot.base == "ns":
            owner = ot.ref
            if owner == "string":
                if key not in STRING_SHARED:
                    raise self.fail(UNDEFINED_SYMBOL, f"String.{func.name}", func)
                return f"_STRING_SHARED[{key!r}]({', '.join(self.arg_codes(args))})", SType("integer")
            if isinstance(owner, type):
                return self.library_call(f"L_{owner.gpl_name.lower()}", owner, key, args, func, shared=True)
            sym = self.member_of_namespace(owner, key, func)
            if isinstance(sym, ProcSym):
                if sym.instance:
                    raise self.fail(INVALID_STATEMENT, f"{sym.name} is not Shared: call it on an object", func)
                return self.call_proc(sym, None, args, e, statement)
            if isinstance(sym, VarSym):
                t = sym.type
                self.references.add(sym.py)
                if t.base == "delegate" and not t.rank and (args or statement):
                    return self.invoke_delegate(sym.py, t.ref, args, e)  # Module.fallback(x)
                if args:
                    return f"{sym.py}[{self.indices(args)}]", t.element
                return sym.py, t
            if isinstance(sym, PropSym):
                return self.get_property(sym, None, args, e)
            raise self.fail(TYPE_MISMATCH, f"{func.name} is not a value", func)
        if ot is not None and ot.is_array:
            return self.array_member(ocode, ot, key, self.arg_codes(args), func)
        if ot is not None and ot.is_string:
            if key not in STRING_MEMBERS:
                raise self.fail(UNDEFINED_SYMBOL, f"String member {func.name}", func)
            _, is_property, rtype = STRING_MEMBERS[key]
            code = f"_STRING[{key!r}]({', '.join([ocode] + self.arg_codes(args))})"
            return code, SType(rtype) if rtype else (SType("string", None, 1) if key == "split" else None)
        if ot is not None and ot.base == "user":
            sym = self.class_member(ot.ref, key, func)
            if isinstance(sym, VarSym):
                where = sym.py if sym.kind == "shared" else f"{ocode}.{sym.py}"
                if sym.kind == "shared":
                    self.references.add(sym.py)
                if sym.type.base == "delegate" and not sym.type.rank and (args or statement):
                    return self.invoke_delegate(where, sym.type.ref, args, e)  # obj.handler(x)
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
            return self.library_call(ocode, ot.ref, key, args, func, shared=False)
        if ot is not None and ot.base in BASIC and not ot.rank:
            raise self.fail(UNDEFINED_SYMBOL, f"{ot} has no member {func.name}", func)
        if args and key in self.project.byref_names:
            return self.untyped_call_with_refs(ocode, key, args)
        codes = self.arg_codes(args)
        call_args = f"({', '.join(codes)}{',' if codes else ''})" if (args or not no_parens) else "None"
        call = f"_callm(rt, {ocode}, {key!r}, {call_args})"
        if key in self.project.waiting:
            return f"(yield from _w({call}))", None
        return call, None

    def untyped_call_with_refs(self, ocode: str, key: str, args) -> tuple[str, None]:
        """obj.key(args) where only the run time knows obj's class (`tc.Client.Receive(buf, n)`)
        and some class has a ByRef member of that name: each variable goes in a
        cell that _callm passes ByRef where the member found takes it so, and
        that is written back to the variable only then."""
        codes, cells = [], []
        for a in args:
            code = self.expr(a)[0]
            if self.assignable(a):
                cell = self.fresh("ref")
                self.emit(self.depth, f"{cell} = _Cell({code})")
                cells.append((cell, a))
                code = cell
            codes.append(code)
        temp = self.fresh("v")
        self.emit(self.depth, f"{temp} = (yield from _w(_callm(rt, {ocode}, {key!r}, ({', '.join(codes)},))))")
        for cell, a in cells:
            self.emit(self.depth, f"if {cell}.passed:")
            self.store(a, f"{cell}.value", None, self.depth + 1)
        return temp, None

    def assignable(self, e: ast.Expr) -> bool:
        """A variable, a field of a user object or an array element (not a function's result)."""
        if isinstance(e, ast.Name):
            sym = self.lookup_value(e.key, e)
            return isinstance(sym, VarSym) and not sym.const
        if isinstance(e, ast.Call):
            return self.assignable(e.func)
        if isinstance(e, ast.Member):
            ot = self.expr_or_ns(e.obj)[1]
            return ot is not None and ot.base == "user" and not ot.rank and \
                isinstance(self.class_member(ot.ref, e.key, e), VarSym)
        return False

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
            raise self.fail(UNDEFINED_SYMBOL, f"{cls.name}.{getattr(node, 'name', key)}", node)
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
            raise self.fail(UNDEFINED_SYMBOL, f"{cls.gpl_name}.{getattr(node, 'name', key)}", node)
        return attr

    def library_call(self, owner_code: str, cls: type, key: str, args, func, shared: bool):
        attr = self.library_attr(cls, key, func)
        kind = _library_kind(cls, attr)
        if shared and kind != "shared":
            raise self.fail(INVALID_STATEMENT, f"{cls.gpl_name}.{func.name} needs an object", func)
        if kind == "property":
            if args:
                raise self.fail(TYPE_MISMATCH, f"{cls.gpl_name}.{func.name} takes no arguments", func)
            return f"{owner_code}.{attr}", None
        low, high = library_arity(cls, attr)
        self.check_count(f"{cls.gpl_name}.{func.name}", low, high, len(args), func)
        refs = []
        for i in sorted(library_byref(cls, attr)):
            if i < len(args) and not isinstance(args[i], ast.Omitted):
                refs.append((self.fresh("ref"), args[i]))
        call_codes = self.library_arguments(_library_function(cls, attr), args, 1,
                                            {id(arg): ref for ref, arg in refs}, func)
        prefix = ["rt"] if kind == "shared" else []
        call = f"{owner_code}.{attr}({', '.join(prefix + call_codes)})"
        if library_waits(cls, attr):
            call = f"(yield from {call})"
        if refs:
            return self.with_refs(call, refs)
        return call, None

    def check_count(self, what: str, low: int, high: int, given: int, node) -> None:
        if not low <= given <= high:
            expected = str(low) if low == high else f"{low} to {high}" if high < 99 else f"at least {low}"
            raise self.fail(WRONG_ARGUMENT_COUNT, f"{what} takes {expected} argument(s), {given} given", node)

    def library_arguments(self, fn, args, skip: int, refs: dict, node) -> list[str]:
        """The argument codes for a built-in's Python function `fn` after its first `skip`
        parameters (self, rt); after an argument left out (`New Thread("w", , "w1")`) the
        rest go by keyword."""
        params = [p for p in list(inspect.signature(fn).parameters.values())[skip:]
                  if p.kind is p.POSITIONAL_OR_KEYWORD]
        codes, by_keyword = [], False
        for i, a in enumerate(args):
            if isinstance(a, ast.Omitted) or (by_keyword and i >= len(params)):
                if i >= len(params) or params[i].default is params[i].empty:
                    raise self.fail(WRONG_ARGUMENT_COUNT, f"argument {i + 1} cannot be left out", a)
                by_keyword = True
                continue
            code = refs.get(id(a)) or self.expr(a)[0]
            codes.append(f"{params[i].name}={code}" if by_keyword else code)
        return codes

    def arg_codes(self, args) -> list[str]:
        return [self.expr(a)[0] for a in args]

    def e_Omitted(self, e: ast.Omitted):
        raise self.fail(INVALID_STATEMENT, "only an optional argument of a built-in member can be left out", e)

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
