"""Broken V+ programs, as a careless or hostile user writes them (issue #14): each one
ends in the controller's error, located at file, line and column with the source line,
and never in a Python exception (a Python error escaping from the interpreter fails the
test, since only ProgramError is caught).

* Every keyword, systematically: for each argument of each instruction and function in
  the keyword tables, a value of the wrong kind in that position (a string constant where
  a real belongs is a load-time *Wrong data type*; a location or a real variable of the
  wrong kind at run time).
* Categories written out: numbers beyond the real range, nesting, a byte-order mark,
  DELAY of absurd lengths, string and format limits, malformed statements.
* Fuzzing of the parser and compiler with hypothesis, bounded and derandomized.
"""

from __future__ import annotations

import inspect

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from twin.errors import ProgramError
from twin.language.vplus import messages as msg
from twin.language.vplus.compile_library import LIBRARY_CALLS
from twin.language.vplus.keywords import FUNCTIONS, INSTRUCTIONS, STRING_FUNCTIONS, argument_check, arity
from twin.language.vplus.parser import parse
from twin.language.vplus.structure import MAX_NESTING

from vplus_helpers import run_vplus

FILE = "corpus.pg"
PROLOGUE = ["SET loc = TRANS(1, 2, 3)", "n = 1", '$s = "a"']  # one value of each kind
# A value of the right kind for each check, and the wrong ones to try.
RIGHT = {"_real": "1", "_location": "loc", "_point": "loc", "_str": '"a"'}
WRONG_CONSTANT = {"_real": '"x"', "_location": '"x"', "_point": '"x"', "_str": "5"}  # caught at load
WRONG_VARIABLE = {"_real": "loc", "_location": "n", "_point": "n", "_str": "n"}  # caught when it runs
# Keywords whose statement form is not `NAME args` / `NAME(args)`: keyed (BITS 1, 8 = v),
# I/O (READ (lun) ...) and the library forms with names, arrays or formats as arguments.
SPECIAL = {"BITS", "DECOMPOSE", "SWITCH", "TIMER", "PACK", "KEYMODE", "AIO.OUT", "SELECT", "SOLVE.ANGLES",
           "SOLVE.TRANS", *LIBRARY_CALLS}


def outcome(body: list[str], max_cycles: int = 2000) -> ProgramError | None:
    """The error a program stops with, at load or when it runs; None if it ends normally."""
    text = ".PROGRAM t()\n" + "".join(line + "\n" for line in body) + ".END\n"
    try:
        _system, task = run_vplus(text, max_cycles=max_cycles)
    except ProgramError as err:
        return err
    return task.error


def assert_located(err: ProgramError | None, code: int, line: int, source: str) -> None:
    assert err is not None, "the program should stop with an error"
    assert err.code == code, str(err)
    assert err.line == line and err.column is not None and err.column >= 1, str(err)
    assert err.text is not None and err.text.strip() == source.strip(), str(err)


def _keyword_cases():
    """(id, statement, expected code) for a wrong value in every checked position."""
    tables = [(name, spec.function, "instruction") for name, spec in INSTRUCTIONS.items() if not spec.names]
    tables += [(name, fn, "function") for name, fn in FUNCTIONS.items()]
    tables += [(name, fn, "string") for name, fn in STRING_FUNCTIONS.items()]
    for name, fn, kind in sorted(tables, key=lambda t: (t[0], t[2])):
        if name in SPECIAL:
            continue
        fewest, most = arity(fn)
        count = int(min(most, max(fewest, 1)))
        checks = [argument_check(fn, i) for i in range(count)]
        if not count or any(c is None for c in checks):
            continue
        for position, check in enumerate(checks):
            for variant, wrong in (("constant", WRONG_CONSTANT), ("variable", WRONG_VARIABLE)):
                args = ", ".join(wrong[check] if i == position else RIGHT[c] for i, c in enumerate(checks))
                if kind == "instruction":
                    statement = f"{name} {args}"
                elif kind == "function":
                    statement = f"x = {name}({args})"
                else:
                    statement = f"$r = {name}({args})"
                yield pytest.param(statement, id=f"{kind}-{name}-{position}-{variant}")


KEYWORD_CASES = list(_keyword_cases())


@pytest.mark.parametrize("statement", KEYWORD_CASES)
def test_a_value_of_the_wrong_kind_is_wrong_data_type_at_its_step(statement):
    # V+ guide v17, "Data Types" (reals, strings, locations are distinct types) and the
    # summary tables' argument kinds; the V+ Language Reference's keyword pages.
    err = outcome([*PROLOGUE, statement])
    assert_located(err, msg.WRONG_TYPE, len(PROLOGUE) + 2, statement)


def test_the_corpus_covers_every_category_with_at_least_150_programs():
    assert len(KEYWORD_CASES) + len(WRITTEN_CASES) >= 150


def test_the_issue_examples_are_wrong_data_type():
    # Issue #14: SHIFT(start BY "a", 0, 0), TRANS("a", ...), APPRO start, "high", DEPART "x",
    # ACCEL "a", "b", DURATION "x", PAYLOAD "heavy", CONFIG("a").
    for statement in ('SET p = SHIFT(loc BY "a", 0, 0)', 'SET p = TRANS("a", 1)', 'APPRO loc, "high"',
                      'DEPART "x"', 'ACCEL "a", "b"', 'DURATION "x"', 'PAYLOAD "heavy"', 'x = CONFIG("a")',
                      "SET p = SHIFT(n BY 1, 0, 0)", "x = DX(n)", "MOVE n", "SPEED loc", 'SPEED "fast"',
                      "x = loc + 1", "x = -loc", "x = loc MOD 2", "x = loc BAND 1"):
        err = outcome([*PROLOGUE, statement])
        assert_located(err, msg.WRONG_TYPE, len(PROLOGUE) + 2, statement)


# (statement lines, expected code, line of the error counted from the first body line)
WRITTEN_CASES = [
    # numbers beyond the range of a real ([000] L3868-3895)
    (["x = 1E400"], msg.OVERFLOW, 1),
    (["x = -1E400"], msg.OVERFLOW, 1),
    (["x = 1E39"], msg.OVERFLOW, 1),
    (["x = 1E38", "y = x * x"], msg.OVERFLOW, 2),
    (["x = 1E300 * 1E300 * 1E300"], msg.OVERFLOW, 1),
    (["AUTO DOUBLE d", "d = 1E300 * 1E300 * 1E300"], msg.OVERFLOW, 2),
    # strings: 128 characters at most ([000] "String Data Type")
    (['$a = "' + "x" * 100 + '"', "$b = $a + $a"], msg.STRING_TOO_LONG, 2),
    (['$a = "' + "x" * 100 + '"', "TYPE LEN($a + $a)"], msg.STRING_TOO_LONG, 2),
    (['$a = "' + "x" * 129 + '"'], msg.STRING_TOO_LONG, 1),
    (['$a = $ENCODE(/X200)'], msg.STRING_TOO_LONG, 1),
    # format widths
    (["TYPE /I1000000000, 1"], msg.SYNTAX_ERROR, 1),
    (["TYPE /C100000000"], msg.SYNTAX_ERROR, 1),
    (["TYPE /X999999"], msg.SYNTAX_ERROR, 1),
    (["TYPE /F5.1000, 1"], msg.SYNTAX_ERROR, 1),
    (["TYPE /Q3, 1"], msg.SYNTAX_ERROR, 1),
    # kinds in expressions and statements
    (['x = "a" + 1'], msg.WRONG_TYPE, 1),
    (['$a = 1'], msg.WRONG_TYPE, 1),
    (['x = "a"'], msg.WRONG_TYPE, 1),
    (['IF "a" THEN', "END"], msg.WRONG_TYPE, 1),
    (['WHILE $s DO', "END"], msg.WRONG_TYPE, 1),
    (["SET loc = TRANS(1)", "SET p = loc:n"], msg.WRONG_TYPE, 2),
    (["SET p = n"], msg.WRONG_TYPE, 1),
    (["SET #p = loc"], msg.WRONG_TYPE, 1),
    (["FOR i = loc TO 3", "END"], msg.WRONG_TYPE, 1),
    (["FOR i = 1 TO loc", "END"], msg.WRONG_TYPE, 1),
    (["CASE loc OF", "VALUE 1:", "END"], msg.WRONG_TYPE, 1),
    (["IF loc THEN", "END"], msg.WRONG_TYPE, 1),
    (["WHILE loc DO", "END"], msg.WRONG_TYPE, 1),
    (["DO", "UNTIL loc"], msg.WRONG_TYPE, 2),
    (["x = NOT loc"], msg.WRONG_TYPE, 1),
    (["IF loc GOTO 10", "10 x = 1"], msg.WRONG_TYPE, 1),
    (["x[loc] = 1"], msg.WRONG_TYPE, 1),
    (['x[$s] = 1'], msg.WRONG_TYPE, 1),
    (["x[-1] = 1"], msg.ILLEGAL_ARRAY_INDEX, 1),
    (["x[1, 2, 3, 4] = 1"], msg.ILLEGAL_ARRAY_INDEX, 1),
    (["AUTO a[3]", "a[4] = 1"], msg.ILLEGAL_ARRAY_INDEX, 2),
    (["x = y + 1"], msg.UNDEFINED_VALUE, 1),
    (["x = 1 / 0"], msg.DIVIDE_BY_ZERO, 1),
    (["x = 1 MOD 0"], msg.DIVIDE_BY_ZERO, 1),
    (["x = SQRT(-1)"], msg.ILLEGAL_VALUE, 1),
    (["PARAMETER HAND.TIME = loc"], msg.WRONG_TYPE, 1),
    (['PARAMETER HAND.TIME = "a"'], msg.WRONG_TYPE, 1),
    (["SIGNAL 99999"], msg.ILLEGAL_SIGNAL, 1),
    (['CALLS "nosuch"()'], msg.UNDEFINED_PROGRAM, 1),
    (["CALLS n()"], msg.WRONG_TYPE, 1),
    (["CALL nosuch()"], msg.UNDEFINED_PROGRAM, 1),
    (["EXECUTE 99 t()"], msg.ILLEGAL_VALUE, 1),
    (["LOCK 1000"], msg.ILLEGAL_VALUE, 1),
    (["REACT 5, t"], msg.ILLEGAL_SIGNAL, 1),
    (["WAIT.EVENT , loc"], msg.WRONG_TYPE, 1),
    (['WAIT.EVENT , "a"'], msg.WRONG_TYPE, 1),
    # keyed statements and the library's special forms
    (['BITS 1, 8 = "a"'], msg.WRONG_TYPE, 1),
    (["BITS 1, 8 = loc"], msg.WRONG_TYPE, 1),
    (['BITS "a", 8 = 1'], msg.WRONG_TYPE, 1),
    (["TIMER 1 = loc"], msg.WRONG_TYPE, 1),
    (["DECOMPOSE d[] = n"], msg.WRONG_TYPE, 1),
    (["PACK $a[0], 1, 3 = 5"], msg.WRONG_TYPE, 1),
    (["SOLVE.ANGLES j[], f, e = n, j[], 0"], msg.WRONG_TYPE, 1),
    (['y = TAS(n, "a")'], msg.WRONG_TYPE, 1),
    (["y = TAS(n, loc)"], msg.WRONG_TYPE, 1),
    (["$t = $DECODE($s, 5, 0)"], msg.WRONG_TYPE, 1),
    (['a[0] = 1', '$u = $UNPACK(a[0], "x", 1)'], msg.WRONG_TYPE, 2),
    (["x = LAST(n)"], msg.WRONG_TYPE, 1),
    (["x = PARAMETER(NO.SUCH.THING)"], msg.ILLEGAL_VALUE, 1),
    (["ENABLE NO.SUCH.SWITCH"], msg.ILLEGAL_VALUE, 1),
    # malformed statements
    (["x = (1"], msg.SYNTAX_ERROR, 1),
    (["x = 1)"], msg.SYNTAX_ERROR, 1),
    (["x = = 1"], msg.SYNTAX_ERROR, 1),
    (["IF THEN"], msg.SYNTAX_ERROR, 1),
    (["FOR = 1 TO 2"], msg.SYNTAX_ERROR, 1),
    (["x = ^B111111111"], msg.SYNTAX_ERROR, 1),
    (["x = ^HZZ"], msg.SYNTAX_ERROR, 1),
    (['TYPE "unterminated'], msg.SYNTAX_ERROR, 1),
    (["x = 1 +"], msg.SYNTAX_ERROR, 1),
    (["GOTO 10"], msg.UNDEFINED_LABEL, 1),
    (["99999999 x = 1"], msg.SYNTAX_ERROR, 1),
    (["END"], msg.CONTROL_STRUCTURE, 1),
    (["ELSE"], msg.CONTROL_STRUCTURE, 1),
    (["IF n THEN"], msg.CONTROL_STRUCTURE, 1),
    (["DO", "x = 1"], msg.CONTROL_STRUCTURE, 1),
    (["UNTIL 1"], msg.CONTROL_STRUCTURE, 1),
    (["EXIT"], msg.CONTROL_STRUCTURE, 1),
    (["FROBNICATE 1"], msg.UNKNOWN_KEYWORD, 1),
    (["MOVE"], msg.INVALID_ARGUMENT, 1),
    (["x = SIN()"], msg.INVALID_ARGUMENT, 1),
    (["x = SIN(1, 2)"], msg.INVALID_ARGUMENT, 1),
    (["x = NOSUCH(1)"], msg.UNDEFINED_PROGRAM, 1),
    (["pi = 3"], msg.SYNTAX_ERROR, 1),
    (["x = 1", "AUTO y"], msg.SYNTAX_ERROR, 2),
    (["x = " + "+".join(["n"] * 100)], None, 1),
    (["x = " + "+".join(["n"] * 3000)], msg.SYNTAX_ERROR, 1),  # "expression too complicated"
    (["x = " + "(" * 400 + "n" + ")" * 400], None, 1),
    (["x = " + "-" * 3000 + "n"], msg.SYNTAX_ERROR, 1),
]


@pytest.mark.parametrize("body, code, line", WRITTEN_CASES, ids=[f"written-{i}" for i in range(len(WRITTEN_CASES))])
def test_written_cases(body, code, line):
    declarations = [b for b in body if b.startswith("AUTO ")]  # they come before any executable step
    err = outcome([*declarations, *PROLOGUE, *body[len(declarations):]])
    if code is None:
        assert err is None, str(err)
        return
    where = line + (0 if line <= len(declarations) else len(PROLOGUE))
    assert_located(err, code, 1 + where, body[line - 1])


@pytest.mark.parametrize("section, code", [
    (".LOCATIONS\nspot 1 2\n.END", msg.SYNTAX_ERROR),
    (".LOCATIONS\nspot a b c d e f\n.END", msg.SYNTAX_ERROR),
    (".LOCATIONS\n$s 1 2 3 4 5 6\n.END", msg.WRONG_TYPE),
    (".LOCATIONS\nspot 1E400 0 0 0 0 0\n.END", msg.OVERFLOW),
    (".REALS\nx =\n.END", msg.SYNTAX_ERROR),
    (".REALS\nx = 1E400\n.END", msg.OVERFLOW),
    (".REALS\nx = 1E39\n.END", msg.OVERFLOW),
    (".REALS\n$s = 1\n.END", msg.WRONG_TYPE),
    (".REALS\n#p = 1\n.END", msg.WRONG_TYPE),
    (".REALS\nx[-1] = 5\n.END", msg.SYNTAX_ERROR),
    (".STRINGS\ns = \"a\"\n.END", msg.WRONG_TYPE),
    (".STRINGS\n$s = \"open\n.END", msg.SYNTAX_ERROR),
    (".STRINGS\n$s = \"" + "x" * 129 + "\"\n.END", msg.STRING_TOO_LONG),
    (".DOUBLES\nd = abc\n.END", msg.SYNTAX_ERROR),
])
def test_broken_data_sections_are_located_errors(section, code):
    # docs/vplus.md "Program files": the layout STOREL/STORER/STORES write; values as in
    # programs ([000] "String Data Type", L3868-3895).
    with pytest.raises(ProgramError) as caught:
        run_vplus(".PROGRAM t()\n.END\n" + section + "\n")
    err = caught.value
    assert err.code == code and err.line == 4 and err.text == section.split("\n")[1], str(err)


@pytest.mark.parametrize("depth", [100, MAX_NESTING])
@pytest.mark.parametrize("head", ["IF n == 1 THEN", "FOR i = 1 TO 1", "WHILE n == 1 DO", "DO"])
def test_blocks_nested_within_the_limit_run(head, depth):
    # docs/vplus.md, "Deep nesting": within the limit, any depth runs.
    close = "UNTIL TRUE" if head == "DO" else "END"
    body = [*PROLOGUE, *[head] * depth, "n = 2" if head.startswith("WHILE") else "y = 1", *[close] * depth]
    assert outcome(body) is None


@pytest.mark.parametrize("depth", [MAX_NESTING + 1, 1000, 5000])
def test_blocks_nested_beyond_the_limit_are_a_control_structure_error(depth):
    body = [*["IF n == 1 THEN"] * depth, "y = 1", *["END"] * depth]
    err = outcome([*PROLOGUE, *body])
    assert_located(err, msg.CONTROL_STRUCTURE, len(PROLOGUE) + 2 + MAX_NESTING, "IF n == 1 THEN")


def test_an_automatic_array_larger_than_the_stack_stops_the_program_at_its_start():
    # [000] "Stack Space Required by a Subroutine": AUTO arrays live on the stack.
    err = outcome(["AUTO REAL a[1E30]", "x = 1"])
    assert_located(err, msg.TOO_MANY_CALLS, 1, ".PROGRAM t()")


def test_a_source_that_is_not_a_file_is_refused_without_reading_it(tmp_path):
    import os

    from twin.language.vplus.parser import parse_file

    fifo = tmp_path / "prog.pg"
    os.mkfifo(fifo)  # reading it would wait for a writer for ever
    with pytest.raises(ProgramError) as caught:
        parse_file(fifo)
    assert caught.value.file == str(fifo) and "not a file" in str(caught.value)
    with pytest.raises(ProgramError):
        parse_file(tmp_path)


def test_a_utf8_byte_order_mark_is_accepted(tmp_path):
    from twin.language.vplus.parser import parse_file

    path = tmp_path / "bom.pg"
    path.write_bytes(b"\xef\xbb\xbf.PROGRAM t()\r\n    TYPE 1\r\n.END\r\n")
    assert [p.name for p in parse_file(path).programs] == ["t"]
    assert [p.name for p in parse("\ufeff.PROGRAM t()\nTYPE 1\n.END\n").programs] == ["t"]


# ------------------------------------------------------------------ fuzzing
_WORDS = ["MOVE", "APPRO", "DEPART", "TYPE", "IF", "THEN", "ELSE", "END", "FOR", "TO", "STEP", "WHILE",
          "DO", "UNTIL", "CASE", "OF", "VALUE", "ANY", "GOTO", "CALL", "CALLS", "AUTO", "LOCAL", "GLOBAL",
          "REAL", "DOUBLE", "LOC", "STRING", "SET", "HERE", "SIGNAL", "SIG", "TRANS", "SHIFT", "BY", "DELAY",
          "ACCEL", "SPEED", "ALWAYS", "WAIT", "REACT", "REACTE", "RETURN", "EXIT", "NEXT", "PROMPT",
          "ATTACH", "READ", "WRITE", "FOPENR", "DECOMPOSE", "BITS", "$ENCODE", "$MID", "LEN", "x", "y",
          "$s", "#p", "loc", "a[]", "a[1]", "n", "1", "0", "-1", "1E400", "2.5", "^HFF", "^B101", "'A",
          '"txt"', "(", ")", "[", "]", ",", ":", "=", "==", "<>", "+", "-", "*", "/", "MOD", "AND", "NOT",
          "/I5", "/F8.3", "/C2", "10", ";c", "\t", " "]
_LINE = st.lists(st.sampled_from(_WORDS), min_size=0, max_size=8).map(" ".join)
_PROGRAM = st.lists(_LINE, min_size=0, max_size=8)


@settings(max_examples=250, derandomize=True, deadline=None, suppress_health_check=list(HealthCheck))
@given(_PROGRAM)
def test_fuzzed_programs_end_in_located_errors(lines):
    """Random statements from V+'s own words: the program loads and runs, or stops with a
    V+ error that names its line; nothing else escapes."""
    err = outcome([*PROLOGUE, *lines], max_cycles=50)
    if err is not None:
        assert err.code is not None and err.line is not None and 1 <= err.line <= len(lines) + 5, str(err)


@settings(max_examples=300, derandomize=True, deadline=None, suppress_health_check=list(HealthCheck))
@given(st.text(alphabet=st.sampled_from(list('.PROGRAMENDt()\n"$#[]=+-*/;:, 0123456789^BHDE\x1a\r\ufeff')),
               max_size=200))
def test_fuzzed_text_parses_or_is_a_located_syntax_error(text):
    try:
        parse(text, FILE)
    except ProgramError as err:
        assert err.code is not None and err.line is not None and err.line >= 1, str(err)


def test_argument_checks_come_from_the_keyword_signatures():
    # The table the corpus walks is the compiler's own: a keyword without annotations takes reals.
    assert argument_check(FUNCTIONS["SIN"], 0) == "_real"
    assert argument_check(INSTRUCTIONS["MOVE"].function, 0) == "_point"
    assert argument_check(FUNCTIONS["DX"], 0) == "_location"
    assert argument_check(FUNCTIONS["LEN"], 0) == "_str"
    assert inspect.signature(FUNCTIONS["MAX"]).parameters  # *xs: every argument a real
    assert argument_check(FUNCTIONS["MAX"], 7) == "_real"


@pytest.mark.parametrize("seconds", ["1E6", "1E30"])
def test_a_very_long_delay_is_a_wait_in_constant_memory(seconds):
    # Issue #14: DELAY 1E6 allocated a sampled standing-still trajectory (15 GiB) and
    # DELAY 1E30 crashed.  DELAY is a motion that stands still ([000] motion table): its
    # samples are broadcast views of one row, whatever its length (docs/motion.md).
    from test_motion_controller import run_on_cell

    text = f'.PROGRAM t()\n    DELAY {seconds}\n    TYPE "forward"\n.END\n'
    sim, task, outcome, rows = run_on_cell(text, max_time=0.5)
    assert task.error is None and task.system.console.output == "forward\n"  # forward processing
    (still,) = sim.controller._motions
    assert still.q.strides[0] == 0 and still.qd.strides[0] == 0 and still.delta.strides[0] == 0
    assert still.last >= 0.5 / sim.controller.dt  # it is still standing still when the run ends
