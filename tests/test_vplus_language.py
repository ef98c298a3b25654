"""The V+ language on the interpreter alone, against the manuals' examples.

[000] is the V+ Language User's Guide v17, [001] the eV+ Language User's Guide
(../shared/seeds/); line numbers cite them.
"""

from __future__ import annotations

import pytest

from twin.errors import ProgramError
from twin.language.vplus import messages as msg
from twin.language.vplus.parser import parse

from vplus_helpers import output_of, run_vplus


def program(body: str, name: str = "t", params: str = "") -> str:
    return f".PROGRAM {name}({params})\n{body}\n.END\n"


def test_move_parts_type_line_prints_as_the_manual_shows():
    # [001] "Pick and Place": TYPE "All done. ", /I0, parts, " parts processed"
    out = output_of(program('parts = 100\nTYPE "All done. ", /I0, parts, " parts processed"'))
    assert out == "All done. 100 parts processed\n"


def test_default_real_format_has_no_decimal_point_for_integers():
    # [000] digest 8.4: TYPE "The value of x is ", x, "." with x = 27
    out = output_of(program('x = 27\nTYPE "The value of x is ", x, "."\nTYPE 2.5\nTYPE 1/3'))
    assert out == "The value of x is 27.\n2.5\n0.3333333\n"


def test_format_specifiers():
    out = output_of(program('TYPE /I5, 42, /F8.3, 3.14159, /S\nTYPE /X3, "a", /C1, "b"\nTYPE /I2, 12345'))
    assert out == "   42   3.142   a\nb\n**\n"


def test_for_loop_counts_inclusive_and_steps_down():
    out = output_of(program("FOR i = 1 TO 3\nTYPE i, /S\nEND\nFOR i = 10 TO 1 STEP -4\nTYPE i, /S\nEND\nTYPE"))
    assert out == "1231062\n"


def test_precedence_and_binds_tighter_than_comparisons():
    # [000 L4324-4345]: AND is level 3, comparisons level 5: x > 2 AND y means x > (2 AND y).
    out = output_of(program("x = 1\ny = 0\nTYPE x > 2 AND y\nTYPE (x > 2) AND (y < 10)\nTYPE 2 + 3 * 4, -2 MOD 3"))
    assert out == "-1\n0\n14-2\n"


def test_numeric_literal_forms():
    out = output_of(program("TYPE ^HFF, \" \", ^B1001, \" \", ^346, \" \", 'A, \" \", 1.5E3"))
    assert out == "255 9 230 65 1500\n"


def test_bitwise_operators():
    # [000 L4303]: ^B1001001 BAND ^B1110011 = ^B1000001
    out = output_of(program("TYPE ^B1001001 BAND ^B1110011, \" \", 5 BOR 2, \" \", 6 BXOR 3, \" \", COM 0"))
    assert out == "65 7 5 -1\n"


def test_case_value_any():
    body = """
FOR i = 0 TO 3
  CASE i OF
    VALUE 1, 2:
      TYPE "one or two"
    VALUE 3:
      TYPE "three"
    ANY
      TYPE "other"
  END
END"""
    assert output_of(program(body)) == "other\none or two\none or two\nthree\n"


def test_while_and_do_until():
    body = """
n = 0
WHILE n < 3 DO
  n = n + 1
END
DO
  n = n - 2
UNTIL n < 0
TYPE n"""
    assert output_of(program(body)) == "-1\n"


def test_if_else_blocks_nest():
    body = """
x = 5
IF x > 2 THEN
  IF x > 10 THEN
    TYPE "big"
  ELSE
    TYPE "medium"
  END
ELSE
  TYPE "small"
END"""
    assert output_of(program(body)) == "medium\n"


def test_strings_concatenate_and_compare_ignoring_case():
    body = '$a = "Adept"\n$b = $a + " " + "V+"\nTYPE $b\nIF $a == "ADEPT" THEN\nTYPE "same"\nEND'
    assert output_of(program(body)) == "Adept V+\nsame\n"


def test_call_passes_variables_by_reference_and_expressions_by_value():
    # [001 L504-610] "Argument Passing by Value or Reference"
    text = (
        program("a = 1\nb = 1\n$s = \"x\"\nCALL change(a, (b), $s)\nTYPE a, \" \", b, \" \", $s", name="main")
        + program("x = x + 10\ny = y + 10\n$t = \"changed\"", name="change", params="x, y, $t")
    )
    assert output_of(text) == "11 1 changed\n"


def test_omitted_arguments_arrive_undefined():
    # [001 L600-610] "Undefined Arguments": test them with DEFINED
    text = program("CALL sub(1, , 3)", name="main") + program(
        'TYPE DEFINED(a), " ", DEFINED(b), " ", DEFINED(c)', name="sub", params="a, b, c"
    )
    assert output_of(text) == "-1 0 -1\n"


def test_auto_variables_are_private_to_each_call():
    text = program("x = 7\nCALL sub()\nTYPE x", name="main") + program("AUTO x\nx = 1", name="sub")
    assert output_of(text) == "7\n"


def test_arrays_grow_on_assignment():
    out = output_of(program("a[2] = 5\na[20] = 6\nTYPE a[2] + a[20]"))
    assert out == "11\n"


def test_names_are_case_insensitive_and_15_characters_significant():
    # [000 L450-456]: only the first 15 characters are significant
    out = output_of(program("this_is_a_long_name = 3\nTYPE THIS_IS_A_LONG_NAME_TOO"))
    assert out == "3\n"


def test_prompt_reads_standard_input():
    out = output_of(program('PROMPT "Enter: ", $ans\nTYPE $ans, " ", VAL($ans) * 2'), stdin="21\n")
    assert out == "Enter: 21 42\n"


def test_parameter_hand_time_with_and_without_equals():
    system, task = run_vplus(program("PARAMETER HAND.TIME = 0.16\nPARAMETER HAND.TIME 0.2"))
    assert task.error is None
    assert system.parameters["HAND.TIME"] == pytest.approx(0.2)


def test_undefined_value_error_names_file_line_and_step():
    system, task = run_vplus(program("x = 1\ny = x + z"))
    err = task.error
    assert err.code == msg.UNDEFINED_VALUE
    assert err.message.startswith("*Undefined value*")
    assert (err.file, err.line, err.step) == ("test.pg", 3, 3)


def test_divide_by_zero_is_a_v_plus_error():
    system, task = run_vplus(program("x = 0\ny = 1 / x"))
    assert task.error.code == msg.DIVIDE_BY_ZERO and task.error.line == 3


def test_call_of_missing_program():
    system, task = run_vplus(program("CALL nowhere()"))
    assert task.error.code == msg.UNDEFINED_PROGRAM


def test_syntax_error_reports_file_line_column_and_text():
    with pytest.raises(ProgramError) as info:
        parse(program("x = = 2"), "bad.pg")
    err = info.value
    assert (err.file, err.line, err.code) == ("bad.pg", 2, msg.SYNTAX_ERROR)
    assert err.column == 5 and err.text == "x = = 2"


def test_missing_end_is_a_control_structure_error():
    with pytest.raises(ProgramError) as info:
        parse(program("FOR i = 1 TO 3\nTYPE i"), "bad.pg")
    assert info.value.code == msg.CONTROL_STRUCTURE and info.value.line == 2


def test_long_loops_yield_time_slices():
    # A compute-bound loop hands the CPU back so simulated time goes on.
    system, task = run_vplus(program("FOR i = 1 TO 5000\nx = i\nEND"))
    assert task.error is None and system.clock() > 0.0


def test_wait_expression_waits_for_a_soft_signal():
    text = program("SIGNAL 2001\nWAIT SIG(2001)\nTYPE \"go\"")
    assert output_of(text) == "go\n"


# ------------------------------------------------------------- issue #3: core
def test_relational_and_logical_results_of_the_manual():
    """[000] L4221-4278 (eV+ [001] L1067-1120): with x = 6 and y = 10."""
    body = """
x = 6
y = 10
TYPE x < y, y >= x, y <> x, x > y, x <> 6, x == y, /S
TYPE " ", NOT(x == 7), (x > 2) AND (y =< 10), NOT(x == 6), (x < 2) OR (y > 10)
z = x == y
TYPE z
"""
    assert output_of(program(body)) == "-1-1-1000 -1-100\n0\n"


@pytest.mark.parametrize("expression, value", [
    ("NOT x + 1", 1),  # level 1: (NOT 5) + 1
    ("COM 0 + 1", 0),  # level 1: (COM 0) + 1
    ("-x MOD 3", -2),  # level 2 before level 3: (-5) MOD 3
    ("1 + 2 AND 0", 1),  # AND is level 3, + level 4: 1 + (2 AND 0)
    ("1 > 0 OR 1", -1),  # OR is level 4, relations level 5: 1 > (0 OR 1)
    ("2 * 3 BAND 6", 6),  # level 3, left to right: (2 * 3) BAND 6
    ("8 / 4 / 2", 1),  # left to right
    ("2 - 3 + 4", 3),
    ("2 > 1 AND 0", -1),  # 2 > (1 AND 0), not (2 > 1) AND 0
    ("(x > 2) AND (x < 10)", -1),
    ("6 BXOR 3 BOR 8", 13),
])
def test_operator_precedence_table(expression, value):
    """[000] L4324-4345 "Order of Evaluation" (eV+ [001] L1169-1180):
    NOT COM > unary minus > * / MOD AND BAND > + - OR BOR XOR BXOR > relations."""
    assert output_of(program(f"x = 5\nTYPE {expression}")) == f"{value}\n"


def test_numeric_literal_forms_and_ascii_constants():
    """[000] L3895-3910: decimal, exponent, ^H hex, ^B binary, ^ octal, ^D double, 'c."""
    out = output_of(program("TYPE ^hff, \" \", ^b11, \" \", ^17, \" \", .5, \" \", 1.5E-3, \" \", -193, \" \", '1"))
    assert out == "255 3 15 0.5 0.0015 -193 49\n"


def test_reals_are_single_precision_unless_declared_double():
    """[000] L3868-3895: a real is a 32-bit single (integers exact to
    16,777,216); DOUBLE declares 64 bits; ^D writes a double constant."""
    body = """
AUTO DOUBLE d
GLOBAL DOUBLE g
s = 16777217
d = ^D16777217
g = 1 / 3
h = 1 / 3
tenth = 0.1
TYPE s - 16777216, " ", d - 16777216, " ", tenth == 0.1
"""
    system, task = run_vplus(program(body))
    assert task.error is None
    assert system.console.output == "0 1 -1\n"
    assert system.globals["g"] == 1 / 3 and system.globals["h"] != 1 / 3
    assert system.globals["h"] == pytest.approx(1 / 3, rel=1e-7)


def test_a_value_beyond_single_precision_is_an_overflow():
    system, task = run_vplus(program("x = 1E30\ny = x * x"))
    assert task.error.code == msg.OVERFLOW and task.error.line == 3


def test_arguments_by_reference_and_by_value_of_the_manual():
    """[001] L504-610 (figure at L582): variables are passed by reference;
    loc:NULL, (real) and $s+"" pass copies; an array element and a whole
    array a[] are passed by reference too."""
    text = program("""
SET loc_var_a = TRANS(1, 2, 3)
SET loc_var_b = TRANS(1, 2, 3)
real_var_a = 1
real_var_b = 1
$string_var_a = "old"
CALL a_routine(loc_var_a:NULL, (real_var_a), real_var_b, $string_var_a+"")
TYPE DX(loc_var_a), " ", real_var_a, " ", real_var_b, " ", $string_var_a
CALL a_routine(loc_var_b, real_var_a, arr[2], $string_var_a)
TYPE DX(loc_var_b), " ", real_var_a, " ", arr[2], " ", $string_var_a
CALL fill(arr[])
TYPE arr[0], " ", arr[2], " ", LAST(arr[])
""", name="main") + program("""
SET any_loc = TRANS(9)
any_real_x = any_real_x + 10
any_real_y = 20
$any_string = "new"
""", name="a_routine", params="any_loc, any_real_x, any_real_y, $any_string") + program(
        "b[0] = 7\nb[5] = 8", name="fill", params="b[]")
    system, task = run_vplus(text, setup=lambda s: s.globals.update({"arr[]": __import__(
        "twin.language.vplus.values", fromlist=["VArray"]).VArray({2: 0.0})}))
    assert task.error is None
    assert system.console.output == "1 1 20 old\n9 11 20 new\n7 20 5\n"


def test_runsig_is_on_while_the_task_runs():
    """RUNSIG ([000] L5162): the signal stays on while the task runs and goes off when it ends."""
    seen = []
    system, task = run_vplus(program("RUNSIG 5\nWAIT\nWAIT\nx = 1 / 0"),
                             each_cycle=lambda s: seen.append(s.io.sig(5)))
    assert task.error.code == msg.DIVIDE_BY_ZERO
    assert seen[1:3] == [True, True] and not system.io.sig(5)


def test_instruction_keywords_may_be_abbreviated_when_unique():
    """The V+ editor expands abbreviated keywords ([000] L2583-2593)."""
    system, task = run_vplus(program("SIGN 2001\nSIG 2002"))
    assert task.error is None and system.io.sig(2001) and system.io.sig(2002)
    with pytest.raises(ProgramError) as info:
        run_vplus(program("x = 1\nRE 1001, x"))
    assert info.value.code == msg.UNKNOWN_KEYWORD and info.value.line == 3
    assert "REACT" in info.value.message


def test_arrays_have_at_most_three_dimensions():
    """[000] L3987-4045: one to three dimensions."""
    system, task = run_vplus(program("a[1,2,3] = 10.5\nTYPE a[1,2,3]"))
    assert task.error is None and system.console.output == "10.5\n"
    with pytest.raises(ProgramError) as info:
        run_vplus(program("a[1,2,3,4] = 1"))
    assert info.value.code == msg.ILLEGAL_ARRAY_INDEX and info.value.line == 2


def test_a_file_holds_programs_and_data_sections_in_any_case():
    """[000] L850-873, L1221-1230: several programs per file, keywords in any
    case, comments and step labels; data sections hold variables' values."""
    text = """; a file as STOREM writes it
.program Main() ; the main program
    type "reals ", x.val, " ", $greeting
    Call Show(arr[1])
.END
.PROGRAM show(v)
10  TYPE "v = ", v
.END
.REALS
x.val = 1.5
arr[1] = 4
.END
.STRINGS
$greeting = "hello"
.END
"""
    assert output_of(text, main="main") == "reals 1.5 hello\nv = 4\n"


def test_run_time_errors_name_file_line_column_and_source_text():
    system, task = run_vplus(program("x = 1\n   y = x + undefined.z"))
    err = task.error
    assert (err.file, err.line, err.column, err.step, err.program) == ("test.pg", 3, 4, 3, "t")
    assert err.code == msg.UNDEFINED_VALUE and "undefined.z" in err.message
    assert err.text == "   y = x + undefined.z"


def test_declarations_must_come_before_the_first_executable_step():
    """[000] L859-864: only comments, blank lines and other declarations may
    come between .PROGRAM and AUTO, LOCAL or GLOBAL."""
    system, task = run_vplus(program("; comment\nAUTO a\nLOCAL b\nGLOBAL DOUBLE c\na = 1\nTYPE a"))
    assert task.error is None and system.console.output == "1\n"
    with pytest.raises(ProgramError) as info:
        run_vplus(program("a = 1\nAUTO b"))
    assert info.value.code == msg.SYNTAX_ERROR and info.value.line == 3
    with pytest.raises(ProgramError):
        run_vplus(program("IF TRUE THEN\n  LOCAL c\nEND"))


def test_an_argument_of_the_wrong_data_type_is_an_error():
    """[001] L510: the argument list must match in number and data type."""
    text = program('CALL sub("text")', name="main") + program("TYPE x", name="sub", params="x")
    system, task = run_vplus(text)
    # The CALL step fails: the arguments it passes do not fit.
    assert task.error.code == msg.WRONG_TYPE and (task.error.program, task.error.line) == ("main", 2)
    text = program("CALL sub(5)", name="main") + program("TYPE $s", name="sub", params="$s")
    assert run_vplus(text)[1].error.code == msg.WRONG_TYPE
    text = program("CALL sub(5)", name="main") + program("TYPE LAST(a[])", name="sub", params="a[]")
    assert run_vplus(text)[1].error.code == msg.WRONG_TYPE


@pytest.mark.parametrize("literal", ["^B111111111", "^B102", "^89", "^D1.2.3"])
def test_a_bad_numeric_literal_is_a_syntax_error(literal):
    """[000] L3895-3910: ^B takes at most 8 binary digits; each radix its own digits."""
    with pytest.raises(ProgramError) as info:
        parse(program(f"x = 1\ny = {literal}"), "bad.pg")
    err = info.value
    assert (err.code, err.file, err.line, err.column) == (msg.SYNTAX_ERROR, "bad.pg", 3, 5)
    assert err.text == f"y = {literal}"


@pytest.mark.parametrize("body, code", [
    ("a[-1] = 1", msg.ILLEGAL_ARRAY_INDEX),  # [000] L3987: indices start at 0
    ("x = 1E39", msg.OVERFLOW),  # beyond a single-precision real
    ("LOCK", msg.INVALID_ARGUMENT),
    ("x = PRIORITY(1)", msg.INVALID_ARGUMENT),
    ("EXIT 0", msg.INVALID_ARGUMENT),
])
def test_load_time_errors_name_file_line_and_text(body, code):
    with pytest.raises(ProgramError) as info:
        run_vplus(program(f"y = 0\n{body}"))
    err = info.value
    assert (err.code, err.file, err.line, err.program, err.text) == (code, "test.pg", 3, "t", body)


def test_case_takes_a_real():
    """[000] L4775: the CASE target must be a real or an integer."""
    system, task = run_vplus(program('CASE "a" OF\n  VALUE 1:\n    TYPE 1\nEND'))
    assert task.error.code == msg.WRONG_TYPE and task.error.line == 2


def test_auto_arrays_keep_their_declared_size_global_arrays_grow():
    """[000] L3995-3997: AUTO arrays must be declared with a size; global and
    LOCAL arrays are extended automatically (L4028-4030).  The declared
    number is the highest index."""
    text = program("AUTO a[3], $s[1, 2]\na[3] = 1\n$s[1, 2] = \"x\"\ng[100] = 2\nTYPE a[3] + g[100], $s[1, 2]")
    assert output_of(text) == "3x\n"
    system, task = run_vplus(program("AUTO a[3]\na[4] = 1"))
    assert task.error.code == msg.ILLEGAL_ARRAY_INDEX and task.error.line == 3


@pytest.mark.parametrize("body", ["pi = 3", "AUTO true", "FOR tps = 1 TO 2\nEND", "PROMPT \"x\", priority",
                                  "SET here = TRANS(1)"])
def test_a_reserved_word_is_not_a_variable_name(body):
    """[000] L3778-3800: "pi (reserved word)" is rejected with an error message.
    Reserved: the function keywords written without an argument list."""
    with pytest.raises(ProgramError) as info:
        run_vplus(program(body))
    assert info.value.code == msg.SYNTAX_ERROR and info.value.line == 2 and "reserved" in info.value.message


def test_a_function_that_needs_arguments_may_name_a_variable():
    """[000] L7699-7702 (eV+ guide L3131): `error = IOSTAT(dlun)`; the name of a
    function that is always followed by "(" stays free for a variable, and the
    function is still there: docs/vplus.md, "Reserved words"."""
    body = "error = -504\nsig = 2\n$error = $ERROR(error)\nTYPE error, sig, \" \", $error, SIG(-1)"
    assert output_of(program(body)) == "-5042 *Unexpected end of file*-1\n"


def test_a_constant_function_passed_to_a_call_is_a_value():
    text = program("CALL sub(TRUE, PI)", name="main") + program("a = 1\nb = 2\nTYPE a", name="sub", params="a, b")
    assert output_of(text) == "1\n"


def test_string_operator_example_of_the_manual():
    """[000] L4315-4321: concatenation with +; relational operators compare
    strings (ignoring case while UPPER is on); a string and a real do not mix."""
    body = '''
$name = "Adept "
$incorp = ", Inc."
$coname = $name + "Technology" + $incorp
TYPE $coname
TYPE "abc" < "abd", "b" > "A", "x" <> "X"
'''
    assert output_of(program(body)) == "Adept Technology, Inc.\n-1-10\n"
    system, task = run_vplus(program('$s = "a" + 1'))
    assert task.error.code == msg.WRONG_TYPE and task.error.line == 2
