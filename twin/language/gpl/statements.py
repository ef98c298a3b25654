"""Statements of the GPL compiler: one procedure -> one Python generator function.

Control structures map onto Python's (ch. 9); loops hand the CPU back every
SLICE_ITERATIONS iterations.  A statement list with labels becomes a dispatch
loop over its segments and GoTo raises `_Jump(block, segment)`, caught there
(a GoTo from a Catch into its Try re-enters the Try: the retry of ch. 11).
An Exit from inside a dispatch loop or a Select's loop raises `_Break(loop)`.
Try/Catch/Finally is Python try/except/finally; a Finally does not run when
the thread is discarded (GeneratorExit).
"""

from __future__ import annotations

from dataclasses import dataclass

from . import ast
from .errors import (
    DUPLICATE_SYMBOL, ILLEGAL_GOTO, INVALID_STATEMENT, TOO_DEEP, TYPE_MISMATCH, UNDEFINED_SYMBOL, UNSUPPORTED,
)
from .expressions import ExpressionCompiler
from .library import CLASSES
from .scope import mangle
from .symbols import SType, VarSym
from .values import CONVERT, DEFAULTS

TRY_BODY, FINALLY = "try", "finally"  # _Block.boundary of a Try's statements and of its Finally
MAX_BLOCK_DEPTH = 64  # nested blocks in a procedure (docs/gpl.md); Python's own limits may stop sooner
SLICE_ITERATIONS = 1024  # loop iterations between time slices, as for V+ tasks


@dataclass
class CompiledUnit:
    """One generated Python function and where its lines came from."""

    name: str  # GPL name for messages: Module.Proc
    py: str
    source: str
    line_map: dict[int, tuple[int, int]]  # generated line -> (GPL line, column)
    file: str


@dataclass
class _Block:
    """A statement list with labels: compiled as a dispatch loop."""

    ident: int
    labels: dict[str, int]  # label -> segment
    boundary: object = False  # TRY_BODY (GoTo out allowed); True (a Catch) or FINALLY: no GoTo out


@dataclass
class _Loop:
    kind: str  # "for", "while", "do", "select", "dispatch"
    ident: int
    step: tuple | None = None  # For: (var node, step name) for Continue For
    post: tuple | None = None  # Do ... Loop While/Until: the test Continue Do goes to


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


def _nested_bodies(s) -> list[list]:
    """The statement lists inside s, in source order."""
    out = []
    if isinstance(s, ast.If):
        out.extend(b for _, b in s.branches)
    if isinstance(s, ast.Select):
        out.extend(b for _, b in s.cases)
    for attr in ("body", "catch_body", "finally_body", "orelse", "default"):
        inner = getattr(s, attr, None)
        if isinstance(inner, list):
            out.append(inner)
    return out


def _walk(body: list):
    for s in body:
        yield s
        for inner in _nested_bodies(s):
            yield from _walk(inner)


class ProcCompiler(ExpressionCompiler):
    """Generates one Python function."""

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
        self.check_depth(node.body)
        self.collect_locals(node.body)
        self.node = node
        self.emit(0, f"def {self.py}({', '.join(params)}):")
        self.emit(1, "if False: yield")
        for p, t in zip(proc.params, proc.param_types):
            if t.base in CONVERT and not t.rank and not p.byref:
                self.emit(1, f"a_{p.key} = {CONVERT[t.base]}(a_{p.key})")
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

    def check_depth(self, body: list[ast.Statement]) -> None:
        """Blocks nested more than MAX_BLOCK_DEPTH deep are -2014 at the first statement
        that deep (found without recursion; the compiler itself recurses per block)."""
        pending = [(body, 1)]
        while pending:
            statements, depth = pending.pop()
            for s in statements:
                inner = _nested_bodies(s)
                if inner and depth >= MAX_BLOCK_DEPTH:
                    raise self.fail(TOO_DEEP, f"blocks nested more than {MAX_BLOCK_DEPTH} deep", s)
                pending.extend((b, depth + 1) for b in inner)

    def collect_locals(self, body: list[ast.Statement]) -> None:
        """Every Dim of the procedure, also one inside a block (If, For, Select... as
        Precise's own code writes them): its scope is the whole procedure, and the
        same name declared in two blocks with the same type is one variable."""
        top = {id(s) for s in body}
        for s in _walk(body):
            if isinstance(s, ast.Declare):
                self.declare_locals(s, nested=id(s) not in top)
            if isinstance(s, ast.Try) and s.catch_type is not None:
                self.declare_implicit(s.catch_var, s.catch_type, s)
            if isinstance(s, ast.For) and s.var_type is not None and isinstance(s.var, ast.Name):
                self.declare_implicit(s.var.name, s.var_type, s)

    def declare_implicit(self, name: str, type_ref: ast.TypeRef, node) -> None:
        """A local declared by `Catch e As Exception` or `For i As Integer`."""
        if name.lower() not in self.locals:
            self.locals[name.lower()] = VarSym(name, self.resolve_type(type_ref, node), "local", f"l_{name.lower()}")

    def declare_locals(self, s: ast.Declare, nested: bool = False) -> None:
        for d in s.items:
            t = self.declarator_type(d)
            known = self.locals.get(d.key)
            if known is not None:
                if nested and known.kind == "local" and known.type == t and known.decl is not None:
                    continue  # the same block variable declared again in another block
                raise self.fail(DUPLICATE_SYMBOL, d.name, d)
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
                    # initialised the first time the Static statement runs, then kept
                    done = f"{var.py}__set"
                    self.project.statics[done] = False
                    self.globals_assigned.update((var.py, done))
                    self.emit(depth, f"if not {done}:")
                    self.emit(depth + 1, f"{done} = True")
                    self.emit(depth + 1, f"{var.py} = {self.initial_value(var, d)}")
                continue
            if d.init is None and not d.new and not (d.bounds and any(b is not None for b in d.bounds)):
                continue
            self.emit(depth, f"{var.py} = {self.initial_value(var, d)}")

    def s_Assign(self, s: ast.Assign, depth: int) -> None:
        value = s.value
        target = s.target
        if s.op != "=":
            op = {"^=": "^", "*=": "*", "/=": "/", "\\=": "\\", "+=": "+", "-=": "-", "<<=": "<<",
                  ">>=": ">>", "&=": "&"}[s.op]
            target = self.evaluated_once(target, depth)
            value = ast.Binary(op, target, s.value)
            value.line, value.column = s.line, s.column
        code, vt = self.expr(value)
        self.store(target, code, vt, depth)

    def evaluated_once(self, target: ast.Expr, depth: int) -> ast.Expr:
        """The target of a compound assignment with its indices and object computed once
        (`a(f()) += 1` calls f once, as VB.NET does)."""
        if isinstance(target, ast.Call):
            func = self.evaluated_once(target.func, depth) if isinstance(target.func, ast.Member) else target.func
            args = [self.temporary(a, depth) for a in target.args]
            return ast.Call(func, args, target.line, target.column)
        if isinstance(target, ast.Member) and not isinstance(target.obj, (ast.Name, ast.Me)):
            code, t = self.expr_or_ns(target.obj, target.key)
            if t is not None and t.base == "ns":
                return target
            return ast.Member(ast.Evaluated(code=self.hold(code, depth), type=t),
                              target.name, target.line, target.column)
        return target

    def temporary(self, e: ast.Expr, depth: int) -> ast.Expr:
        if isinstance(e, (ast.Literal, ast.Name, ast.Evaluated)):
            return e
        code, t = self.expr(e)
        return ast.Evaluated(code=self.hold(code, depth), type=t)

    def hold(self, code: str, depth: int) -> str:
        temp = self.fresh("once")
        self.emit(depth, f"{temp} = {code}")
        return temp

    def s_CallStatement(self, s: ast.CallStatement, depth: int) -> None:
        e = s.expr
        if isinstance(e, ast.Call):
            code, _ = self.call(e, statement=True)
        elif isinstance(e, (ast.Name, ast.Member)):
            code, _ = self.call(ast.Call(e, [], e.line, e.column), statement=True)
        else:
            raise self.fail(INVALID_STATEMENT, "an expression is not a statement", s)
        self.emit(depth, code)

    def capture(self, depth: int, compile_condition) -> tuple[str, list[str]]:
        """Compile a condition; also return (and take out of the output) the
        statements it needs first (a call with ByRef arguments, expressions.py),
        so that a loop can run them before every test, not once."""
        saved, self.depth = self.depth, depth
        mark = len(self.lines)
        code = compile_condition()
        extra = self.lines[mark:]
        del self.lines[mark:]
        self.line_map = {k: v for k, v in self.line_map.items() if k <= mark}
        self.depth = saved
        indent = len("    " * depth)
        return code, [line[indent:] for line in extra]

    def emit_lines(self, depth: int, lines: list[str]) -> None:
        for line in lines:
            self.emit(depth, line)

    def s_If(self, s: ast.If, depth: int) -> None:
        self.if_chain(s, s.branches, depth)

    def if_chain(self, s: ast.If, branches: list, depth: int) -> None:
        keyword = "if"
        for i, (cond, body) in enumerate(branches):
            self.node = s
            code, first = self.capture(depth, lambda: self.condition(cond))
            if first and keyword == "elif":  # ElseIf whose test needs statements: else + a nested If
                self.emit(depth, "else:")
                self.if_chain(s, branches[i:], depth + 1)
                return
            self.emit_lines(depth, first)
            self.emit(depth, f"{keyword} {code}:")
            self.block(body, depth + 1)
            keyword = "elif"
        if s.orelse:
            self.node = s
            self.emit(depth, "else:")
            self.block(s.orelse, depth + 1)

    def loop_test(self, depth: int, cond: ast.Expr, until: bool) -> None:
        """`if <loop is over>: break` at the top or bottom of a loop body."""
        code, first = self.capture(depth, lambda: self.condition(cond))
        self.emit_lines(depth, first)
        self.emit(depth, f"if {code if until else f'not {code}'}: break")

    def slice_check(self, depth: int) -> None:
        """Give the CPU back now and then, as the controller time-slices threads."""
        self.emit(depth, "_slice += 1")
        self.emit(depth, f"if _slice >= {SLICE_ITERATIONS}:")
        self.emit(depth + 1, "_slice = 0")
        self.emit(depth + 1, "yield rt.SLICE")

    def loop_body(self, s, kind: str, body: list, depth: int, step=None, post=None) -> _Loop:
        loop = _Loop(kind, id(s), step=step, post=post)
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
        self.emit(depth, "while True:")
        self.loop_test(depth + 1, s.condition, until=False)

        def body(d):
            self.loop_body(s, "while", s.body, d)
            self.slice_check(d)

        self.with_exit_catch(s, depth + 1, body)

    def s_Do(self, s: ast.Do, depth: int) -> None:
        self.emit(depth, "while True:")
        if s.pre is not None:
            kind, cond = s.pre
            self.loop_test(depth + 1, cond, until=kind == "until")

        def body(d):
            self.loop_body(s, "do", s.body, d, post=s.post)
            if s.post is not None:
                self.node = s
                kind, cond = s.post
                self.loop_test(d, cond, until=kind == "until")
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
            self.block(s.body, inner + 1, dispatch_var=pc, boundary=TRY_BODY)
            self.node = s
            self.emit(inner, "except Exception as _e:  # not the _Control jumps (BaseException)")
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
            self.block(s.body, inner, boundary=TRY_BODY)
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
            self.blocks.append(_Block(-1, {}, FINALLY))
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
            if block.boundary and block.boundary is not TRY_BODY:
                break  # out of the try_statements is allowed (the Finally runs), not out of a Catch or Finally
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
                if self.loops[i + 1:]:  # a Python `continue` would go on with the inner loop
                    raise self.fail(UNSUPPORTED, "Continue from an inner loop, a block with labels or an "
                                    "Exit Select", s)
                # what the end of the body does: the next For value, the Loop test, a slice
                if loop.step is not None:
                    var, step = loop.step
                    code, _ = self.expr(var)
                    self.store(var, f"{code} + {step}", None, depth)
                if loop.post is not None:
                    kind, cond = loop.post
                    self.loop_test(depth, cond, until=kind == "until")
                self.slice_check(depth)
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
            self.store(target.func, f"_redim({code}, ({dims},), {default!r}, {s.preserve})", t, depth)
