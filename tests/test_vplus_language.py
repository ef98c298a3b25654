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
