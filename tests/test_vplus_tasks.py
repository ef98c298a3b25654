"""V+ multitasking and program interrupts: EXECUTE, ABORT, KILL, PAUSE,
cycles, the time-sliced scheduler, REACT/LOCK/IGNORE, REACTE/RETURNE, event
flags and robot attachment.

[000] is the V+ Language User's Guide v17, [001] the eV+ Language User's Guide
(../shared/seeds/); line numbers cite them.
"""

from __future__ import annotations

import pytest

from twin.controller.scheduler import RELEASE, SLICES, Scheduler
from twin.language.vplus import messages as msg
from twin.language.vplus.tasking import slice_priorities

from vplus_helpers import output_of, run_vplus


def program(body: str, name: str = "t", params: str = "") -> str:
    return f".PROGRAM {name}({params})\n{body}\n.END\n"


# ---------------------------------------------------------------- scheduler
class Busy:
    """A compute-bound task: uses up every slice it is given and logs it."""

    SLICE = object()

    def __init__(self, name: str, priorities, log: list, waits_after: int | None = None):
        self.name, self.priorities, self.log = name, tuple(priorities), log
        self.finished = False
        self.generator = self._run(waits_after)

    def _run(self, waits_after):
        runs = 0
        while True:
            self.log.append(self.name)
            runs += 1
            if waits_after is not None and runs >= waits_after:
                yield lambda: False  # blocked for good
            yield self.SLICE


def test_default_slice_priorities_share_a_cycle_between_tasks_0_and_1():
    """[000] L1960-2075 "Default Task Priorities": in slices 0-12 the task with
    the higher priority of the slice runs (task 1 has 21/11 where task 0 has
    20/10, and 19/9 elsewhere); in slices 13-15 both have priority 0 and take
    turns."""
    log: list = []
    scheduler = Scheduler()
    scheduler.add(Busy("0", slice_priorities(0), log))
    scheduler.add(Busy("1", slice_priorities(1), log))
    scheduler.run_cycle()
    assert "".join(log) == "0011001100110" + "101"


def test_a_higher_priority_task_locks_out_a_lower_one_until_it_waits():
    """[000] L1440-1446: a task that never waits locks out lower-priority tasks
    in its slices; when it waits, the search goes on in the same slice."""
    log: list = []
    scheduler = Scheduler()
    scheduler.add(Busy("low", [10] * SLICES, log))
    scheduler.add(Busy("high", [20] * SLICES, log, waits_after=3))
    scheduler.run_cycle()
    assert log[:4] == ["high", "high", "high", "low"]
    assert log.count("low") == SLICES - 2


def test_equal_priorities_form_a_round_robin_group():
    """[000] L1410-1416: among equal priorities the least recently run goes first."""
    log: list = []
    scheduler = Scheduler()
    for name in "abc":
        scheduler.add(Busy(name, [15] * SLICES, log))
    scheduler.run_cycle()
    assert "".join(log) == "abc" * 5 + "a"


def test_priority_zero_runs_only_when_nothing_else_is_ready_and_minus_one_never():
    """[000] L1386-1390: priority 0 only if no other task of the slice is
    ready; -1 never, even if no other task is ready."""
    log: list = []
    scheduler = Scheduler()
    scheduler.add(Busy("idle", [0] * SLICES, log))
    scheduler.add(Busy("never", [-1] * SLICES, log))
    scheduler.add(Busy("main", [10] * 8 + [-1] * 8, log))
    scheduler.run_cycle()
    assert "".join(log) == "main" * 8 + "idle" * 8


def test_release_hands_the_slice_to_the_next_ready_task():
    log: list = []

    class Releasing(Busy):
        def _run(self, waits_after):
            while True:
                self.log.append(self.name)
                yield RELEASE

    scheduler = Scheduler()
    scheduler.add(Releasing("r", [20] * SLICES, log))
    scheduler.add(Busy("b", [10] * SLICES, log))
    scheduler.run_cycle()
    assert "".join(log[:4]) == "rbrb"


# ---------------------------------------------------------------- tasks
def test_execute_starts_a_task_that_signals_back():
    """Tasks synchronise with soft signals and WAIT SIG(...) ([000] L882-975;
    digest 10.4)."""
    text = program("""
SIGNAL -2001
EXECUTE 1 worker(5)
WAIT SIG(2001)
TYPE "worker counted ", count, " in task ", TASK(0)
""", name="main") + program("""
count = 0
FOR i = 1 TO n
  count = count + 1
  WAIT
END
SIGNAL 2001
""", name="worker", params="n")
    system, task = run_vplus(text)
    assert task.error is None
    assert system.console.output == "worker counted 5 in task 0\n"
    worker = system.task(1)
    assert worker.program == "worker" and worker.finished and worker.error is None


def test_bare_wait_sleeps_until_the_next_major_cycle():
    """[000] L1435-1437: WAIT with no argument suspends the task until slice 0
    of the next major cycle."""
    system, task = run_vplus(program("FOR i = 1 TO 10\n  WAIT\nEND"))
    assert task.error is None
    # Ten WAITs: the program ends in the 11th cycle (cycle 10), after which the clock reads 11 cycles.
    assert system.clock() == pytest.approx(11 * 0.016)


def test_execute_cycles_and_stop_restart_the_program():
    """[000] L4574-4580: STOP ends the cycle; with cycles left the program
    starts again at its first step."""
    text = program("""
EXECUTE 2 counter(), 3
WAIT TASK(1, 2) == 0
TYPE "count ", count
""", name="main") + program("""
IF NOT DEFINED(count) THEN
  count = 0
END
count = count + 1
STOP
count = 1000
""", name="counter")
    assert output_of(text) == "count 3\n"


def test_task_states_pause_proceed_and_abort():
    """TASK(1, n): 4 executing, 2 paused, 0 idle; PAUSE waits for PROCEED
    ([000] L4584-4590); ABORT stops a task ([000] L4455-4470)."""
    text = program("""
EXECUTE 1 pauser()
WAIT TASK(1, 1) == 2
TYPE "paused: ", TASK(1, 1)
WAIT resumed
TYPE "resumed: ", TASK(1, 1)
EXECUTE 2 spinner()
WAIT
ABORT 2
WAIT
WAIT
TYPE "aborted: ", TASK(1, 2)
""", name="main") + program("""
resumed = FALSE
PAUSE
resumed = TRUE
WAIT.EVENT , 1
""", name="pauser") + program("""
DO
  WAIT
UNTIL FALSE
""", name="spinner")
    proceeded = []

    def each_cycle(system):
        pauser = system.task(1)
        if pauser is not None and pauser.paused and not proceeded:
            proceeded.append(system.clock())
            system.proceed(1)

    system, task = run_vplus(text, each_cycle=each_cycle)
    assert task.error is None
    assert system.console.output == "paused: 2\nresumed: 4\naborted: 0\n"
    assert system.task(2).finished and system.task(2).error is None


def test_a_paused_task_alone_ends_the_run_until_proceed():
    system, task = run_vplus(program("PAUSE\nTYPE \"after\""))
    assert not task.finished and task.paused and system.console.output == ""


def test_execute_of_a_running_task_is_an_error():
    text = program("""
EXECUTE 1 spinner()
EXECUTE 1 spinner()
""", name="main") + program("10 WAIT\nGOTO 10", name="spinner")
    system, task = run_vplus(text, max_cycles=20)
    assert task.error.code == msg.TASK_RUNNING and (task.error.line, task.error.step) == (4, 4)


def test_kill_clears_a_paused_task_but_not_a_running_one():
    text = program("""
EXECUTE 1 pauser()
WAIT TASK(1, 1) == 2
KILL 1
TYPE "killed: ", TASK(1, 1)
EXECUTE 2 spinner()
KILL 2
""", name="main") + program("PAUSE\nTYPE \"never\"", name="pauser") + program("10 WAIT\nGOTO 10", name="spinner")
    system, task = run_vplus(text, max_cycles=50)
    assert system.console.output == "killed: 0\n"
    assert task.error.code == msg.TASK_RUNNING and task.error.line == 8


def test_event_flags_set_event_and_wait_event():
    """WAIT.EVENT waits for the task's event flag, which SET.EVENT sets
    ([000] L4476-4491); WAIT.EVENT , t is a t-second delay ([001] L4294)."""
    text = program("""
CLEAR.EVENT
EXECUTE 3 setter()
WAIT.EVENT 1
TYPE "event at ", INT(TIMER(0) * 1000 + 0.5)
""", name="main") + program("WAIT.EVENT , 0.1\nSET.EVENT 0", name="setter")
    system, task = run_vplus(text)
    assert task.error is None
    assert system.console.output == "event at 112\n"


# ---------------------------------------------------------------- reactions
REACT_EXAMPLE = program("""
; Look for a change in signal 1001 from "on" to "off".
; Call subroutine "alarm" if a change is detected.
; Set priority of "alarm" to 10 (default would be 1).
REACT -1001, alarm, 10
CALL step("a")
CALL step("b")
LOCK 20 ;Defer any REACTions to "alarm"
CALL step("c")
CALL step("d")
LOCK 0 ;Allow REACTions
CALL step("e")
IGNORE -1001
TYPE
""", name="main") + program("""
TYPE $name, /S
WAIT.EVENT , 0.1
""", name="step", params="$name") + program("""
TYPE "!", PRIORITY, /S
REACT -1001, alarm, 10 ;the reaction re-enables itself ([000] L4640)
""", name="alarm")


def drive_inputs(edges: dict[int, list[tuple[float, bool]]], initial: bool = False):
    """Each input follows its (time, level) changes on simulated time."""

    def each_cycle(system):
        for signal, changes in edges.items():
            level = initial
            for time, value in changes:
                if system.clock() >= time:
                    level = value
            system.io.set(signal, level)

    return each_cycle


def test_react_example_of_the_manual_with_lock():
    """[000] L4530-4560 (eV+ [001] L1320-1344): a transition during steps a/b
    calls alarm at once, at its priority 10; one during LOCK 20 (steps c, d)
    is deferred until LOCK 0, before step e.  (Each MOVE of the manual is a
    0.1 s step here.)"""
    system, task = run_vplus(REACT_EXAMPLE, setup=lambda s: s.io.set(1001, True),
                             each_cycle=drive_inputs({1001: [(0.05, False), (0.15, True), (0.25, False)]}, initial=True))
    assert task.error is None
    assert system.console.output == "a!10bcd!10e\n"
    assert task.program_priority == 0


def test_react_transition_is_seen_only_at_the_next_major_cycle_and_fires_once():
    """[000] L4627-4628: the transition is detected at the next major cycle.
    Without re-enabling, the reaction fires once."""
    text = program("""
REACT 2001, flag
SIGNAL 2001
TYPE "before ", DEFINED(fired)
WAIT
TYPE "after ", fired
SIGNAL -2001
WAIT
SIGNAL 2001
WAIT
WAIT
TYPE "once ", fired
""", name="main") + program("IF NOT DEFINED(fired) THEN\n  fired = 0\nEND\nfired = fired + 1", name="flag")
    assert output_of(text) == "before 0\nafter 1\nonce 1\n"


def test_react_refuses_signals_the_manual_does_not_allow():
    """[000] L4507: only 1001-1012 and 2001-2008 can be used for REACT."""
    system, task = run_vplus(program("REACT 1013, t"))
    assert task.error.code == msg.ILLEGAL_SIGNAL


def test_reacte_calls_the_trap_and_returne_goes_on_after_the_failed_step():
    """[000] L1334-1345, L4562-4572: with REACTE the error calls the trap
    routine at program priority 254 instead of stopping the program;
    RETURNE goes on with the step after the one that failed."""
    text = program("""
REACTE trouble
TYPE "before"
x = 1 / 0
TYPE "after, priority ", PRIORITY
y = undefined.var + 1
TYPE "end"
""", name="main") + program("""
TYPE $ERROR(ERROR()), " at priority ", PRIORITY
RETURNE
""", name="trouble")
    assert output_of(text) == ("before\n*Divide by zero* at priority 254\nafter, priority 0\n"
                               "*Undefined value* at priority 254\nend\n")


def test_without_reacte_an_error_stops_the_task_at_its_step():
    system, task = run_vplus(program("TYPE 1\nx = 1 / 0\nTYPE 2"))
    assert task.error.code == msg.DIVIDE_BY_ZERO and task.error.step == 3
    assert system.console.output == "1\n"


# ---------------------------------------------------------------- robot
class RecordingRobot:
    """Stands in for the virtual controller: records which motions it was asked for."""

    def __init__(self):
        self.moves: list = []
        self.stops = 0

    def stop(self):
        self.stops += 1

    def move(self, location, straight, **options):
        self.moves.append(location)
        yield lambda: True

    def here(self):
        return "here"


def test_only_the_task_holding_the_robot_may_move_it():
    """[000] L899-930, [001] L406-432: task 0 attaches the robot (eV+: on its
    first motion keyword); another task that moves it gets
    *Robot not attached to this program*."""
    text = program("""
MOVE TRANS(1, 2, 3)
EXECUTE 1 intruder()
WAIT TASK(1, 1) == 3
TYPE "task 1 stopped: ", $ERROR(ERROR(1))
""", name="main") + program("MOVE TRANS(4, 5, 6)", name="intruder")
    robot = RecordingRobot()
    system, task = run_vplus(text, robot=robot)
    assert task.error is None
    assert len(robot.moves) == 1
    assert system.console.output == "task 1 stopped: *Robot not attached to this program*\n"
    assert system.task(1).error.code == msg.ROBOT_NOT_ATTACHED
    assert system.robot_holder is None  # the ended task 0 let the robot go


def test_program_interrupt_example_of_the_manual():
    """[000] L4609-4690 "Program Interrupt Example": task 1 runs at priority
    30 and task 2 at 20 in all slices, each with a reaction at program
    priority 5.  The numbers in the log are the manual's event numbers:
    (3) task 1's reaction interrupts prog_a; (5) prog_a waits for its event
    flag and task 2 runs prog_b; (8) task 2's reaction is deferred by LOCK 10
    and (9) runs at LOCK 0; (11) signal 1003 triggers task 1's reaction and
    sets its event flag, and task 1 interrupts task 2's reaction; (13)
    prog_a waits again and task 2's reaction goes on; (14) SET.EVENT 1 and
    RELEASE; (15) task 1 resumes."""
    text = program("""
EXECUTE 1 prog_a(), , , 30
EXECUTE 2 prog_b(), , , 20
""", name="main") + program("""
a.done = FALSE
REACT 1003, react_a, 5
TYPE "1 prog_a at ", PRIORITY
WHILE NOT a.done DO
END
TYPE "4 prog_a resumes"
CLEAR.EVENT
WAIT.EVENT 1
TYPE "12 prog_a resumes"
CLEAR.EVENT
WAIT.EVENT 1
TYPE "15 prog_a resumes"
""", name="prog_a") + program("""
TYPE "3 react_a at ", PRIORITY
REACT 1003, react_a, 5
a.done = TRUE
""", name="react_a") + program("""
REACT 1010, react_b, 5
TYPE "5 prog_b"
LOCK 10
WHILE NOT SIG(1011) DO
END
TYPE "9 prog_b LOCK 0"
LOCK 0
TYPE "14 prog_b SET.EVENT 1"
SET.EVENT 1
RELEASE
TYPE "prog_b ends at ", PRIORITY
""", name="prog_b") + program("""
TYPE "9 react_b at ", PRIORITY
WHILE NOT SIG(1012) DO
END
TYPE "13 react_b returns"
""", name="react_b")
    inputs = drive_inputs({1003: [(0.05, True), (0.15, False), (0.2, True)], 1010: [(0.1, True)],
                           1011: [(0.15, True)], 1012: [(0.3, True)]})
    system, task = run_vplus(text, each_cycle=inputs)
    assert [t.error for t in system.tasks] == [None, None, None]
    assert system.console.output.splitlines() == [
        "1 prog_a at 0", "3 react_a at 5", "4 prog_a resumes", "5 prog_b", "9 prog_b LOCK 0",
        "9 react_b at 5", "3 react_a at 5", "12 prog_a resumes", "13 react_b returns",
        "14 prog_b SET.EVENT 1", "15 prog_a resumes", "prog_b ends at 0"]


def test_execution_priority_example_of_the_manual():
    """[000] L1474-1530 "Execution Priority Example": tasks 0 and 2 run at
    priority 20, task 1 at 10.  (1) prog_a waits for its event: task 2 runs
    prog_c; (2) prog_c RELEASEs: task 1 runs; (3) prog_c sets task 0's event
    and runs to the end of its slice, then tasks 0 and 2 swap slice by slice;
    (5) prog_a completes: task 2 goes on; (6) prog_c completes: task 1 runs.
    The log gets a letter each time another task takes over (a loop pass is
    a CALL; 1024 passes use up a 1 ms slice)."""
    text = program("""
AUTO i
$log = ""
$last = ""
c.done = FALSE
CALL mark("a")
EXECUTE 1 prog_b(), , , 10
EXECUTE 2 prog_c(), , , 20
CLEAR.EVENT
WAIT.EVENT 1
FOR i = 1 TO 3000
  CALL mark("a")
END
""", name="prog_a") + program("""
DO
  CALL mark("b")
UNTIL c.done
""", name="prog_b") + program("""
AUTO i
FOR i = 1 TO 100
  CALL mark("c")
END
RELEASE
SET.EVENT 0
FOR i = 1 TO 5000
  CALL mark("c")
END
c.done = TRUE
""", name="prog_c") + program("""
IF $c <> $last THEN
  $log = $log + $c
  $last = $c
END
""", name="mark", params="$c")
    system, task = run_vplus(text)
    assert [t.error for t in system.tasks] == [None, None, None]
    assert system.globals["$log"] == "acbc" + "ac" * 3 + "b"


@pytest.mark.parametrize("dialect, code", [("eV+", None), ("V+", msg.ROBOT_ATTACHED)])
def test_task_0_attaches_the_robot_at_its_first_motion_in_ev_plus_at_its_start_in_v_plus(dialect, code):
    """eV+ [001] L416: task 0 attaches the robot "as soon as a motion related
    keyword is encountered"; V+ [000] L896-897: when task 0 begins.  Before
    that, another task may ATTACH it."""
    text = program("EXECUTE 1 taker()\nWAIT TASK(1, 1) <> 4", name="main") + program("ATTACH ()", name="taker")

    def setup(system):
        system.dialect = dialect

    system, task = run_vplus(text, robot=RecordingRobot(), setup=setup)
    taker = system.task(1)
    assert task.error is None and taker.finished
    assert (taker.error.code if taker.error else None) == code


def test_reacti_stops_the_robot_and_calls_the_routine():
    """[000] L4497-4500: REACTI also issues a BRAKE to stop the current robot
    motion at once; the routine is called like REACT's."""
    robot = RecordingRobot()
    text = program("""
REACTI 1001, halted
WAIT.EVENT , 0.2
TYPE "main goes on"
""", name="main") + program('TYPE "reacted"', name="halted")
    system, task = run_vplus(text, robot=robot, each_cycle=drive_inputs({1001: [(0.05, True)]}))
    assert task.error is None
    assert system.console.output == "reacted\nmain goes on\n" and robot.stops == 1


def test_status_shows_each_task_its_program_state_and_step():
    """STATUS ([000] L1000-1004, the monitor command): which program each task
    runs, its state and the step it is at."""
    text = program("""
EXECUTE 1 sleeper()
EXECUTE 2 broken()
WAIT
WAIT
PAUSE
""", name="main") + program("LOCK 3\nWAIT.EVENT , 10", name="sleeper") + program("x = 1 / 0", name="broken")
    system, task = run_vplus(text, max_cycles=10)
    assert system.status() == [
        {"task": 0, "program": "main", "state": "paused", "at": ("main", 7), "priority": 0, "cycles": 1},
        {"task": 1, "program": "sleeper", "state": "running", "at": ("sleeper", 3), "priority": 3, "cycles": 1},
        {"task": 2, "program": "broken", "state": "error", "at": None, "priority": 0, "cycles": 1},
    ]


def test_one_program_in_two_tasks_shares_its_local_but_not_its_auto():
    """[000] L4063-4128, L1232-1250: a LOCAL is shared by every invocation of
    its program, in any task; an AUTO belongs to one call."""
    text = program("""
EXECUTE 1 counter(1)
EXECUTE 2 counter(2)
WAIT (TASK(1, 1) == 0) AND (TASK(1, 2) == 0)
TYPE "shared ", total
""", name="main") + program("""
LOCAL shared
AUTO mine, i
IF NOT DEFINED(shared) THEN
  shared = 0
END
mine = 0
FOR i = 1 TO 5
  shared = shared + 1
  mine = mine + 1
  WAIT
END
result[who] = mine
total = shared
""", name="counter", params="who")
    system, task = run_vplus(text)
    assert task.error is None and system.console.output == "shared 10\n"
    assert dict(system.globals["result[]"]) == {1: 5.0, 2: 5.0}


def test_a_task_without_a_priority_table_gets_one_turn_per_cycle():
    """GPL threads bring no V+ slice table: they run in slice 0 of each cycle."""
    log: list = []

    class Plain(Busy):
        def __init__(self, name, log):
            self.name, self.log, self.finished = name, log, False
            self.generator = self._run(None)

    scheduler = Scheduler()
    scheduler.add(Plain("g", log))
    scheduler.run_cycle()
    scheduler.run_cycle()
    assert log == ["g", "g"]


@pytest.mark.parametrize("trap", [False, True])
def test_an_error_thrown_into_a_waiting_task_belongs_to_its_step(trap):
    """The simulation throws a cell-detected error (a collision) into a task's
    generator: it stops the program at the step it waits in, or goes to its
    REACTE routine, which lets the program go on with the next step."""
    from twin.errors import ProgramError

    text = program(("REACTE trouble\n" if trap else "") + 'WAIT.EVENT , 1\nTYPE "after"', name="main") + program(
        'TYPE "trapped ", ERROR()\nRETURNE', name="trouble")

    def each_cycle(system):
        task = system.task(0)
        if system.clock() >= 0.1 and not task.finished and task.last_error is None:
            try:  # as twin.simulation does for a collision
                task.generator.throw(ProgramError("*Collision detected*", -1020))
            except StopIteration:
                pass  # the task ended

    system, task = run_vplus(text, each_cycle=each_cycle)
    if trap:
        assert task.error is None and system.console.output == "trapped -1020\nafter\n"
    else:
        assert task.error.code == -1020 and (task.error.line, task.error.program) == (2, "main")
        assert system.console.output == ""
