"""V+ source text -> AST.

`parse(text, file)` runs the lark grammar in `vplus.lark` (LALR, built once and
cached), turns the parse tree into the dataclasses of `ast.py` and nests the
block statements.  Syntax errors become `ProgramError`s with the file, line,
column and offending text, and the V+ message.
"""

from __future__ import annotations

import math
from functools import lru_cache
from importlib.resources import files
from pathlib import Path

from lark import Lark, Token, Transformer_NonRecursive, Tree, v_args
from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedInput, UnexpectedToken, VisitError

from ...errors import ProgramError
from ..lalr import lalr_parser
from . import ast
from . import messages as msg
from .keywords import STRING_FUNCTIONS
from .structure import nest

NAME_LENGTH = 15  # significant characters of a V+ name, not counting the prefix
MAX_LABEL = 65535  # step labels are integers 0 to 65535 ([000] L805-808)


@lru_cache(maxsize=1)
def _parser() -> Lark:
    grammar = files(__package__).joinpath("vplus.lark").read_text()  # packaged beside this module
    return lalr_parser(grammar, "vplus")


def normalize_name(text: str) -> str:
    """V+ names are case-insensitive and only 15 characters are significant."""
    text = text.lower()
    prefix = text[0] if text[0] in "$#%" else ""
    return prefix + text[len(prefix) :][:NAME_LENGTH]


# AUTO REAL x, LOCAL DOUBLE d, GLOBAL LOC spot: REAL a single-precision real, DOUBLE 64 bits,
# LOC a location (a transformation, or a precision point for a # name).
DECLARATION_TYPES = ("REAL", "DOUBLE", "LOC")
UTF8_BOM = b"\xef\xbb\xbf"
# Monitor commands of a command program ("MC" lines) that do what the program
# instruction of the same name does.
MONITOR_INSTRUCTIONS = ("EXECUTE", "ABORT", "KILL", "PROCEED", "ENABLE", "DISABLE", "CALIBRATE", "SIGNAL",
                        "PARAMETER", "WAIT.START")
BINARY_DIGITS = 8  # "^B ... binary (maximum of 8 bits)", [000] L3903-3905


def parse_number(text: str) -> float:
    """Decimal, ^H hex, ^B binary, ^D double and plain ^ octal constants;
    ValueError for digits the radix does not have."""
    if not text.startswith("^"):
        return float(text)
    body = text[1:]
    radix = {"H": 16, "B": 2, "D": 10}.get(body[:1].upper())
    if radix is None:
        return float(int(body, 8))
    body = body[1:]
    if radix == 2 and len(body) > BINARY_DIGITS:
        raise ValueError(f"more than {BINARY_DIGITS} binary digits")
    return float(body) if radix == 10 else float(int(body, radix))


def _pos(meta_or_token) -> dict:
    return {"line": meta_or_token.line, "column": meta_or_token.column}


@v_args(meta=True)
class _ToAst(Transformer_NonRecursive):  # long expressions make deep trees
    """Parse tree -> AST.  Statements come out flat, one per line."""

    # ---- expressions
    def number(self, meta, children):
        text = str(children[0])
        try:
            value = parse_number(text)
        except ValueError:
            raise ProgramError(f"{msg.message(msg.SYNTAX_ERROR)} bad number {text}", msg.SYNTAX_ERROR,
                               line=meta.line, column=meta.column) from None
        if not math.isfinite(value):  # 1E400: beyond even a DOUBLE ([000] L3868-3895)
            raise ProgramError(f"{msg.message(msg.OVERFLOW)} {text} is beyond the range of a real",
                               msg.OVERFLOW, line=meta.line, column=meta.column)
        return ast.Num(value, double=text[:2].upper() == "^D")

    def string(self, meta, children):
        return ast.Str(str(children[0])[1:-1])

    def ascii_const(self, meta, children):
        return ast.Num(float(ord(str(children[0])[1])))

    def variable(self, meta, children):
        name = normalize_name(str(children[0]))
        if len(children) == 1:
            return ast.Var(name)
        indices = [c for c in children[1:] if c is not None]
        return ast.Var(name, indices)

    def paren(self, meta, children):
        inner = children[0]
        if isinstance(inner, ast.Var):
            return ast.Var(inner.name, inner.indices, parenthesized=True)
        return inner

    def variable_ref(self, meta, children):
        return ast.Var(normalize_name(str(children[0])))

    def array_ref(self, meta, children):
        return ast.Var(normalize_name(str(children[0])), [])

    def call(self, meta, children):
        return ast.Call(str(children[0]).upper(), children[1])

    def arglist(self, meta, children):
        return [] if children == [None] else list(children)

    def shift_call(self, meta, children):
        return ast.ByCall(str(children[0]).upper(), children[1], list(children[2:]))

    def binary(self, meta, children):
        left, op, right = children
        op = str(op).upper()
        return ast.Binary({"=<": "<=", "=>": ">="}.get(op, op), left, right)

    def neg(self, meta, children):
        operand = children[0]
        if isinstance(operand, ast.Num):
            return ast.Num(-operand.value, operand.double)
        return ast.Unary("-", operand)

    def not_(self, meta, children):
        return ast.Unary("NOT", children[1])

    def com(self, meta, children):
        return ast.Unary("COM", children[1])

    def compound_(self, meta, children):
        return ast.Compound(children[0], children[1])

    # ---- statements
    def line(self, meta, children):
        label, statement = children
        if statement is None:
            if label is None:
                return None
            statement = ast.LabelOnly(**_pos(label))
        if label is not None:
            statement.label = int(str(label).strip())
            if statement.label > MAX_LABEL:
                raise ProgramError(f"{msg.message(msg.SYNTAX_ERROR)} step label {statement.label} (0 to {MAX_LABEL})",
                                   msg.SYNTAX_ERROR, line=label.line, column=label.column)
        return statement

    def assignment(self, meta, children):
        return ast.Assign(children[0], children[1], **_pos(meta))

    def set_statement(self, meta, children):
        return ast.SetLocation(children[0], children[1], **_pos(meta))

    def here_statement(self, meta, children):
        """HERE frame:loc is SET loc = INVERSE(frame):HERE ([000] "HERE" in the summary of
        location instructions); HERE #p reads the joints (#PHERE)."""
        *frames, target = children
        value = ast.Call("#PHERE" if target.name.startswith("#") else "HERE", [])
        if frames:
            frame = frames[0]
            for f in frames[1:]:
                frame = ast.Compound(frame, f)
            value = ast.Compound(ast.Call("INVERSE", [frame]), value)
        return ast.SetLocation(target, value, **_pos(meta))

    def declaration(self, meta, children):
        scope, kind, *items = children
        if kind is not None:
            kind_name = str(kind).upper()
            if kind_name not in DECLARATION_TYPES:
                raise ProgramError(f"{msg.message(msg.SYNTAX_ERROR)} unknown type {kind} (REAL, DOUBLE or LOC)",
                                   msg.SYNTAX_ERROR, line=kind.line, column=kind.column)
            kind = kind_name
        return ast.Declare(str(scope).upper(), kind == "DOUBLE", [i for i in items if i is not None], kind=kind,
                           **_pos(meta))

    def decl_item(self, meta, children):
        dims = [c for c in children[1:] if c is not None]
        return (ast.Var(normalize_name(str(children[0]))), dims or None)

    def if_goto(self, meta, children):
        return ast.IfGoto(children[0], int(children[1]), **_pos(meta))

    def if_then(self, meta, children):
        return ast.IfThen(children[0], **_pos(meta))

    def else_clause(self, meta, children):
        return ast.Else(**_pos(meta))

    def end_clause(self, meta, children):
        return ast.End(**_pos(meta))

    def for_statement(self, meta, children):
        return ast.ForHead(children[0], children[1], children[2], children[3], **_pos(meta))

    def while_statement(self, meta, children):
        return ast.WhileHead(children[0], **_pos(meta))

    def do_statement(self, meta, children):
        return ast.DoHead(**_pos(meta))

    def until_statement(self, meta, children):
        return ast.UntilTail(children[0], **_pos(meta))

    def case_statement(self, meta, children):
        return ast.CaseHead(children[0], **_pos(meta))

    def value_clause(self, meta, children):
        return ast.ValueClause([c for c in children if not isinstance(c, Token)], **_pos(meta))

    def any_clause(self, meta, children):
        return ast.AnyClause(**_pos(meta))

    def goto_statement(self, meta, children):
        return ast.Goto(int(children[0]), **_pos(meta))

    def call_statement(self, meta, children):
        return ast.CallProgram(normalize_name(str(children[0])), children[1] or [], **_pos(meta))

    def calls_statement(self, meta, children):
        """CALLS $program_name(length, width) ([000] "CALLS"): the string variable names
        the program and the arguments follow it."""
        name, args = children
        if args is None and isinstance(name, ast.Call) and name.name not in STRING_FUNCTIONS:
            name, args = ast.Var(normalize_name(name.name)), name.args
        return ast.CallProgram(None, args or [], name_expr=name, **_pos(meta))

    def type_statement(self, meta, children):
        items = [c for c in children if c is not None]
        return ast.TypeOut(items, **_pos(meta))

    def format_item(self, meta, children):
        text = str(children[0])[1:]
        code, spec = text[0].upper(), text[1:]
        width = decimals = None
        if spec:
            whole, _, frac = spec.partition(".")
            width = int(whole)
            decimals = int(frac) if frac else None
        return ast.Format(code, width, decimals)

    def prompt_statement(self, meta, children):
        return ast.Prompt(children[0], list(children[1:]), **_pos(meta))

    def parameter_statement(self, meta, children):
        name, index, value = children
        return ast.Parameter(name, index, value, **_pos(meta))

    def dotted_name(self, meta, children):
        return str(children[0]).upper()

    def speed_statement(self, meta, children):
        value, rotation, *mods = children
        return ast.Speed(value, rotation, [str(m).upper() for m in mods], **_pos(meta))

    def execute_statement(self, meta, children):
        task, name, args, options = children
        return ast.ExecuteProgram(task, normalize_name(str(name)), args or [], options or [], **_pos(meta))

    def instruction(self, meta, children):
        name, args, always = children
        return ast.Instruction(str(name).upper(), args, always is not None, **_pos(meta))

    def profiled_instruction(self, meta, children):
        name, first, args = children
        return ast.Instruction(str(name).upper(), args, parenthesised=first, **_pos(meta))

    # ---- I/O and keyed statements (lang-library)
    def io_statement(self, meta, children):
        name, unit, *items = children
        return ast.IoStatement(str(name).upper(), unit, [i for i in items if i is not None], **_pos(meta))

    def keyed_assignment(self, meta, children):
        name, args, value, *more = children
        return ast.KeyedAssign(str(name).upper(), args, value, more, **_pos(meta))

    def mc_statement(self, meta, children):
        """MC command: a monitor command that is also a program instruction (EXECUTE,
        ENABLE, CALIBRATE...) is that instruction; monitor SPEED sets the monitor speed
        (SPEED n MONITOR); the others are MonitorCommand (runtime.py)."""
        token = children[0]
        text = str(token)[2:].strip()
        word = text.split(None, 1)[0].upper()
        if word == "SPEED":
            text += " MONITOR"
        elif word not in MONITOR_INSTRUCTIONS:
            return ast.MonitorCommand(word, text, **_pos(token))
        try:
            program = _parser().parse(f".PROGRAM mc()\n{text}\n.END\n").children[0]
        except UnexpectedInput:
            raise ProgramError(f"{msg.message(msg.SYNTAX_ERROR)} monitor command {text!r}",
                               msg.SYNTAX_ERROR, line=token.line, column=token.column) from None
        line = next(child for child in program.children if isinstance(child, Tree) and child.data == "line")
        statement = self.transform(line.children[1])
        statement.line, statement.column = token.line, token.column
        return statement

    def encode_call(self, meta, children):
        return ast.Call("$ENCODE", [c for c in children[1:] if c is not None])

    # ---- units
    def param(self, meta, children):
        return children[0]

    def program(self, meta, children):
        name = normalize_name(str(children[0]))
        params = [c for c in children[1:] if isinstance(c, ast.Var)]
        body = [c for c in children[1:] if isinstance(c, ast.Statement)]
        return ast.Program(name, params, body, file="", line=meta.line)

    def data_line(self, meta, children):
        return None if children[0] is None else (children[0].line, str(children[0]).strip())

    def data_section(self, meta, children):
        kind = str(children[0])[1:].upper()
        return ast.DataSection(kind, [c for c in children[1:] if c is not None], file="")

    def start(self, meta, children):
        return children


def _syntax_error(err: UnexpectedInput, text: str, file: str) -> ProgramError:
    lines = text.splitlines()
    line = getattr(err, "line", None)
    column = getattr(err, "column", None)
    if isinstance(err, UnexpectedEOF) or line is None or line < 1:
        line = len(lines)
        column = 1
    source = lines[line - 1] if 0 < line <= len(lines) else ""
    if isinstance(err, UnexpectedToken) and err.token.type == "$END":
        detail = "unexpected end of file (a .PROGRAM or data section without its .END)"
    elif isinstance(err, UnexpectedToken):
        got = str(err.token).strip()  # a line end is blank
        detail = f"unexpected {got!r}" if got else "unexpected end of line"
    elif isinstance(err, UnexpectedCharacters):
        detail = f"unexpected character {source[column - 1:column]!r}" if column else "unexpected character"
    else:
        detail = "unexpected end of file"
    return ProgramError(
        f"{msg.message(msg.SYNTAX_ERROR)} {detail}",
        msg.SYNTAX_ERROR,
        file=file,
        line=line,
        column=column,
        text=source,
    )


def parse(text: str, file: str = "<string>") -> ast.Module:
    """Parse a whole V+ file (programs and data sections) into a Module."""
    # The controller marks the end of a file with Ctrl-Z; lines may end in CR LF.
    text = text.removeprefix("\ufeff").replace("\r\n", "\n").split("\x1a", 1)[0]
    if not text.endswith("\n"):
        text += "\n"
    try:
        tree = _parser().parse(text)
        units = _ToAst().transform(tree)
    except UnexpectedInput as err:
        raise _syntax_error(err, text, file) from None
    except VisitError as err:
        if isinstance(err.orig_exc, ProgramError):
            line = err.orig_exc.line
            source = text.splitlines()[line - 1] if line else None
            raise err.orig_exc.located(file=file, text=source) from None
        raise
    source_lines = text.splitlines()
    module = ast.Module(file, [], [], source_lines)
    for unit in units:
        unit.file = file
        if isinstance(unit, ast.Program):
            for statement in unit.body:
                statement.step = statement.line - unit.line + 1
            try:
                unit.body = nest(unit.body)
            except ProgramError as err:
                line = err.line
                raise err.located(
                    file=file, program=unit.name, text=source_lines[line - 1] if line else None
                ) from None
            module.programs.append(unit)
        else:
            module.data.append(unit)
    return module


def parse_file(path: str | Path) -> ast.Module:
    path = Path(path)
    if path.exists() and not path.is_file():  # a folder, a FIFO or a device: nothing to load, never a hang
        raise ProgramError(f"*Invalid file specification* {path} is not a file", file=str(path))
    try:
        data = path.read_bytes()
    except OSError:
        raise ProgramError(f"*Nonexistent file* {path}", file=str(path)) from None
    # An editor on the host may have written a UTF-8 byte-order mark: it is not part of the program.
    return parse(data.removeprefix(UTF8_BOM).decode("latin-1"), str(path))
