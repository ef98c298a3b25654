"""GPL source text -> AST.

`parse(text, file)` prepares the text line by line (comments and `#` lines
blanked, implicit continuations marked), runs the LALR grammar in gpl.lark
and turns the tree into the dataclasses of ast.py.  A syntax error becomes a
ProgramError with file, line, column, the offending text and GPL's code.
"""

from __future__ import annotations

import os
import re
import stat
from functools import lru_cache
from importlib.resources import files
from pathlib import Path

from lark import Lark, Token, v_args
from lark.visitors import Transformer_NonRecursive
from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedInput, UnexpectedToken

from ...errors import ProgramError
from ..lalr import lalr_parser
from . import ast
from .errors import SYNTAX_ERROR, TOO_DEEP, message


@lru_cache(maxsize=1)
def _parser() -> Lark:
    grammar = files(__package__).joinpath("gpl.lark").read_text()  # packaged beside this module
    return lalr_parser(grammar, "gpl")


# A line that ends in one of these goes on on the next line (VB.NET's implicit
# continuation); the manual's examples lost many of their " _" markers.
_OPEN_END = re.compile(r"(,|\(|&|\+|-|\*|/|=|<>|<=|>=|\b(and|andalso|or|orelse|xor|not)\b)\s*$", re.I)


def _code_part(line: str) -> str:
    """The line without its comment: a ' outside a string literal starts one."""
    in_string = False
    for i, ch in enumerate(line):
        if ch == '"':
            in_string = not in_string
        elif ch == "'" and not in_string:
            return line[:i]
    return line


# `Add(1,_` : a line continuation written without the blank before the underscore, after
# a character that cannot end a name (Precise's and Brooks' code does this).
_TIGHT_CONTINUATION = re.compile(r"(?<=[^\w\s])_$")


MAX_LINE_LENGTH = 16384  # characters in one source line (docs/gpl.md); the parser's time grows with it


def prepare(text: str, file: str = "<string>") -> str:
    """Blank comments, `#` lines and REM lines (keeping line numbers); mark continuations."""
    text = text.removeprefix("\ufeff").removeprefix("\xef\xbb\xbf")  # a byte-order mark from a Windows editor
    lines = text.replace("\r\n", "\n").replace("\r", "\n").split("\n")
    out = []
    for number, raw in enumerate(lines, start=1):
        if len(raw) > MAX_LINE_LENGTH:
            raise ProgramError(f"{message(TOO_DEEP)}: a line of {len(raw):,} characters (at most "
                               f"{MAX_LINE_LENGTH:,})", TOO_DEEP, file=file, line=number, column=MAX_LINE_LENGTH + 1,
                               text=raw[:80] + "...")
        stripped = raw.lstrip()
        if stripped.startswith("#") or re.match(r"rem(\s|$)", stripped, re.I):
            out.append("")
            continue
        code = _code_part(raw).rstrip()
        code = _TIGHT_CONTINUATION.sub(" _", code)
        if code and not code.endswith(" _") and _OPEN_END.search(code) and not code.lstrip().endswith(":"):
            code += " _"
        out.append(code)
    return "\n".join(out) + "\n"


def _pos(meta_or_token) -> dict:
    return {"line": meta_or_token.line, "column": meta_or_token.column}


def _body(tree_or_list) -> list[ast.Statement]:
    return tree_or_list if isinstance(tree_or_list, list) else []


@v_args(meta=True)
class _ToAst(Transformer_NonRecursive):  # no recursion: a program nested 10,000 deep still parses
    # ---- literals and names
    def number(self, meta, c):
        text = str(c[0])
        if re.fullmatch(r"[0-9]+", text):
            value = int(text)
            return ast.Literal(value if value < 2**31 else float(value))
        return ast.Literal(float(text))

    def hex_number(self, meta, c):
        return ast.Literal(_to_int32(int(str(c[0])[2:], 16)))

    def oct_number(self, meta, c):
        return ast.Literal(_to_int32(int(str(c[0])[2:], 8)))

    def string(self, meta, c):
        return ast.Literal(str(c[0])[1:-1].replace('""', '"'))

    def true(self, meta, c):
        return ast.Literal(True)

    def false(self, meta, c):
        return ast.Literal(False)

    def nothing(self, meta, c):
        return ast.Nothing()

    def me(self, meta, c):
        node = ast.Me()
        node.line, node.column = meta.line, meta.column
        return node

    def name(self, meta, c):
        return ast.Name(str(c[0]), **_pos(c[0]))

    def paren(self, meta, c):
        return c[0]

    def member_name(self, meta, c):
        return c[0]

    def member(self, meta, c):
        return ast.Member(c[0], str(c[1]), **_pos(meta))

    def call_args(self, meta, c):
        if c == [None]:
            return []
        return [ast.Omitted(line=meta.line, column=meta.column) if a is None else a for a in c]

    def call(self, meta, c):
        return ast.Call(c[0], c[1], **_pos(meta))

    def new(self, meta, c):
        return ast.New(c[1], c[2], **_pos(meta))

    def address_of(self, meta, c):
        return ast.AddressOf(c[0], **_pos(meta))

    def type_ref(self, meta, c):
        return ast.TypeRef([str(t) for t in c])

    # ---- operators
    def _binary(self, meta, op, left, right):
        node = ast.Binary(op, left, right)
        node.line, node.column = meta.line, meta.column
        return node

    def binary(self, meta, c):
        return self._binary(meta, str(c[1]), c[0], c[2])

    def compare(self, meta, c):
        return self._binary(meta, str(c[1]), c[0], c[2])

    def logic(self, meta, c):
        return self._binary(meta, str(c[1]).lower(), c[0], c[2])

    def xor(self, meta, c):
        return self._binary(meta, "xor", c[0], c[1])

    def is_(self, meta, c):
        return self._binary(meta, "is", c[0], c[1])

    def isnot(self, meta, c):
        """`a IsNot b` (VB.NET 2005) is `Not a Is b`."""
        node = ast.Unary("not", self._binary(meta, "is", c[0], c[1]))
        node.line, node.column = meta.line, meta.column
        return node

    def concat(self, meta, c):
        return self._binary(meta, "&", c[0], c[1])

    def mod(self, meta, c):
        return self._binary(meta, "mod", c[0], c[1])

    def intdiv(self, meta, c):
        return self._binary(meta, "\\", c[0], c[1])

    def power(self, meta, c):
        return self._binary(meta, "^", c[0], c[1])

    def neg(self, meta, c):
        operand = c[0]
        if isinstance(operand, ast.Literal) and type(operand.value) in (int, float):
            return ast.Literal(-operand.value)
        node = ast.Unary("-", operand)
        node.line, node.column = meta.line, meta.column
        return node

    def not_(self, meta, c):
        node = ast.Unary("not", c[0])
        node.line, node.column = meta.line, meta.column
        return node

    # ---- statements
    def body(self, meta, c):
        out: list[ast.Statement] = []
        for item in c:
            if isinstance(item, list):
                out.extend(item)
        return out

    def plain_line(self, meta, c):
        return [c[0]]

    def label_only(self, meta, c):
        return [ast.Label(name=_label_name(c[0]), **_label_pos(c[0]))]

    def labelled(self, meta, c):
        return [ast.Label(name=_label_name(c[0]), **_label_pos(c[0])), c[1]]

    def assignment(self, meta, c):
        return ast.Assign(target=c[0], op=str(c[1]), value=c[2], **_pos(meta))

    def call_statement(self, meta, c):
        return ast.CallStatement(expr=c[-1], **_pos(meta))

    def goto(self, meta, c):
        return ast.Goto(label=str(c[0]).lower(), **_pos(meta))

    def label_ref(self, meta, c):
        return c[0]  # a name, a number, or a keyword: the manual's TftpWrite jumps to `exit:`

    def block_kind(self, meta, c):
        return str(c[0]).lower()

    def exit_statement(self, meta, c):
        return ast.Exit(kind=c[0], **_pos(meta))

    def continue_statement(self, meta, c):
        return ast.Continue(kind=c[0], **_pos(meta))

    def return_statement(self, meta, c):
        return ast.Return(value=c[0], **_pos(meta))

    def throw_statement(self, meta, c):
        return ast.Throw(value=c[0], **_pos(meta))

    def redim(self, meta, c):
        preserve, *targets = c
        return ast.ReDim(targets=targets, preserve=preserve is not None, **_pos(meta))

    def if_line(self, meta, c):
        cond, then, orelse = c
        return ast.If(branches=[(cond, [then])], orelse=[orelse] if orelse is not None else None, **_pos(meta))

    def elseif(self, meta, c):
        return (c[0], _body(c[-1]))

    def else_part(self, meta, c):
        return _body(c[0])

    def if_block(self, meta, c):
        cond, body, *rest = c
        branches = [(cond, _body(body))]
        orelse = rest.pop() if rest else None
        branches.extend(r for r in rest if r is not None)
        return ast.If(branches=branches, orelse=orelse, **_pos(meta))

    def for_block(self, meta, c):
        var, var_type, start, stop, step, body = c[0], c[1], c[3], c[4], c[5], c[6]
        return ast.For(var=var, start=start, stop=stop, step=step, body=_body(body), var_type=var_type,
                       **_pos(meta))

    def while_block(self, meta, c):
        return ast.While(condition=c[1], body=_body(c[2]), **_pos(meta))

    def loop_test(self, meta, c):
        return (str(c[0]).lower(), c[1])

    def do_block(self, meta, c):
        return ast.Do(pre=c[0], body=_body(c[1]), post=c[2], **_pos(meta))

    def case_value(self, meta, c):
        return ast.CaseTest("value", "=", c[0])

    def case_range(self, meta, c):
        return ast.CaseTest("range", "", c[0], c[1])

    def case_is(self, meta, c):
        return ast.CaseTest("is", str(c[0]), c[1])

    def case_clause(self, meta, c):
        return (list(c[:-1]), _body(c[-1]))

    def case_else(self, meta, c):
        return ("else", _body(c[0]))

    def select_block(self, meta, c):
        subject = c[0]
        cases, default = [], None
        for clause in c[1:]:
            if clause is None:
                continue
            if clause[0] == "else":
                default = clause[1]
            else:
                cases.append(clause)
        return ast.Select(subject=subject, cases=cases, default=default, **_pos(meta))

    def catch_part(self, meta, c):
        name, type_ref, body = c
        return ("catch", str(name) if name is not None else None, _body(body), type_ref)

    def finally_part(self, meta, c):
        return ("finally", _body(c[0]))

    def try_block(self, meta, c):
        body, catch, fin = c
        return ast.Try(
            body=_body(body),
            catch_var=catch[1] if catch else None,
            catch_body=catch[2] if catch else None,
            catch_type=catch[3] if catch else None,
            finally_body=fin[1] if fin else None,
            **_pos(meta),
        )

    # ---- declarations
    def modifier(self, meta, c):
        return str(c[0]).lower()

    def modifiers(self, meta, c):
        return list(c)

    def rank(self, meta, c):
        return list(c)

    def declarator(self, meta, c):
        name, bounds, new_kw, type_ref, ctor_args, _eq, init = c
        return ast.Declarator(str(name), bounds, type_ref, new_kw is not None, ctor_args, init, **_pos(name))

    def member_decl(self, meta, c):
        return ast.Declare(modifiers=c[0], items=_share_types(list(c[1:])), **_pos(meta))

    def local_decl(self, meta, c):
        mods = [m for m in c if isinstance(m, str)]
        items = [d for d in c if isinstance(d, ast.Declarator)]
        return ast.Declare(modifiers=mods, items=_share_types(items), **_pos(meta))

    # ---- procedures and classes
    def passing(self, meta, c):
        return str(c[0]).lower()

    def param(self, meta, c):
        passing, name, rank, type_ref = c
        if type_ref is not None and rank is not None:
            type_ref.rank = len(rank)
        return ast.Param(str(name), passing == "byref", type_ref)

    def params(self, meta, c):
        return [p for p in c if p is not None]

    def proc_kind(self, meta, c):
        return str(c[0]).lower()

    def proc_name(self, meta, c):
        return str(c[0])

    def procedure(self, meta, c):
        mods, kind, name, params, rtype, body, _end_kind = c
        return ast.Procedure(kind, name, params or [], rtype, _body(body), mods, meta.line, meta.column)

    def getter(self, meta, c):
        return ("get", _body(c[0]))

    def setter(self, meta, c):
        return ("set", c[0], _body(c[1]))

    def property_decl(self, meta, c):
        mods, name, params, type_ref, *accessors = c
        getter = setter = setter_param = None
        for acc in accessors:
            if acc is None:
                continue
            if acc[0] == "get":
                getter = acc[1]
            else:
                setter_param, setter = acc[1], acc[2]
        return ast.Property(str(name), params or [], type_ref, getter, setter_param, setter, mods, meta.line)

    def delegate_decl(self, meta, c):
        mods, kind, name, params, rtype = c
        return ast.DelegateDecl(kind, str(name), params or [], rtype, mods, meta.line)

    def class_decl(self, meta, c):
        mods, name, *members = c
        return ast.ClassDecl(str(name), mods, [m for m in members if m is not None], meta.line)

    def module(self, meta, c):
        name, *members = c
        return ast.Module(str(name), [m for m in members if m is not None], file="", line=meta.line)

    def start(self, meta, c):
        return [x for x in c if x is not None]


def _share_types(items: list[ast.Declarator]) -> list[ast.Declarator]:
    """`Dim ii, jj As Integer`: a name without a type takes the next type in the
    statement (ch. 4, "Variable Declarations")."""
    following = None
    for d in reversed(items):
        if d.type is None:
            d.type = following
        else:
            following = d.type
    return items


@lru_cache(maxsize=1)
def keywords() -> frozenset[str]:
    """GPL's reserved words (ch. 4 "Variable Declarations"), as the grammar spells them."""
    return frozenset(t.pattern.value for t in _parser().terminals
                     if t.pattern.type == "str" and "i" in t.pattern.flags and t.pattern.value.isalpha())


def _to_int32(value: int) -> int:
    """&H/&O constants are 32-bit patterns: &HFFFFFFFF is -1."""
    value &= 0xFFFFFFFF
    return value - (1 << 32) if value >= 1 << 31 else value


def _label_name(token: Token) -> str:
    return str(token).strip().rstrip(":").strip().lower()


def _label_pos(token: Token) -> dict:
    indent = len(str(token)) - len(str(token).lstrip())
    return {"line": token.line, "column": token.column + indent}


def _spelled(terminals) -> list[str]:
    """The keywords among a few expected terminals, as a programmer writes them."""
    if not terminals or len(terminals) > 3:
        return []
    patterns = {t.name: t.pattern for t in _parser().terminals}
    words = [patterns[name].value for name in terminals
             if name in patterns and patterns[name].type == "str" and patterns[name].value.isalpha()]
    return sorted(w.capitalize() for w in words) if len(words) == len(terminals) else []


def _syntax_error(err: UnexpectedInput, lines: list[str], file: str) -> ProgramError:
    line = getattr(err, "line", None)
    column = getattr(err, "column", None)
    if isinstance(err, UnexpectedEOF) or line is None or line < 1:
        line, column = len(lines), 1
    source = lines[line - 1] if 0 < line <= len(lines) else ""
    if isinstance(err, UnexpectedToken) and err.token.type == "$END":
        detail = "unexpected end of file (a block without its End?)"
    elif isinstance(err, UnexpectedToken):
        got = str(err.token).strip()
        detail = f"unexpected {got!r}" if got else "unexpected end of line"
        wanted = _spelled(err.expected)
        if wanted:
            detail += f", expected {' or '.join(wanted)}"  # `End Sub` inside an If: expected If
    elif isinstance(err, UnexpectedCharacters):
        detail = f"unexpected character {source[column - 1:column]!r}" if column else "unexpected character"
    else:
        detail = "unexpected end of file"
    return ProgramError(
        f"{message(SYNTAX_ERROR)}: {detail}", SYNTAX_ERROR, file=file, line=line, column=column, text=source
    )


def parse(text: str, file: str = "<string>") -> ast.SourceFile:
    """Parse one .gpl or .gpo file.  Members outside any Module go to an implicit module."""
    source = ast.SourceFile(file)
    try:
        items = _ToAst().transform(_parser().parse(prepare(text, file)))
    except UnexpectedInput as err:
        raise _syntax_error(err, text.replace("\r\n", "\n").split("\n"), file) from None
    loose = []
    for item in items:
        if isinstance(item, ast.Module):
            item.file = file
            source.modules.append(item)
        else:
            loose.append(item)
    if loose:
        stem = re.sub(r"\W", "_", Path(file).stem) or "main"
        source.modules.append(ast.Module(stem, loose, file, line=1, implicit=True))
    return source


def parse_file(path: str | Path) -> ast.SourceFile:
    path = Path(path)
    try:
        if not stat.S_ISREG(os.stat(path).st_mode):  # a FIFO or a device would hang or never end
            raise ProgramError(f"Cannot open file {path}: not a regular file", file=str(path))
        text = path.read_text(encoding="latin-1")
    except OSError:
        raise ProgramError(f"Cannot open file {path}", file=str(path)) from None
    return parse(text, str(path))
