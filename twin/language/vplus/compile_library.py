"""Compiling the library's statement forms (a mixin of `ProgramCompiler`).

* `IoStatement`: `KEYWORD (unit...) items` -> `I[name](rt, (unit...), (items...))`.
  READ's items are variables: the instruction returns one value per variable
  (None leaves it unchanged, as after an end of file) and the compiled code
  assigns them.  ATTACH (lun, 4) returns the unit it picked, written into lun,
  which may still be undefined before the statement.
* `KeyedAssign`: `KEYWORD args = value` -> `I[name](rt, value, args...)`.
* GETC(lun) in wait mode: a function cannot wait, so the step (or the
  condition of IF, WHILE, UNTIL, CASE) first waits (`yield from`) until the
  unit has a byte, then runs; GETC finds it there.
* Functions that assign to their first argument ($DECODE, TAS) return
  (result, new value); the expression stores the new value with `:=`, so an
  AUTO variable (a Python local) can be written from inside an expression.
"""

from __future__ import annotations

import dataclasses
import math

from . import ast
from . import messages as msg
from .keywords import (FUNCTIONS, INSTRUCTIONS, NAME_ARGUMENTS, STRING_FUNCTIONS, WRITES_FIRST_ARGUMENT,
                       argument_check, arity)

FORMAT_ARGUMENTS = {"$ENCODE"}  # arguments are TYPE items: expressions and /I0, /F8.3 ...
ARRAY_ARGUMENTS = {"$UNPACK", "SOLVE.FLAGS"}  # the first argument a[i] (a[]) is passed as (array, index)
FORMAT_CODES = set("SCXBUNDFEGHOI")  # formats.py renders each of them
# Field widths and repeat counts (/I10, /C2, /X40) at most this: wider than any terminal
# line or record (the guides set no number; a larger one is a load-time *Syntax error*).
MAX_FORMAT_WIDTH = 255
LIBRARY_CALLS = WRITES_FIRST_ARGUMENT | NAME_ARGUMENTS | FORMAT_ARGUMENTS | ARRAY_ARGUMENTS


def _calls(node, name: str):
    """The calls of `name` in a simple statement's expressions."""
    if isinstance(node, ast.Call) and node.name == name:
        yield node
    if isinstance(node, list):
        for item in node:
            yield from _calls(item, name)
    elif dataclasses.is_dataclass(node):
        for f in dataclasses.fields(node):
            yield from _calls(getattr(node, f.name), name)


# Device keywords whose argument at this position is a variable that receives the
# device's error status ([001] "Using DEVICE and SETDEVICE": SETDEVICE (0, unit, error,
# command), DEVICE(0, unit, error, select)): it may be undefined before, and gets 0 (no
# error: the twin's encoders never fail) when the keyword has done its work.
ERROR_OUTPUT = {"SETDEVICE": 2, "DEVICES": 2, "DEVICE": 2}


class LibraryStatements:
    # ------------------------------------------------------------ statements
    def s_IoStatement(self, s: ast.IoStatement, depth: int) -> None:
        spec = INSTRUCTIONS.get(s.name)
        if spec is None:
            raise self.error(s, msg.UNKNOWN_KEYWORD, s.name)
        unit = ["None" if a is None else self.expr(a) for a in s.unit]
        error_var = self.error_output(s.name, s.unit)
        if error_var is not None:
            unit[ERROR_OUTPUT[s.name]] = self.peek(error_var)
        unit_var = s.unit[0] if s.unit and isinstance(s.unit[0], ast.Var) else None
        if spec.returns_unit and unit_var is not None:
            unit[0] = self.peek(unit_var)
        handle_var = s.unit[1] if spec.writes_back and len(s.unit) > 1 and isinstance(s.unit[1], ast.Var) else None
        if handle_var is not None:
            unit[1] = self.peek(handle_var)
        if spec.targets:
            if not all(isinstance(item, ast.Var) for item in s.items):
                raise self.error(s, msg.INVALID_ARGUMENT, f"{s.name} needs variables")
            items = [repr("s" if item.name.startswith("$") else "r") for item in s.items]
        else:
            items = [self.io_item(item) for item in s.items]
        result = self.fresh("io")
        call = f"I[{s.name!r}](rt, ({''.join(u + ', ' for u in unit)}), ({''.join(i + ', ' for i in items)}))"
        self.emit(depth, f"{result} = {'yield from ' if spec.waits else ''}{call}")
        if spec.targets:
            for i, item in enumerate(s.items):
                self.emit(depth, f"if {result}[{i}] is not None:")
                self.assign(item, f"{result}[{i}]", depth + 1)
        if handle_var is not None:
            self.emit(depth, f"if {result}[-1] is not None:")
            self.assign(handle_var, f"{result}[-1]", depth + 1)
        if spec.returns_unit and unit_var is not None:
            self.emit(depth, f"if {result} is not None:")
            self.assign(unit_var, result, depth + 1)
        if error_var is not None:
            self.assign(error_var, "0.0", depth)

    def error_output(self, name: str, args: list) -> ast.Var | None:
        """The variable that receives a device keyword's error status, if one is given."""
        position = ERROR_OUTPUT.get(name)
        if position is None or len(args) <= position:
            return None
        var = args[position]
        return var if isinstance(var, ast.Var) and var.indices != [] and not self.reserved(var) else None

    def io_item(self, item) -> str:
        """A TYPE, WRITE or $ENCODE item: an expression or a format specifier."""
        if isinstance(item, ast.Format):
            if item.code not in FORMAT_CODES:
                raise self.error(self.current, msg.SYNTAX_ERROR, f"unknown format /{item.code}")
            if max(item.width or 0, item.decimals or 0) > MAX_FORMAT_WIDTH:
                raise self.error(self.current, msg.SYNTAX_ERROR, f"format width above {MAX_FORMAT_WIDTH}")
            return f"_fmt({item.code!r}, {item.width!r}, {item.decimals!r})"
        return self.expr(item)

    def s_KeyedAssign(self, s: ast.KeyedAssign, depth: int) -> None:
        spec = INSTRUCTIONS.get(s.name)
        if spec is None:
            raise self.error(s, msg.UNKNOWN_KEYWORD, s.name)
        values = [s.value, *s.more]  # the values after "=" come first
        fewest, most = arity(spec.function)
        self.argument_count(f"{s.name} ... =", s.args, max(fewest - len(values), 0), most - len(values))
        passed = []
        for i, v in enumerate(values):
            if i in spec.array_values:
                if not isinstance(v, ast.Var) or v.indices is None:
                    raise self.error(s, msg.INVALID_ARGUMENT, f"{s.name} needs an array")
                passed.append(self.array_ref(v))
            elif i in spec.name_values and isinstance(v, ast.Var) and v.indices is None:
                passed.append(repr(v.name))
            else:
                passed.append(self.checked(v, argument_check(spec.function, i), s.name))
        writes = []  # (position, variable) of the plain variables the instruction sets
        for i, a in enumerate(s.args):
            if a is None:
                passed.append("None")
            elif spec.names and isinstance(a, ast.Var):
                passed.append(repr(a.name.upper()))
            elif spec.targets and isinstance(a, ast.Var) and a.indices is not None:
                passed.append(self.array_ref(a))
            elif spec.writes_back and isinstance(a, ast.Var):
                passed.append(self.peek(a))
                writes.append((i, a))
            else:
                passed.append(self.checked(a, argument_check(spec.function, len(passed)), s.name))
        call = f"I[{s.name!r}](rt{''.join(', ' + a for a in passed)})"
        if not writes:
            self.emit(depth, call)
            return
        result = self.fresh("kw")
        self.emit(depth, f"{result} = {call}")
        for i, var in writes:
            self.emit(depth, f"if {result} is not None and {result}[{i}] is not None:")
            self.assign(var, f"{result}[{i}]", depth + 1)

    def wait_for_input(self, node, depth: int) -> None:
        """Wait before a simple statement, or before a condition (IF, WHILE,
        UNTIL, CASE, IF ... GOTO) is evaluated, for the GETCs in it."""
        for call in _calls(node, "GETC"):
            # The mode is bit flags: 1 no-wait, 2 no echo (v17 L7224-7225,
            # L7530-7533); GETC(lun, 2) waits, as the ROS-Industrial driver's does.
            mode = call.args[1] if len(call.args) > 1 else None
            if not call.args or call.args[0] is None:
                continue
            wait = f"yield from rt.system.devices.wait_for_byte(rt, {self.expr(call.args[0])})"
            if mode is None or (isinstance(mode, ast.Num) and not math.floor(mode.value + 0.5) & 1):
                self.emit(depth, wait)
            elif not isinstance(mode, ast.Num):
                self.emit(depth, f"if not _no_wait({self.checked(mode, '_real', 'GETC')}):")
                self.emit(depth + 1, wait)

    # ----------------------------------------------------------- references
    def peek(self, var: ast.Var) -> str:
        """The variable's (or array element's) value, or None while it is undefined."""
        key = self.key(var)
        if var.indices:
            if key in self.scope.auto:
                return f"{self.pyname(var)}.get({self.index(var.indices)})"
            table = "L" if key in self.scope.local else "G"
            return f"_element_or_none({table}, {key!r}, {self.index(var.indices)})"
        if key in self.scope.auto:
            return f"locals().get({self.pyname(var)!r})"
        return f"{'L' if key in self.scope.local else 'G'}.get({key!r})"

    def array_store(self, var: ast.Var) -> str:
        whole = ast.Var(var.name, [])
        key = self.key(whole)
        if key in self.scope.auto:
            return self.pyname(whole)
        return f"_array({'L' if key in self.scope.local else 'G'}, {key!r})"

    def array_ref(self, var: ast.Var) -> str:
        """(array, index) for `a[i]`, (array, None) for the whole array `a[]`."""
        index = self.index(var.indices) if var.indices else "None"
        return f"({self.array_store(var)}, {index})"

    def assign_expr(self, var: ast.Var, value: str) -> str:
        """An expression that stores `value` in `var`."""
        if var.indices:
            return f"{self.array_store(var)}.__setitem__({self.index(var.indices)}, {value})"
        key = self.key(var)
        if key in self.scope.auto:
            return f"({self.pyname(var)} := {value})"
        return f"{'L' if key in self.scope.local else 'G'}.__setitem__({key!r}, {value})"

    def library_call(self, e: ast.Call) -> str:
        if e.name in FORMAT_ARGUMENTS:
            return f"F[{e.name!r}](rt{''.join(', ' + self.io_item(a) for a in e.args)})"
        if e.name in ARRAY_ARGUMENTS:
            first = e.args[0] if e.args else None
            if not isinstance(first, ast.Var) or first.indices is None or (e.name == "$UNPACK" and not first.indices):
                raise self.error(self.current, msg.INVALID_ARGUMENT, f"{e.name} needs an array element")
            function = (STRING_FUNCTIONS if e.name.startswith("$") else FUNCTIONS)[e.name]
            rest = "".join(", " + self.checked(a, argument_check(function, i), e.name)
                           for i, a in enumerate(e.args[1:], start=1))
            return f"F[{e.name!r}](rt, {self.array_ref(first)}{rest})"
        if e.name in NAME_ARGUMENTS:
            # A bare name is the name itself; anything else (a string) is evaluated.
            args = [repr(a.name.upper()) if isinstance(a, ast.Var) and a.indices is None
                    else "None" if a is None else self.expr(a) for a in e.args]
            return f"F[{e.name!r}](rt{''.join(', ' + a for a in args)})"
        if not e.args or not isinstance(e.args[0], ast.Var):
            raise self.error(self.current, msg.INVALID_ARGUMENT, f"{e.name} needs a variable")
        result = self.fresh("wb")
        function = (STRING_FUNCTIONS if e.name.startswith("$") else FUNCTIONS)[e.name]
        args = ", ".join([self.expr(e.args[0])] + [self.checked(a, argument_check(function, i), e.name)
                                                   for i, a in enumerate(e.args[1:], start=1)])
        return f"({result} := F[{e.name!r}](rt, {args}), {self.assign_expr(e.args[0], f'{result}[1]')})[0][0]"
