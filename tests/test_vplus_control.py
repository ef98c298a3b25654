"""V+ control structures on the interpreter alone: GOTO and labels, EXIT/NEXT,
and the manuals' control-structure examples.

[000] is the V+ Language User's Guide v17, [001] the eV+ Language User's Guide
(../shared/seeds/); line numbers cite them.  The manual listings carry step
numbers in their first column; those are not source and are left out here.
"""

from __future__ import annotations

import pytest

from twin.errors import ProgramError
from twin.language.vplus import messages as msg
from twin.language.vplus.compiler import compile_program
from twin.language.vplus.parser import parse

from vplus_helpers import output_of, run_vplus


LOOPS_WITH_EXIT_AND_NEXT = """
FOR i = 1 TO 6
  IF i == 2 THEN
    NEXT
  END
  IF i == 5 THEN
    EXIT
  END
  TYPE i, /S
END
TYPE " ", i, /S
n = 0
WHILE n < 10 DO
  n = n + 1
  IF n MOD 2 == 1 THEN
    NEXT
  END
  IF n > 6 THEN
    EXIT
  END
  TYPE n, /S
END
TYPE " ", /S
k = 0
DO
  k = k + 1
  IF k == 2 THEN
    NEXT
  END
  TYPE k, /S
UNTIL k >= 4
TYPE
"""

FOR_EXAMPLES = """
FOR i = 2 TO 32
  $names[i] = $CHR(64 + i)
END
FOR i = 2 TO 32 STEP 2
  TYPE $names[i], /S
END
TYPE
FOR i = 1 TO 10
  FOR j = 1 to 10
    values[i,j] = i * j
  END
END
FOR i = 1 TO 10
  FOR j = 1 to 10
    TYPE values[i,j], /S
  END
  TYPE " ", /C1
END
FOR i = 10 TO 1 STEP -1
  TYPE i
END
"""

NESTED_BLOCKS = """
FOR i = 1 TO 4
  CASE i OF
    VALUE 1, 3:
      j = 0
      WHILE j < i DO
        j = j + 1
        IF j == 2 THEN
          NEXT
        ELSE
          TYPE i * 10 + j, /S
        END
      END
    VALUE 2:
      DO
        i = i + 0
        TYPE "d", /S
      UNTIL TRUE
    ANY
      TYPE "any", /S
  END
END
TYPE
"""


def program(body: str, name: str = "t", params: str = "") -> str:
    return f".PROGRAM {name}({params})\n{body}\n.END\n"


def compiled_source(text: str) -> str:
    return compile_program(parse(text).programs[0]).source


def test_goto_skips_forward_to_its_label():
    """[000] L4376-4395 "GOTO": GOTO 100 lands on the step labelled 100."""
    body = """
GOTO 100
TYPE "not printed"
100 TYPE "The instruction GOTO 100 got me he re."
"""
    assert output_of(program(body)) == "The instruction GOTO 100 got me he re.\n"


def test_if_goto_loops_backward():
    """[000] L4723-4733 "IF...GOTO": the branch happens only while the condition is true."""
    body = """
i = 0
10 i = i + 1
TYPE i, /S
IF i < 5 GOTO 10
TYPE
"""
    assert output_of(program(body)) == "12345\n"


def test_case_menu_goto_repeats_the_menu():
    """[000] L4799-4822 (eV+ [001] L1519-1542): the ANY branch prompts again
    (answer discarded) and GOTO 50 shows the menu once more."""
    body = """
; Create a menu structure using a CASE statement
50 TYPE "1. Execute the program."
TYPE "2. Execute the programmer."
TYPE "3. Execute the computer."
PROMPT "Enter menu selection.", select
CASE select OF
  VALUE 1:
    CALL exec_program()
  VALUE 2:
    CALL exec_programmer()
  VALUE 3:
    CALL exec_computer()
  ANY
    PROMPT "Entry must be from 1 to 3", select
    GOTO 50
END
"""
    text = (
        program(body, name="menu")
        + program('TYPE "program"', name="exec_program")
        + program('TYPE "programmer"', name="exec_programmer")
        + program('TYPE "computer"', name="exec_computer")
    )
    menu = "1. Execute the program.\n2. Execute the programmer.\n3. Execute the computer.\nEnter menu selection."
    out = output_of(text, stdin="7\n1\n2\n")
    assert out == f"{menu}Entry must be from 1 to 3{menu}programmer\n"


def test_goto_into_an_if_block_from_outside():
    """[000] L7789-7792 (disk I/O example): label 100 sits inside an IF block
    and is reached by GOTO from outside it."""
    body = """
code = -500
IF code < 0 GOTO 100
code = 0
IF code < 0 THEN
100 TYPE "error ", code
END
TYPE "done"
"""
    assert output_of(program(body)) == "error -500\ndone\n"


def test_goto_out_of_nested_loops_and_back_into_a_for_body():
    body = """
FOR i = 1 TO 3
  FOR j = 1 TO 3
    IF i * j == 4 GOTO 20
    TYPE i * j, /S
  END
END
20 TYPE " at ", i, j
"""
    assert output_of(program(body)) == "1232 at 22\n"


def test_label_on_a_loop_end_runs_the_next_pass():
    """A GOTO to the label of a FOR's END step goes on with the next pass."""
    body = """
FOR j = 1 TO 4
  IF j == 2 GOTO 20
  TYPE j, /S
20 END
TYPE
"""
    assert output_of(program(body)) == "134\n"


def test_goto_to_a_missing_label_is_a_load_error():
    with pytest.raises(ProgramError) as info:
        run_vplus(program("x = 1\nGOTO 99"))
    err = info.value
    assert err.code == msg.UNDEFINED_LABEL and err.message.startswith("*Undefined label*")
    assert (err.line, err.step) == (3, 3)


def test_programs_without_goto_keep_the_structured_form():
    assert "_pc" not in compiled_source(program("FOR i = 1 TO 3\nTYPE i\nEND"))
    assert "_pc" in compiled_source(program("10 TYPE 1\nGOTO 10"))


def test_goto_loop_hands_the_cpu_back():
    """A backward GOTO closes a loop: it is time-sliced like FOR, so a long
    compute loop lets simulated time go on."""
    system, task = run_vplus(program("i = 0\n10 i = i + 1\nIF i < 50000 GOTO 10"))
    assert task.error is None and system.globals["i"] == 50000
    assert system.clock() > 0.0


def test_run_time_error_after_a_goto_names_its_step():
    system, task = run_vplus(program("GOTO 10\nx = 1\n10 y = 1 / 0"))
    assert task.error.code == msg.DIVIDE_BY_ZERO
    assert (task.error.line, task.error.step) == (4, 4)


def test_exit_and_next_in_every_loop_kind():
    """EXIT leaves the innermost loop, NEXT starts its next pass ([000] L5043, L5106)."""
    assert output_of(program(LOOPS_WITH_EXIT_AND_NEXT)) == "134 5246 134\n"


def test_exit_with_a_level_leaves_several_loops():
    body = """
FOR i = 1 TO 3
  FOR j = 1 TO 3
    IF j == 2 THEN
      NEXT 2
    END
    IF i == 3 THEN
      EXIT 2
    END
    TYPE i, j, /S
  END
END
TYPE " ", i
"""
    assert output_of(program(body)) == "1121 3\n"


def test_exit_outside_a_loop_is_a_control_structure_error():
    with pytest.raises(ProgramError) as info:
        run_vplus(program("x = 1\nEXIT"))
    assert info.value.code == msg.CONTROL_STRUCTURE and info.value.line == 3


def test_for_examples_of_the_manual():
    """[000] L4856-4885: even elements of $names, a 10x10 grid, a countdown."""
    lines = output_of(program(FOR_EXAMPLES)).split("\n")
    assert lines[0] == "".join(chr(64 + i) for i in range(2, 33, 2))
    # Each row ends with " " and /C1: one blank line between rows.
    assert lines[1:21:2] == ["".join(str(i * j) for j in range(1, 11)) + " " for i in range(1, 11)]
    assert set(lines[2:21:2]) == {""}
    assert lines[21:31] == [str(i) for i in range(10, 0, -1)]


def test_do_until_examples_of_the_manual():
    """[000] L4911-4934: count to 100; echo until 15 characters or "#"."""
    count = output_of(program("x = 1\nDO\n  TYPE x\n  x = x + 1\nUNTIL x > 100"))
    assert count.split() == [str(i) for i in range(1, 101)]
    body = """
x = 1
DO
  PROMPT "Enter a character: ", $ans
  TYPE $ans
  x = x + 1
UNTIL (x > 15) OR ($ans == "#")
"""
    out = output_of(program(body), stdin="a\nb\n#\nc\n")
    assert out == "Enter a character: a\nEnter a character: b\nEnter a character: #\n"


def test_while_validation_loop_of_the_manual():
    """[000] L4962-4969: re-prompt until the number is in 32..64."""
    body = """
PROMPT "Enter a number in the range 32 to 64.", ans
WHILE (ans < 32) OR (ans > 64) DO
  PROMPT "Number must be in the range 32-64.", ans
END
TYPE ans
"""
    out = output_of(program(body), stdin="7\n99\n40\n")
    assert out == ("Enter a number in the range 32 to 64."
                   "Number must be in the range 32-64.Number must be in the range 32-64.40\n")


def test_if_then_else_example_of_the_manual():
    """[000] L4747-4770: with signal 1033 off, the ELSE branch runs."""
    body = """
need_part = TRUE
IF SIG(1033) AND need_part THEN
  TYPE "picked"
ELSE
  TYPE "Part not picked up."
END
"""
    assert output_of(program(body)) == "Part not picked up.\n"


def test_lowered_while_do_and_case_blocks_with_exit_and_next():
    """Blocks that hold a GOTO run as jumps; EXIT/NEXT inside them, and a
    structured IF inside a lowered loop, still find their loop."""
    body = """
n = 0
WHILE n < 10 DO
  n = n + 1
  IF n == 2 GOTO 30
  IF n == 7 THEN
    EXIT
  END
  CASE n OF
    VALUE 4:
      NEXT
    VALUE 5:
      GOTO 40
  END
  TYPE n, /S
30 END
40 TYPE " n=", n, /S
k = 0
DO
  k = k + 1
  IF k == 2 GOTO 50
  IF k == 3 THEN
    NEXT
  END
  TYPE k, /S
50 UNTIL k >= 4
TYPE
"""
    out = output_of(program(body))
    assert out == "13 n=514\n"
    assert "_pc" in compiled_source(program(body))


_OPENERS = ("IF ", "ELSE", "FOR ", "WHILE ", "DO", "VALUE ", "ANY")


def with_untaken_gotos(body: str) -> str:
    """The same program with an `IF FALSE GOTO` in every block, so that the
    compiler lowers every block to jumps; what it prints must not change."""
    lines = []
    for line in body.splitlines():
        lines.append(line)
        word = line.strip().upper()
        if word.startswith(_OPENERS) and " GOTO " not in word:
            lines.append("IF FALSE GOTO 9999")
    return "\n".join(lines) + "\n9999 TYPE \"\", /S"


@pytest.mark.parametrize("body", [LOOPS_WITH_EXIT_AND_NEXT, NESTED_BLOCKS, FOR_EXAMPLES])
def test_lowered_blocks_behave_as_structured_ones(body):
    structured, lowered = program(body), program(with_untaken_gotos(body))
    assert "_pc" not in compiled_source(structured) and "_pc" in compiled_source(lowered)
    assert output_of(lowered) == output_of(structured)


def test_goto_into_a_for_body_fails_at_its_end():
    """A GOTO into a FOR loop skips the FOR step: at its END there is no loop
    to go on with, a *Control structure error* of that FOR."""
    system, task = run_vplus(program("GOTO 10\nFOR i = 1 TO 3\n10 TYPE \"in\"\nEND"))
    assert system.console.output == "in\n"
    assert task.error.code == msg.CONTROL_STRUCTURE and task.error.line == 3


def test_a_step_label_is_at_most_65535():
    """[000] L805-808: a step label is an integer 0 to 65535."""
    assert output_of(program("GOTO 65535\nTYPE 1\n65535 TYPE 2")) == "2\n"
    with pytest.raises(ProgramError) as info:
        parse(program("65536 TYPE 1"), "bad.pg")
    assert (info.value.code, info.value.line) == (msg.SYNTAX_ERROR, 2)
