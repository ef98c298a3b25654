"""Runaways corpus: programs that can never finish are stopped by the watchdog with an
explanation that names each task, its program, line and statement (docs/robustness.md,
"Runaways"); legitimate waits and long programs are left alone.  Limits are short here
(--no-progress-limit 3) so that each case takes a fraction of a second of wall time."""

from __future__ import annotations

import time

import pytest

from robustness_helpers import gpl_main, gpl_project, run_cli, vplus_file
from twin.controller.watchdog import DEADLOCK, NO_PROGRESS, WALL_TIME_LIMIT

SHORT = ("--no-progress-limit", "3")

# (id, program, expected code, texts the message must hold)
VPLUS_RUNAWAYS = [
    ("busy-while", """
.PROGRAM spin()
    i = 0
    WHILE TRUE DO
        i = i+1
    END
.END""", NO_PROGRESS, ["*No progress* for 3 s", "task 0 in spin"]),
    ("busy-goto", """
.PROGRAM spin()
    x = 0
10  x = x+1
    GOTO 10
.END""", NO_PROGRESS, ["task 0 in spin", "prog.pg:"]),
    ("busy-printing", """
.PROGRAM chatter()
    DO
        TYPE "still here"
    UNTIL FALSE
.END""", NO_PROGRESS, ["*No progress*", "chatter"]),
    ("delay-loop", """
.PROGRAM idle()
    WHILE TRUE DO
        DELAY 0.5
    END
.END""", NO_PROGRESS, ["*No progress*", "idle"]),
    ("timer-wait-never-true", """
.PROGRAM later()
    WAIT TIMER(1) > 1E9
.END""", NO_PROGRESS, ["WAIT TIMER(1) > 1E9"]),
    ("wait-input-nothing-drives", """
.PROGRAM wait.part()
    WAIT SIG(1001)
    TYPE "never"
.END""", DEADLOCK, ["*Deadlock*", "task 0 in wait.part", "WAIT SIG(1001)"]),
    ("wait-soft-signal", """
.PROGRAM wait.soft()
    WAIT SIG(2010)
.END""", DEADLOCK, ["WAIT SIG(2010)"]),
    ("wait-off-output", """
.PROGRAM wait.off()
    SIGNAL 5
    WAIT SIG(-5)
.END""", DEADLOCK, ["WAIT SIG(-5)"]),
    ("two-tasks-deadlocked", """
.PROGRAM main()
    EXECUTE 1 other()
    WAIT SIG(2002)
    SIGNAL 2001
.END
.PROGRAM other()
    WAIT SIG(2001)
    SIGNAL 2002
.END""", DEADLOCK, ["task 0 in main", "WAIT SIG(2002)", "task 1 in other", "WAIT SIG(2001)"]),
    ("wait-event-nobody-sets", """
.PROGRAM wait.ev()
    CLEAR.EVENT
    WAIT.EVENT 1
.END""", DEADLOCK, ["WAIT.EVENT 1"]),
    ("wait-variable-nobody-changes", """
.PROGRAM wait.var()
    ready = FALSE
    WAIT ready
.END""", DEADLOCK, ["WAIT ready"]),
    ("react-on-undriven-signal", """
.PROGRAM main()
    REACT 1003, handler
    WAIT.EVENT 1
.END
.PROGRAM handler()
    TYPE "never"
.END""", DEADLOCK, ["WAIT.EVENT 1"]),
    ("deadlock-after-motion", """
.PROGRAM main()
    MOVE start
    WAIT SIG(1005)
.END""", DEADLOCK, ["WAIT SIG(1005)"]),
    ("one-task-busy-one-waiting", """
.PROGRAM main()
    EXECUTE 1 spin()
    WAIT SIG(2005)
.END
.PROGRAM spin()
    n = 0
    WHILE TRUE DO
        n = n+1
    END
.END""", NO_PROGRESS, ["task 0 in main", "WAIT SIG(2005)", "task 1 in spin"]),
]

GPL_RUNAWAYS = [
    ("busy-while", gpl_main("""        Dim i As Integer
        While True
            i = i + 1
        End While"""), NO_PROGRESS, ["*No progress*", "thread main in M.Main"]),
    ("busy-do-loop", gpl_main("""        Dim s As String
        Do
            s = "x"
        Loop"""), NO_PROGRESS, ["thread main"]),
    ("sleep-loop", gpl_main("""        While True
            Thread.Sleep(500)
        End While"""), NO_PROGRESS, ["Thread.Sleep(500)"]),
    ("poll-input-forever", gpl_main("""        While Not Signal.DIO(10001)
            Thread.Sleep(10)
        End While"""), NO_PROGRESS, ["thread main"]),
    ("wait-event-forever", gpl_main("""        Dim got As Integer
        got = Thread.WaitEvent(1, -1)"""), DEADLOCK, ["*Deadlock*", "Thread.WaitEvent(1, -1)"]),
    ("join-each-other", """
Module M
    Dim a As Thread
    Dim b As Thread
    Public Sub Main()
        a = New Thread("RunA")
        b = New Thread("RunB")
        a.Start()
        b.Start()
        a.Join()
    End Sub
    Public Sub RunA()
        Thread.Sleep(100)
        b.Join()
    End Sub
    Public Sub RunB()
        Thread.Sleep(100)
        a.Join()
    End Sub
End Module""", DEADLOCK, ["thread main", "a.Join()", "thread RunA", "b.Join()", "thread RunB"]),
    ("join-a-sleeper", """
Module M
    Public Sub Main()
        Dim t As New Thread("Sleeper")
        t.Start()
        t.Join()
    End Sub
    Public Sub Sleeper()
        While True
            Thread.Sleep(100000)
        End While
    End Sub
End Module""", NO_PROGRESS, ["t.Join()", "thread Sleeper"]),
    ("join-self", gpl_main("""        Dim me_ As Thread = Thread.CurrentThread
        me_.Join()"""), DEADLOCK, ["me_.Join()"]),
]


def _stopped(capsys, program, code: int, texts: list[str], *extra: str):
    start = time.perf_counter()
    result = run_cli(capsys, "run", program, *SHORT, *extra)
    wall = time.perf_counter() - start
    assert result.status == 1, result.err
    assert f"({code})" in result.err, result.err
    for text in texts:
        assert text in result.err, (text, result.err)
    assert "Traceback" not in result.err
    assert wall < 30, wall  # far under the 90 s bar even on a loaded machine
    return result


@pytest.mark.parametrize("source, code, texts", [c[1:] for c in VPLUS_RUNAWAYS],
                         ids=[c[0] for c in VPLUS_RUNAWAYS])
def test_vplus_runaway_is_stopped_and_explained(tmp_path, capsys, source, code, texts):
    _stopped(capsys, vplus_file(tmp_path, source), code, texts)


@pytest.mark.parametrize("module, code, texts", [c[1:] for c in GPL_RUNAWAYS],
                         ids=[c[0] for c in GPL_RUNAWAYS])
def test_gpl_runaway_is_stopped_and_explained(tmp_path, capsys, module, code, texts):
    _stopped(capsys, gpl_project(tmp_path, module), code, texts)


def test_runaway_report_is_written_with_the_explanation(tmp_path, capsys):
    import json

    program = vplus_file(tmp_path, ".PROGRAM w()\n    WAIT SIG(1001)\n.END")
    report = tmp_path / "out.json"
    _stopped(capsys, program, DEADLOCK, ["WAIT SIG(1001)"], "--report", report)
    (error,) = json.loads(report.read_text())["errors"]
    assert error["code"] == DEADLOCK and "WAIT SIG(1001)" in error["text"]


def test_deadlock_is_found_within_two_simulated_seconds(tmp_path, capsys):
    import json

    program = vplus_file(tmp_path, ".PROGRAM w()\n    WAIT SIG(1001)\n.END")
    report = tmp_path / "out.json"
    run_cli(capsys, "run", program, "--report", report)  # default limits
    data = json.loads(report.read_text())
    assert data["errors"][0]["code"] == DEADLOCK
    assert data["sim_time_s"] < 2.0


def test_default_no_progress_limit_stops_a_busy_loop_within_a_minute(tmp_path, capsys):
    """The default limit, 30 s (a GPL loop: it simulates fastest)."""
    import json

    program = gpl_project(tmp_path, gpl_main("        Dim i As Integer\n        While True\n"
                                             "            i = i + 1\n        End While"))
    report = tmp_path / "out.json"
    run_cli(capsys, "run", program, "--report", report)
    data = json.loads(report.read_text())
    assert data["errors"][0]["code"] == NO_PROGRESS
    assert 30.0 <= data["sim_time_s"] < 31.0


def test_scene_sets_the_no_progress_limit(tmp_path, capsys):
    from conftest import SCARA_SCENE

    scene = tmp_path / "cell.toml"
    text = SCARA_SCENE.read_text()
    assert "[controller]" not in text
    scene.write_text(text + "\n[controller]\nno_progress_s = 2.0\n")
    program = vplus_file(tmp_path, ".PROGRAM s()\n10  GOTO 10\n.END")
    result = run_cli(capsys, "run", program, "--scene", scene)
    assert result.status == 1 and "*No progress* for 2 s" in result.err


def test_wall_time_limit(tmp_path, capsys):
    program = vplus_file(tmp_path, ".PROGRAM s()\n10  GOTO 10\n.END")
    start = time.perf_counter()
    result = run_cli(capsys, "run", program, "--no-progress-limit", "0", "--max-wall-time", "0.5")
    assert time.perf_counter() - start < 10
    assert result.status == 1 and f"*Wall time limit reached* (0.5 s) ({WALL_TIME_LIMIT})" in result.err


def test_no_progress_limit_off_leaves_the_simulated_time_limit(tmp_path, capsys):
    program = vplus_file(tmp_path, ".PROGRAM s()\n10  GOTO 10\n.END")
    result = run_cli(capsys, "run", program, "--no-progress-limit", "0", "--max-sim-time", "2")
    assert result.status == 1 and "*Simulation time limit reached* (2 s)" in result.err


# Legitimate programs the watchdog must leave alone.
LEGITIMATE_VPLUS = [
    ("timed-wait-event", """
.PROGRAM main()
    WAIT.EVENT , 2.5
    TYPE "done"
.END"""),
    ("wait-on-a-busy-task", """
.PROGRAM main()
    EXECUTE 1 count()
    WAIT SIG(2001)
    TYPE "done"
.END
.PROGRAM count()
    n = 0
    FOR i = 1 TO 3000
        n = n+1
    END
    SIGNAL 2001
.END"""),
    ("short-delays", """
.PROGRAM main()
    FOR i = 1 TO 4
        DELAY 0.5
    END
    TYPE "done"
.END"""),
    ("timer-wait", """
.PROGRAM main()
    TIMER 1 = 0
    WAIT TIMER(1) > 2.5
    TYPE "done"
.END"""),
    ("signal-set-by-reaction-task", """
.PROGRAM main()
    EXECUTE 1 helper()
    WAIT SIG(2003)
    TYPE "done"
.END
.PROGRAM helper()
    WAIT.EVENT , 2
    SIGNAL 2003
.END"""),
]


@pytest.mark.parametrize("source", [c[1] for c in LEGITIMATE_VPLUS], ids=[c[0] for c in LEGITIMATE_VPLUS])
def test_legitimate_vplus_program_is_not_stopped(tmp_path, capsys, source):
    result = run_cli(capsys, "run", vplus_file(tmp_path, source), "--no-progress-limit", "3")
    assert result.status == 0, result.err
    assert "done" in result.out


def test_legitimate_gpl_join_of_a_working_thread(tmp_path, capsys):
    module = """
Module M
    Public Sub Main()
        Dim t As New Thread("Work")
        t.Start()
        t.Join()
        Console.WriteLine("done")
    End Sub
    Public Sub Work()
        Thread.Sleep(2500)
    End Sub
End Module"""
    result = run_cli(capsys, "run", gpl_project(tmp_path, module), "--no-progress-limit", "3")
    assert result.status == 0, result.err
    assert "done" in result.out


def test_moving_robot_is_progress(tmp_path, capsys):
    """Motions back and forth for longer than the limit: the robot moves, so it is not stopped."""
    source = """
.PROGRAM main()
    FOR i = 1 TO 3
        APPRO pick, 50
        APPRO place, 50
    END
    TYPE "done"
.END"""
    result = run_cli(capsys, "run", vplus_file(tmp_path, source), "--no-progress-limit", "1")
    assert result.status == 0, result.err


# ------------------------------------------------------------------ a cell that never rests
def _conveyor_scene():
    from conftest import SCARA_SCENE

    return SCARA_SCENE.parent / "scara_conveyor.toml"


def test_program_polling_the_belt_sensor_is_not_stopped(tmp_path, capsys):
    """Parts arrive every 2 s on average past the photo-eye on input 1001: a program counting
    them with WAIT runs its course although it never moves the robot."""
    source = """
.PROGRAM count.parts()
    FOR i = 1 TO 4
        WAIT SIG(1001)
        WAIT SIG(-1001)
    END
    TYPE "done"
.END"""
    result = run_cli(capsys, "run", vplus_file(tmp_path, source), "--scene", _conveyor_scene(),
                     "--no-progress-limit", "6", "--max-sim-time", "60")
    assert result.status == 0, result.err
    assert "done" in result.out


def test_busy_loop_in_a_cell_whose_belt_never_stops_is_stopped(tmp_path, capsys):
    """Parts keep coming and the sensor keeps switching, but the program never looks: no
    progress (and no deadlock: the cell is never at rest)."""
    source = ".PROGRAM spin()\n    i = 0\n    WHILE TRUE DO\n        i = i+1\n    END\n.END"
    result = run_cli(capsys, "run", vplus_file(tmp_path, source), "--scene", _conveyor_scene(), *SHORT)
    assert result.status == 1 and f"({NO_PROGRESS})" in result.err, result.err


def test_wait_on_an_input_no_sensor_drives_in_a_live_cell_is_no_progress(tmp_path, capsys):
    source = ".PROGRAM w()\n    WAIT SIG(1010)\n.END"
    result = run_cli(capsys, "run", vplus_file(tmp_path, source), "--scene", _conveyor_scene(), *SHORT)
    assert result.status == 1 and f"({NO_PROGRESS})" in result.err and "WAIT SIG(1010)" in result.err
