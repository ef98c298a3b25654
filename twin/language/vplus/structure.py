"""Nest the flat, one-per-line statements into blocks.

V+ checks block structure when a program is loaded and reports a mismatch as
"*Control structure error*" at the offending step (V+ guide v17, "Program
Format"); this pass does the same.
"""

from __future__ import annotations

from ...errors import ProgramError
from . import ast
from . import messages as msg


def _error(statement: ast.Statement, what: str) -> ProgramError:
    return ProgramError(
        f"{msg.message(msg.CONTROL_STRUCTURE)} {what}",
        msg.CONTROL_STRUCTURE,
        line=statement.line,
        column=statement.column,
        step=statement.step,
    )


# Blocks (IF, FOR, WHILE, DO, CASE) may nest this deep.  The guides set no number; the
# controller's program stack bounds it.  Deeper is a load-time *Control structure error*
# at the opening step (docs/vplus.md, "Deep nesting").
MAX_NESTING = 200


class _Nester:
    def __init__(self, statements: list[ast.Statement]):
        self.statements = statements
        self.pos = 0
        self.depth = 0

    def block(self, stops: tuple[type, ...]) -> tuple[list[ast.Statement], ast.Statement | None]:
        """Statements up to (not including) one of the `stops` types."""
        body: list[ast.Statement] = []
        while self.pos < len(self.statements):
            statement = self.statements[self.pos]
            if isinstance(statement, stops):
                self.pos += 1
                if statement.label is not None:
                    # A label on ELSE, END, UNTIL, VALUE or ANY: a GOTO to it
                    # lands where that step would go on, the end of the
                    # block it closes.
                    body.append(ast.LabelOnly(line=statement.line, column=statement.column,
                                              step=statement.step, label=statement.label))
                return body, statement
            if isinstance(statement, (ast.Else, ast.End, ast.UntilTail, ast.ValueClause, ast.AnyClause)):
                raise _error(statement, f"unexpected {type(statement).__name__.replace('Clause', '').replace('Tail', '').upper()}")
            self.pos += 1
            body.append(self.one(statement))
        return body, None

    def require(self, opener: ast.Statement, stops: tuple[type, ...], name: str):
        if self.depth >= MAX_NESTING:
            raise _error(opener, f"blocks nested deeper than {MAX_NESTING}")
        self.depth += 1
        try:
            body, stop = self.block(stops)
        finally:
            self.depth -= 1
        if stop is None:
            raise _error(opener, f"missing {name}")
        return body, stop

    def one(self, s: ast.Statement) -> ast.Statement:
        where = {"line": s.line, "column": s.column, "step": s.step, "label": s.label}
        if isinstance(s, ast.IfThen):
            body, stop = self.require(s, (ast.Else, ast.End), "END")
            orelse: list[ast.Statement] = []
            if isinstance(stop, ast.Else):
                orelse, _ = self.require(s, (ast.End,), "END")
            return ast.If(s.condition, body, orelse, **where)
        if isinstance(s, ast.ForHead):
            body, _ = self.require(s, (ast.End,), "END")
            return ast.For(s.target, s.start, s.stop, s.step_by, body, **where)
        if isinstance(s, ast.WhileHead):
            body, _ = self.require(s, (ast.End,), "END")
            return ast.While(s.condition, body, **where)
        if isinstance(s, ast.DoHead):
            body, stop = self.require(s, (ast.UntilTail,), "UNTIL")
            return ast.DoUntil(body, stop.condition, stop, **where)
        if isinstance(s, ast.CaseHead):
            return self.case(s, where)
        return s

    def case(self, head: ast.CaseHead, where: dict) -> ast.Case:
        cases: list[tuple[list[ast.Expr], list[ast.Statement]]] = []
        default = None
        # Only comments may sit between CASE and the first VALUE.
        clause = self.statements[self.pos] if self.pos < len(self.statements) else None
        if not isinstance(clause, (ast.ValueClause, ast.AnyClause, ast.End)):
            raise _error(clause or head, "VALUE expected after CASE")
        self.pos += 1
        while True:
            body, stop = self.require(head, (ast.ValueClause, ast.AnyClause, ast.End), "END")
            if clause.label is not None and not cases and default is None:
                body.insert(0, ast.LabelOnly(line=clause.line, column=clause.column, step=clause.step,
                                             label=clause.label))
            if isinstance(clause, ast.ValueClause):
                cases.append((clause.values, body))
            elif isinstance(clause, ast.AnyClause):
                if default is not None:
                    raise _error(clause, "second ANY")
                default = body
            if isinstance(stop, ast.End):
                return ast.Case(head.subject, cases, default, **where)
            if default is not None:
                raise _error(stop, "VALUE after ANY")
            clause = stop


def nest(statements: list[ast.Statement]) -> list[ast.Statement]:
    nester = _Nester(statements)
    body, stop = nester.block(())
    return body
