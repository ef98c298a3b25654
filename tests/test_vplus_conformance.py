"""V+ and eV+ as field programs write them (issue #10): each rule with the manual section,
or for constructs the guides only name, the V+ Language Reference form recorded in
docs/vplus.md.  [000] is the V+ Language User's Guide v17, [001] the eV+ guide."""

from __future__ import annotations

import numpy as np
import pytest

from twin.errors import ProgramError
from twin.language.vplus import messages as msg
from twin.runner import run_program

from test_motion_controller import run_on_cell
from test_vplus_tasks import RecordingRobot, drive_inputs
from vplus_helpers import output_of, run_vplus


def program(body: str, name: str = "t", params: str = "") -> str:
    return f".PROGRAM {name}({params})\n{body}\n.END\n"


def load_error(text: str) -> ProgramError:
    with pytest.raises(ProgramError) as caught:
        run_vplus(text)
    return caught.value


# ------------------------------------------------------------ typed declarations
def test_typed_declarations_as_adepts_code_writes_them():
    # [000] L4063 "GLOBAL DOUBLE dbl_real_var", L4096 "AUTO DOUBLE dbl_auto_var"; the
    # Language Reference's AUTO/LOCAL/GLOBAL [type] list: REAL, DOUBLE, LOC.
    text = program("""
AUTO REAL x, y[10]
AUTO LOC #p, spot
LOCAL REAL r
GLOBAL DOUBLE d
x = 0.1
y[10] = 2
r = 1 / 3
d = 1 / 3
SET spot = TRANS(10, 20, 30)
SET #p = #PPOINT(1, 2, 3, 4)
TYPE DX(spot), " ", y[10], " ", LAST(y[])
g = (d == 1 / 3) AND (r <> d) AND (x == 0.1)
""")
    system, task = run_vplus(text)
    assert task.error is None, task.error
    assert system.console.output == "10 2 10\n"
    assert system.globals["g"] == -1.0  # REAL is a single, DOUBLE keeps 64 bits ([000] L3868-3895)
    assert system.globals["d"] == 1 / 3


@pytest.mark.parametrize("body, line", [
    ("AUTO REAL x\nSET x = TRANS(1)", 3),  # a location into a REAL
    ("AUTO LOC spot\nspot = 1", 3),  # a real into a LOC
    ("AUTO REAL $s", 2),  # a string cannot be typed REAL
    ("AUTO DOUBLE #p", 2),  # a precision point is a LOC
    ("GLOBAL DOUBLE d\nSET d = TRANS(1)", 3),
])
def test_declared_types_are_enforced_at_load(body, line):
    err = load_error(program(body))
    assert err.code == msg.WRONG_TYPE and err.line == line and err.text is not None


def test_an_unknown_type_word_is_a_syntax_error_and_a_variable_may_be_named_loc():
    err = load_error(program("AUTO STRING x"))
    assert err.code == msg.SYNTAX_ERROR and err.line == 2 and err.column == 6
    system, task = run_vplus(program("AUTO loc\nSET loc = TRANS(5)\nTYPE DX(loc)"))
    assert task.error is None and system.console.output == "5\n"


# ------------------------------------------------------------ CALLS
def test_calls_with_a_string_variable_and_arguments():
    # [000] L4432-4443: "CALLS $program_name(length, width)"; arguments by reference.
    text = program("""
$program_name = "area"
length = 3
width = 4
CALLS $program_name(length, width)
TYPE length
CALLS "AREA"(width, length)
TYPE width
$program_name = "hello"
CALLS $program_name
""", name="main") + program("a = a * b", name="area", params="a, b") + program('TYPE "hi"', name="hello")
    assert output_of(text) == "12\n48\nhi\n"


# ------------------------------------------------------------ TASK() and STATE()
def test_task_1_is_4_while_a_task_executes():
    # LRG TASK(select, task): field drivers wait with TASK(1, n) == 4 for an executing task.
    text = program("""
EXECUTE 2 worker()
WAIT TASK(1, 2) == 4
TYPE "running ", TASK(1, 2)
WAIT TASK(1, 2) == 0
TYPE "idle ", TASK(1, 2), " never run ", TASK(1, 5), " me ", TASK(1), " ", TASK()
""", name="main") + program("WAIT.EVENT , 0.1", name="worker")
    assert output_of(text) == "running 4\nidle 0 never run 0 me 4 0\n"


def test_state_selectors_real_drivers_read():
    # LRG STATE(select): 1 the robot state (7 program control), 2 the motion state,
    # 3 the manual mode (5 computer control), 4..9 hardware conditions (none here).
    text = program("""
TYPE STATE(1), " ", STATE(2), " ", STATE(3), " ", STATE(4), " ", STATE(5), " ", STATE(9)
MOVE HERE
TYPE STATE(2)
""")
    sim, task, outcome, rows = run_on_cell(text, max_time=2.0)
    assert task.error is None, task.error
    assert task.system.console.output == "7 0 5 0 0 0\n1\n"


# ------------------------------------------------------------ ACCEL (profile)
def test_accel_takes_the_acceleration_profile_in_parentheses():
    # LRG "ACCEL (profile) acceleration, deceleration": profile 0 to 8; a profile not
    # defined for the robot is profile 0 (docs/motion.md); omitted values keep theirs.
    text = program("""
ACCEL (2) 50, 40
TYPE ACCEL(0), " ", ACCEL(1), " ", ACCEL(2)
ACCEL 60
TYPE ACCEL(0), " ", ACCEL(1), " ", ACCEL(2)
ACCEL (0)
TYPE ACCEL(0)
""")
    sim, task, outcome, rows = run_on_cell(text, max_time=1.0)
    assert task.error is None, task.error
    assert task.system.console.output == "2 50 40\n2 60 40\n0\n"
    sim, task, outcome, rows = run_on_cell(program("ACCEL (9) 50"), max_time=1.0)
    assert task.error.code == msg.ILLEGAL_VALUE
    assert load_error(program("SPEED (2) 50")).code == msg.SYNTAX_ERROR


# ------------------------------------------------------------ several files
def test_twin_run_loads_several_files_and_starts_the_first_files_first_program(tmp_path):
    # A cell keeps its programs and its .LOCATIONS / .REALS in separate modules, loaded
    # together as LOAD loads several files ([000] "Program Files"; docs/vplus.md).
    main = tmp_path / "main.pg"
    data = tmp_path / "data.pg"
    main.write_text('.PROGRAM main()\n    TYPE "count ", count, " at ", DX(spot)\n    CALL helper()\n.END\n')
    data.write_text('.PROGRAM helper()\n    TYPE "helper"\n.END\n.LOCATIONS\nspot 100 200 300 0 180 0\n.END\n'
                    ".REALS\ncount = 7\n.END\n")
    result = run_program([main, data], max_sim_time=1.0)
    assert result.report.output == "count 7 at 100\nhelper\n"
    again = tmp_path / "again.pg"
    again.write_text(".PROGRAM helper()\n.END\n")
    with pytest.raises(ProgramError) as caught:
        run_program([main, data, again], max_sim_time=1.0)
    assert caught.value.code == msg.SYNTAX_ERROR and caught.value.file == str(again)


def test_the_command_line_takes_several_files(tmp_path, capsys):
    from twin.cli import main as cli

    (tmp_path / "a.pg").write_text(".PROGRAM a()\n    TYPE x\n.END\n")
    (tmp_path / "b.pg").write_text(".REALS\nx = 42\n.END\n")
    cli(["run", str(tmp_path / "a.pg"), str(tmp_path / "b.pg"), "--max-sim-time", "0.5"])
    assert capsys.readouterr().out == "42\n"


# ------------------------------------------------------------ files and tasks
def test_a_file_open_for_writing_is_locked_against_other_tasks(tmp_path):
    # [000] L7689-7691, [001] L3118: "While a file is open for write or append access,
    # another control program task cannot access that file"; readers may share a file.
    text = program("""
ATTACH (d, 4) "DISK"
FOPENW (d) "log.txt"
WRITE (d) "one"
EXECUTE 1 other()
WAIT TASK(1, 1) == 0
FCLOSE (d)
EXECUTE 1 other()
WAIT TASK(1, 1) == 0
DETACH (d)
""", name="main") + program("""
ATTACH (e, 4) "DISK"
FOPENR (e) "log.txt"
TYPE "read ", IOSTAT(e)
DETACH (e)
""", name="other")
    system, task = run_vplus(text, sandbox=tmp_path)
    assert task.error is None, task.error
    assert system.console.output == f"read {msg.FILE_ALREADY_OPEN}\nread 1\n"


def test_several_tasks_may_read_a_file_at_once(tmp_path):
    (tmp_path / "data.txt").write_bytes(b"abc\r\n")
    text = program("""
ATTACH (d, 4) "DISK"
FOPENR (d) "data.txt"
EXECUTE 1 other()
WAIT TASK(1, 1) == 0
READ (d) $a
TYPE $a
""", name="main") + program("""
ATTACH (e, 4) "DISK"
FOPENR (e) "data.txt"
READ (e) $b
TYPE $b, " ", IOSTAT(e)
FOPENW (e) "data.txt"
""", name="other")
    system, task = run_vplus(text, sandbox=tmp_path)
    assert system.console.output == "abc 1\nabc\n"


# ------------------------------------------------------------ reactions and priority
def test_a_reaction_held_off_by_raised_priority_runs_as_soon_as_it_drops():
    # [000] L1267-1345, L4615-4690: a reaction waits while the program priority is at or
    # above its own (the REACTE trap runs at 254, a reaction routine at its priority, LOCK
    # sets it); it runs when the priority drops: at RETURNE before the next step of the
    # main program, at the routine's RETURN, at LOCK 0.
    text = program("""
REACT 2001, handler, 10
REACTE trap
x = undefined.var + 1
TYPE "main goes on"
SIGNAL -2001
REACT 2001, handler, 10
LOCK 20
SIGNAL 2001
WAIT
WAIT
TYPE "locked"
LOCK 0
TYPE "unlocked"
SIGNAL -2001
REACT 2001, slow, 30
REACT 2002, handler, 10
SIGNAL 2001, 2002
WAIT
WAIT
TYPE "after both"
""", name="main") + program("""
TYPE "trap"
SIGNAL 2001
WAIT
WAIT
TYPE "trap returns"
RETURNE
""", name="trap") + program('TYPE "handler"', name="handler") + program('WAIT\nWAIT\nTYPE "slow"', name="slow")
    assert output_of(text) == ("trap\ntrap returns\nhandler\nmain goes on\nlocked\nhandler\nunlocked\n"
                               "slow\nhandler\nafter both\n")


def test_reacti_without_a_program_only_stops_the_robot():
    # [000] L4497-4500: REACTI stops the robot; with no program named, nothing is called.
    robot = RecordingRobot()
    text = program("REACTI 1001\nWAIT.EVENT , 0.2\nTYPE \"main goes on\"")
    system, task = run_vplus(text, robot=robot, each_cycle=drive_inputs({1001: [(0.05, True), (0.1, False),
                                                                                 (0.15, True)]}))
    assert task.error is None, task.error
    assert system.console.output == "main goes on\n" and robot.stops == 1  # it fires once


# ------------------------------------------------------------ DRY.RUN
def test_dry_run_ignores_motion_instructions():
    # [000] L750-751, L778-779, L5853: with DRY.RUN enabled "robot motion instructions are
    # ignored"; the robot is still attached to the task.
    text = program("""
ENABLE DRY.RUN
SET far = SHIFT(HERE BY 80, 60, 0)
MOVE far
MOVES far
APPRO far, 50
DEPART 30
DRIVE 1, 20, 100
BREAK
TYPE "done"
""")
    sim, task, outcome, rows = run_on_cell(text, max_time=3.0)
    assert task.error is None, task.error
    assert task.system.console.output == "done\n"
    start = rows[0][1]
    assert all(np.allclose(r[2], start, atol=1e-9) for r in rows)  # nothing commanded
    assert not sim.controller.history


# ------------------------------------------------------------ pitch
def test_pitch_is_shown_within_plus_minus_180():
    # [000] L6018-6019: "Pitch is represented as +-180, not as 360 degrees of rotation.
    # Thus, a positive rotation of 190 degrees is shown as -170 degrees."  The SCARA's
    # tool pointing down keeps yaw 0, pitch 180 and its turn in roll.
    text = program("""
SET a = TRANS(0, 0, 0, 0, 190, 0)
TYPE a
DECOMPOSE d[] = a
TYPE d[3], " ", d[4], " ", d[5]
SET b = TRANS(1, 2, 3, 30, 40, 20)
TYPE b
SET c = TRANS(1, 2, 3, 90, 180, 0)
TYPE c
""")
    assert output_of(text) == ("0.00 0.00 0.00 0.000 -170.000 0.000\n0 -170 0\n"
                               "1.00 2.00 3.00 30.000 40.000 20.000\n1.00 2.00 3.00 0.000 180.000 -90.000\n")


# ------------------------------------------------------------ the program stack
@pytest.mark.parametrize("dialect, depth", [("V+", 109), ("eV+", 584)])
def test_call_depth_is_bounded_by_the_stack_size_in_bytes(dialect, depth):
    # [000] "Program Stacks": 6 KB per task in V+ ([001] L445: 32 KB in eV+); a call takes
    # 20 bytes, an argument 32 plus 4 for a real: r(n) is 56 bytes under main's 20.
    text = program("CALL r(0)", name="main") + program("depth = n + 1\nCALL r(n + 1)", name="r", params="n")
    system, task = run_vplus(text, setup=lambda s: setattr(s, "dialect", dialect))
    assert task.error.code == msg.TOO_MANY_CALLS
    assert system.globals["depth"] == (STACK[dialect] - 20) // 56 == depth


STACK = {"V+": 6 * 1024, "eV+": 32 * 1024}


def test_automatic_variables_take_stack_space():
    # [000] "Stack Space Required by a Subroutine": a string 132 bytes, times the array size.
    text = program("CALL r(0)", name="main") + program("AUTO $a[9]\ndepth = n + 1\nCALL r(n + 1)", name="r",
                                                        params="n")
    system, task = run_vplus(text, setup=lambda s: setattr(s, "dialect", "V+"))
    assert task.error.code == msg.TOO_MANY_CALLS
    assert system.globals["depth"] == (6 * 1024 - 20) // (56 + 10 * 132) == 4


def test_the_deepest_ev_plus_stack_is_reached_without_a_python_error():
    text = program("depth = 0\nCALL r", name="main") + program("depth = depth + 1\nWAIT\nCALL r", name="r")
    system, task = run_vplus(text)
    assert task.error.code == msg.TOO_MANY_CALLS and task.error.program == "r"
    assert system.globals["depth"] == (32 * 1024 - 20) // 20


# ------------------------------------------------------------ absent features
@pytest.mark.parametrize("statement", ['MCS "ZERO"', "INT.EVENT 1, 2", "WAIT.START", "x = TIME()",
                                       "ALTON (1) 2", "ALTER (1) 1, 2, 3, 0, 0, 0", "ALTOFF", 'x = STATUS("a")',
                                       "AMOVE 5, 10", "MOVEF loc, 10, 10",
                                       # bus memory of other processor boards, third-party I/O boards
                                       "IOPUTB ^H1000, 0 = 5", 'IOPUTS ^H1000, 0 = "ab"', "x = IOGETW(^H1000, 1)",
                                       "$s = $IOGETS(^H1000, 0, 4)", "x = IOTAS(^H1000, 0)",
                                       "DEF.DIO 1 = ^H2000, 1",
                                       # the arm's own latch, block-command devices
                                       "SET l = LATCH(1)", "SET #p = #PLATCH(1)", "DEVICES (0, 0, st) 1 = 5"])
def test_keywords_of_absent_features_load_and_stop_with_device_not_ready(statement):
    # Issue #10: a field program loads and runs as far as the cell allows, with a clear
    # message where a device is absent (docs/vplus.md, "Absent hardware").
    system, task = run_vplus(program(f'SET loc = TRANS(1)\nTYPE "before"\n{statement}\nTYPE "after"'))
    assert system.console.output == "before\n"
    assert task.error.code == msg.DEVICE_NOT_READY and task.error.line == 4


def test_absent_keywords_leave_their_names_free_for_variables():
    assert output_of(program("time = 3\nstatus = 4\nTYPE time + status")) == "7\n"
