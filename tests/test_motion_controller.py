"""The virtual controller end to end: V+ motion programs run on the MuJoCo cells.

Forward processing, continuous path, speed settings, TOOL, precision points, DRIVE, the
V+ errors with the program line and the robot stopped, collisions, the Adept cycle
benchmark, and the same program on the SCARA and the Cartesian cell.  Manual references
are to the V+ Language User's Guide v17 (/work/shared/seeds/vplus-language-users-guide-v17.txt).
"""

from __future__ import annotations

import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest

from twin.controller.location import Location
from twin.language.vplus.runtime import Console, VPlusSystem
from twin.runner import run_program
from twin.simulation import Simulation

ROOT = Path(__file__).resolve().parent.parent
SCARA = ROOT / "scenes" / "scara_pick.toml"
GANTRY = ROOT / "scenes" / "cartesian_pick.toml"
DOWN = (0.0, 180.0, 180.0)  # tool pointing down, jaws along x: the demo cells' orientation


class Probe:
    """Sampled every major cycle through the recorder hook: time, measured and commanded
    joints, the digital outputs and whether the controller is moving."""

    def __init__(self, sim: Simulation):
        self.sim = sim
        self.rows: list[tuple] = []

    def wants_frame(self, t: float) -> bool:
        return True

    def sample(self, t: float, data) -> None:
        c = self.sim.controller
        self.rows.append((t, c.joints(), c.q_command.copy(), dict(self.sim.io.state), c.moving))

    def log_scalar(self, name: str, t: float, value: float) -> None:
        """Signals are read from io.state in sample(); the recorder's stream is not needed."""

    def log_text(self, t: float, text: str, level: str = "INFO", path: str = "program/log") -> None:
        """Cell events are in the report; not needed here."""


def run_on_cell(text: str, scene: Path = SCARA, locations: dict | None = None, max_time: float = 20.0,
                prepare=None, console: Console | None = None):
    """Run V+ `text` on a cell (monitor speed 100 unless the program says otherwise);
    `prepare(sim)` is called just before the run."""
    sim = Simulation(scene)
    probe = Probe(sim)
    sim.recorder = probe
    sim.controller.settings.monitor_speed = 100.0
    system = VPlusSystem(sim.controller, sim.io, sim.clock, console=console or Console(echo=None))
    for name, loc in {**sim.taught_locations(), **(locations or {})}.items():
        system.define_location(name, loc)
    name = system.load_text(text, "test.pg")[0]  # the first program is the main one
    task = system.start(name)
    sim.scheduler.add(task)
    if prepare is not None:
        prepare(sim)
    outcome = sim.run(max_sim_time=max_time)
    return sim, task, outcome, probe.rows


def cycle_time_bench():
    """The module bench/cycle_time.py (the bench folder is not a package)."""
    sys.path.insert(0, str(ROOT / "bench"))
    try:
        import cycle_time
    finally:
        sys.path.pop(0)
    return cycle_time


def _program(*lines: str) -> str:
    return ".PROGRAM t()\n" + "\n".join(f"    {line}" for line in lines) + "\n.END\n"


def _metres(loc: Location) -> np.ndarray:
    T = loc.matrix()
    T[:3, 3] /= 1e3
    return T


def _tip_path(sim: Simulation, rows) -> np.ndarray:
    """Commanded flange positions (mm, robot frame) of the probe rows."""
    return np.array([sim.kinematics.fk(qc)[:3, 3] * 1e3 for _, _, qc, _, _ in rows])


A = Location(350.0, -100.0, 280.0, *DOWN)
B = Location(300.0, 150.0, 250.0, *DOWN)


# ---------------------------------------------------------------- forward processing
def test_signal_after_move_fires_when_the_motion_starts_and_break_waits_for_the_stop():
    """V+ guide v17 L6316-6324: MOVE part.1 / SIGNAL 1 turns the signal on just after the
    robot starts moving; the second MOVE waits for the first motion; L6444-6452: BREAK
    holds SIGNAL 2 until the robot has stopped."""
    sim, task, outcome, rows = run_on_cell(_program("MOVE a", "SIGNAL 1", "MOVE b", "BREAK", "SIGNAL 2"),
                                           locations={"a": A, "b": B})
    assert task.error is None and outcome.errors == []
    first, second = sim.controller.history
    on1 = next(t for t, _, _, io, _ in rows if io.get(1))
    on2 = next(t for t, _, _, io, _ in rows if io.get(2))
    assert first.start_s <= on1 <= first.start_s + 0.02  # within the cycle the motion began
    assert on1 < first.start_s + first.duration_s  # long before the robot arrives
    end = second.start_s + second.duration_s
    assert on2 >= end  # after the last motion is over ...
    q_b = sim.kinematics.ik(_metres(B), sim.controller.joints())
    at_on2 = next(q for t, q, _, io, _ in rows if io.get(2))
    assert np.max(np.abs(at_on2 - q_b)) < 2e-4  # ... and the robot stands at b


def test_closei_waits_for_the_robot_to_stop():
    """OPENI/CLOSEI break continuous path: the hand acts only once the robot has stopped
    (V+ guide v17 L6454-6456, "Breaking Continuous-Path Operation")."""
    sim, task, outcome, rows = run_on_cell(_program("MOVE a", "CLOSEI", "SIGNAL 3"), locations={"a": A})
    assert outcome.errors == []
    (move,) = sim.controller.history
    on = next(t for t, _, _, io, _ in rows if io.get(3))
    assert on >= move.start_s + move.duration_s + 0.16 - 0.02  # stopped, then HAND.TIME (0.05 -> 0.048)


# ---------------------------------------------------------------- continuous path
def test_continuous_path_blends_only_in_the_decel_and_accel_phases():
    """V+ guide v17 "Continuous-Path Trajectories" (L6402-6436): with CP the robot does not
    stop at the corner; "Robot Speed" (L6560-6565): the transition happens in the
    deceleration phase.  The blend overlaps the previous deceleration with the next
    acceleration and nothing else, and only as far as the joint limits allow (a joint that
    turns back allows none: see the limits test below); with DISABLE CP each motion starts
    after the previous."""
    a, b = A.shifted(dz=-80.0), B.shifted(dz=10.0)  # down to a's approach; up to b's
    text = _program("APPRO a, 50", "MOVES a", "DEPARTS 50", "APPRO b, 50", "MOVES b", "BREAK")
    cp_sim, _, out_cp, cp_rows = run_on_cell(text, locations={"a": a, "b": b})
    no_sim, _, out_no, no_rows = run_on_cell(text.replace("APPRO a, 50", "DISABLE CP\n    APPRO a, 50"),
                                             locations={"a": a, "b": b})
    assert out_cp.errors == [] and out_no.errors == []
    cp, no = cp_sim.controller.history, no_sim.controller.history
    assert [m.overlap_s for m in no] == [0.0] * 5
    # The quill turns back at a and at b's approach point: no blend there.
    assert [m.overlap_s > 0 for m in cp] == [False, True, False, True, False]
    for before, after in zip(cp, cp[1:]):
        assert before.start_s + before.duration_s - after.start_s == pytest.approx(after.overlap_s, abs=0.002)
    assert no[-1].start_s + no[-1].duration_s - (cp[-1].start_s + cp[-1].duration_s) > 2 * 0.02
    # The corner above a is rounded, not cut: while the tool is still more than 2 mm from
    # a's vertical it has come down less than 40 % of the approach height.
    path = _tip_path(cp_sim, cp_rows)
    first_a = cp[1].start_s + cp[1].duration_s
    around = [p for (t, *_), p in zip(cp_rows, path) if t <= first_a]
    off_line = [p for p in around if 2.0 < np.hypot(p[0] - a.x, p[1] - a.y) < 20.0]
    assert off_line and min(p[2] for p in off_line) > a.z + 30


def test_a_straight_line_stays_within_0_1_mm_of_the_line():
    """MOVES: the tool tip on the straight line (V+ guide v17 L6336-6343), at full speed:
    the controller's commanded path and the flange the servos actually move (MuJoCo, with
    velocity and acceleration feed-forward), sampled every 16 ms."""
    sim, _, outcome, rows = run_on_cell(_program("MOVE a", "BREAK", "MOVES b", "BREAK"),
                                        locations={"a": A, "b": B})
    assert outcome.errors == []
    start = sim.controller.history[1].start_s
    moving = [r for r in rows if r[0] >= start]
    commanded = _tip_path(sim, moving)
    measured = np.array([sim.kinematics.fk(q)[:3, 3] * 1e3 for _, q, _, _, _ in moving])
    p0, p1 = A.position(), B.position()
    d = (p1 - p0) / np.linalg.norm(p1 - p0)
    for path in (commanded, measured):
        off = path - p0
        deviation = np.linalg.norm(off - np.outer(off @ d, d), axis=1)
        assert deviation.max() < 0.1
    assert np.linalg.norm(commanded[-1] - p1) < 1e-3
    assert np.linalg.norm(measured[-1] - p1) < 0.02


@pytest.mark.parametrize("straight", [False, True])
def test_a_motion_takes_the_time_toppra_computed(straight):
    """MOVE and MOVES to the same point: the executed motion lasts as long as toppra's
    time-optimal trajectory, within 1 % (the 2 ms physics step is the only slack), and the
    servos bring the robot to the destination within FINE soon after."""
    far = Location(100.0, 450.0, 280.0, *DOWN)
    text = _program("MOVE a", "BREAK", f"MOVE{'S' if straight else ''} b", "BREAK", "SIGNAL 1")
    sim, _, outcome, rows = run_on_cell(text, locations={"a": A, "b": far})
    assert outcome.errors == []
    record = sim.controller.history[1]
    assert record.duration_s > 0.25
    assert record.end_s - record.start_s == pytest.approx(record.duration_s, rel=0.01)
    # The record is what the servos were fed: moving until then, still afterwards (16 ms probe).
    moving = [t for t, _, _, _, m in rows if m and t > record.start_s + 0.008]
    assert record.end_s - 0.016 <= max(moving) <= record.end_s + 0.016
    settled = next(t for t, _, _, io, _ in rows if io.get(1))
    assert settled - (record.start_s + record.duration_s) < 0.15


# ---------------------------------------------------------------- speed and modifiers
def test_speed_without_always_applies_to_the_next_motion_only():
    """SPEED without ALWAYS: next motion only; with ALWAYS: every motion after it (V+ guide
    v17 "Motion Modifiers", SPEED*)."""
    text = _program("MOVE a", "SPEED 25", "MOVE b", "MOVE a", "SPEED 25 ALWAYS", "MOVE b", "MOVE a", "BREAK")
    sim, _, outcome, _ = run_on_cell(text, locations={"a": A, "b": B})
    assert outcome.errors == []
    _, slow, fast, slow2, slow3 = [m.duration_s for m in sim.controller.history]
    assert slow > 2 * fast and slow2 > 2 * fast and slow3 > 2 * fast
    assert slow == pytest.approx(slow2, rel=0.01)


def test_speed_mmps_sets_the_straight_line_tool_speed():
    """SPEED 100 MMPS ALWAYS (V+ guide v17 L6601-6610): the tool tip moves at 100 mm/s on a
    long straight line (monitor speed 100)."""
    sim, _, outcome, rows = run_on_cell(_program("MOVE a", "BREAK", "SPEED 100 MMPS ALWAYS", "MOVES b", "BREAK"),
                                        locations={"a": A, "b": B})
    assert outcome.errors == []
    record = sim.controller.history[1]
    length = np.linalg.norm(B.position() - A.position())
    assert record.duration_s == pytest.approx(length / 100.0, rel=0.05)
    start = record.start_s
    path = _tip_path(sim, [r for r in rows if start <= r[0] <= start + record.duration_s])
    speeds = np.linalg.norm(np.diff(path, axis=0), axis=1) / 0.016
    assert speeds.max() == pytest.approx(100.0, rel=0.03)


def test_accel_and_duration_lengthen_a_motion():
    """ACCEL 25, 25 (percent of the maximum) makes the same motion slower; DURATION 1.5
    makes the next motion last at least 1.5 s (V+ guide v17 "Robot Speed", L6646-6650)."""
    text = _program("MOVE a", "MOVE b", "ACCEL 25, 25", "MOVE a", "DURATION 1.5", "MOVE b", "MOVE a", "BREAK")
    sim, _, outcome, _ = run_on_cell(text, locations={"a": A, "b": B})
    assert outcome.errors == []
    _, fast, gentle, stretched, after = [m.duration_s for m in sim.controller.history]
    assert gentle > 1.3 * fast
    assert stretched == pytest.approx(1.5)
    assert after == pytest.approx(gentle)


def test_tool_transformation_moves_the_tool_tip_to_the_location():
    """TOOL (V+ guide v17 "Tool Transformations"): with a tool 100 mm along the flange Z,
    MOVE a puts the tool tip at a, i.e. the flange 100 mm above it, and HERE reports a."""
    low = A.shifted(dz=-100.0)
    text = _program("TOOL TRANS(0, 0, 100)", "MOVE a", "BREAK", "SET h = HERE")
    sim, task, outcome, _ = run_on_cell(text, locations={"a": low})
    assert outcome.errors == []
    flange = sim.kinematics.fk(sim.controller.joints())[:3, 3] * 1e3
    assert np.allclose(flange, low.position() + [0, 0, 100], atol=0.05)
    here = task.globals["h"]
    assert np.allclose(here.position(), low.position(), atol=0.05)


def _servo_references(monkeypatch) -> list[tuple[float, np.ndarray, np.ndarray | None]]:
    """Every servo reference the cell gets, as (time s, qd, qdd): one step's through
    `set_servo`, a chunk of steps' through `servo_feed` (one row a step)."""
    from twin.physics.cell import Cell

    references = []
    set_servo, servo_feed = Cell.set_servo, Cell.servo_feed

    def one(self, q, qd, qdd=None):
        references.append((self.time, np.array(qd), None if qdd is None else np.array(qdd)))
        set_servo(self, q, qd, qdd)

    def rows(self, q, qd, qdd):
        references.extend((self.time + j * self.timestep, np.array(qd[j]), np.array(qdd[j])) for j in range(len(q)))
        return servo_feed(self, q, qd, qdd)

    monkeypatch.setattr(Cell, "set_servo", one)
    monkeypatch.setattr(Cell, "servo_feed", rows)
    return references


def test_duration_lowers_the_speed_and_keeps_the_accelerations(monkeypatch):
    """DURATION slows a motion down as a lower speed would ("the motion is slowed", V+
    Language Reference, DURATION): it lasts the given time, and its joints accelerate as
    hard as without DURATION (a uniform slow-down of a 0.3 s motion to 1.5 s would cut the
    accelerations 25-fold)."""
    references = _servo_references(monkeypatch)
    durations, peaks = [], []
    for prefix in ([], ["DURATION 1.5"]):
        references.clear()
        sim, _, outcome, _ = run_on_cell(_program("MOVE a", "BREAK", *prefix, "MOVE b", "BREAK"),
                                         locations={"a": A, "b": B})
        assert outcome.errors == []
        move = sim.controller.history[1]
        durations.append(move.duration_s)
        kin = sim.kinematics  # the largest acceleration, as a fraction of the joint's maximum
        peaks.append(max(float(np.max(np.abs(qdd) / kin.max_acceleration))
                         for t, _, qdd in references if qdd is not None and move.start_s <= t <= move.end_s))
    assert durations[0] < 0.5 and durations[1] == pytest.approx(1.5)
    assert peaks[1] == pytest.approx(peaks[0], rel=0.1) and peaks[0] > 0.9


def test_precision_point_and_drive_move_the_joints():
    """Precision points hold joint values in degrees and mm (V+ guide v17 L5944-5946);
    DRIVE 2, 10, 50 turns joint 2 by 10 degrees (V+ guide v17 L6380-6388)."""
    joints = (20.0, 60.0, 80.0, 45.0)
    sim, _, outcome, _ = run_on_cell(_program("MOVE #p", "BREAK", "DRIVE 2, 10, 50", "BREAK"),
                                     locations={"#p": joints})
    assert outcome.errors == []
    got = sim.controller.to_user_joints(sim.controller.joints())
    assert np.allclose(got, (20.0, 70.0, 80.0, 45.0), atol=0.02)


# ---------------------------------------------------------------- errors
@pytest.mark.parametrize("target, code, text", [
    ("TRANS(700, 0, 250, 0, 180, 180)", -610, "*Location out of range*"),
    ("TRANS(-300, -250, 250, 0, 180, 180)", -1021, "*Joint 1 limit stop*"),
])
def test_unreachable_location_stops_program_and_robot_with_the_v_plus_error(target, code, text):
    """An unreachable destination: the V+ error with its code and the program line; the
    robot finishes the motion in progress and stands still; the program goes no further."""
    program = _program("MOVE a", f"MOVE {target}", "SIGNAL 1")
    sim, task, outcome, rows = run_on_cell(program, locations={"a": A})
    (error,) = outcome.errors
    assert (error["code"], error["message"], error["line"], error["program"]) == (code, text, 3, "t")
    assert not any(io.get(1) for _, _, _, io, _ in rows)
    assert not sim.controller.moving
    assert np.linalg.norm(sim.controller.here().position() - A.position()) < 0.05


def test_straight_line_through_the_j1_axis_is_refused():
    """A straight line the arm cannot follow (through the hole around the J1 axis) is an
    error before the robot moves, not a path bent around it."""
    program = _program("MOVE a", "MOVES TRANS(-350, -100, 280, 0, 180, 180)")
    sim, _, outcome, _ = run_on_cell(program, locations={"a": A})
    (error,) = outcome.errors
    assert error["code"] in (-610, -1021) and error["line"] == 3
    assert np.linalg.norm(sim.controller.here().position() - A.position()) < 0.05


def test_collision_with_the_cell_is_reported_and_stops_robot_and_program():
    """Driving the gripper into the outfeed belt: a collision error at the program line, the
    robot halted where it hit, and a collision event in the report (docs/motion.md)."""
    into_belt = Location(300.0, 300.0, 150.0, *DOWN)
    program = _program("MOVE a", "MOVE belt", "BREAK", "SIGNAL 1")
    sim, _, outcome, rows = run_on_cell(program, locations={"a": A, "belt": into_belt})
    (error,) = outcome.errors
    assert error["code"] == -1020 and error["message"].startswith("*Collision detected* gripper/")
    assert error["line"] == 4  # the program was waiting in BREAK
    assert not any(io.get(1) for _, _, _, io, _ in rows)
    assert any(e["kind"] == "collision" and "belt" in e["with"] for e in sim.cell.events)
    assert sim.controller.here().z > into_belt.z + 20  # stopped on the belt, not through it


# ---------------------------------------------------------------- benchmark and the gantry
def test_adept_cycle_is_within_15_percent_of_the_datasheet():
    """The standard SCARA cycle (25 mm up, 305 mm over, 25 mm down and back) at full speed
    with continuous path: Cobra s600 datasheet 0.54 s (models/robots/cobra_s600.xml)."""
    bench = cycle_time_bench()
    times = bench.cycle_times(cycles=4)
    assert max(times) - min(times) < 0.02
    assert np.median(times) == pytest.approx(bench.DATASHEET_S, rel=0.15)


def test_the_same_program_runs_on_the_cartesian_cell(tmp_path):
    """move.parts from the eV+ guide, unchanged, on the gantry: the two scenes differ only in
    the robot and the taught locations, and parts go from the nest onto the belt."""
    scara = tomllib.loads(SCARA.read_text())
    gantry = tomllib.loads(GANTRY.read_text())
    assert {k: v for k, v in scara.items() if k not in ("robot", "locations")} == \
        {k: v for k, v in gantry.items() if k not in ("robot", "locations")}
    assert scara["locations"] != gantry["locations"]
    report = run_program(ROOT / "programs" / "vplus" / "move_parts.pg", scene=GANTRY, max_sim_time=14.0).report
    assert [e["message"] for e in report.errors] == ["*Simulation time limit reached* (14 s)"]
    releases = [e for e in report.events if e["kind"] == "release"]
    assert len(releases) >= 5 and all(e["where"] == "conveyor" for e in releases)
    assert not [e for e in report.events if e["kind"] in ("slip", "dropped", "collision")]


def test_base_shifts_the_world_frame_relative_to_the_robot():
    """BASE dx, dy, dz translates the world reference frame relative to the robot (V+ guide
    v17 L6306, digest §7.3): after BASE 20, -30, 0 the location a is reached 20 mm further
    along the robot's x and 30 mm back along its y, and HERE still reads a."""
    sim, task, outcome, _ = run_on_cell(_program("BASE 20, -30, 0", "MOVE a", "BREAK", "SET h = HERE"),
                                        locations={"a": A})
    assert outcome.errors == []
    flange = sim.kinematics.fk(sim.controller.joints())[:3, 3] * 1e3
    assert np.allclose(flange, A.position() + [20, -30, 0], atol=0.05)
    assert np.allclose(task.globals["h"].position(), A.position(), atol=0.05)


def test_cpoff_always_stops_at_every_location_and_cpon_blends_the_next_motion_only():
    """CPOFF ALWAYS: every motion decelerates to a stop; CPON (no ALWAYS) lets the next
    motion blend into the one after it (V+ guide v17 "Motion Modifiers", CPON/CPOFF)."""
    arc = {name: Location(400 * np.cos(np.radians(deg)), 400 * np.sin(np.radians(deg)), 250.0, *DOWN)
           for name, deg in (("p1", -45), ("p2", -15), ("p3", 15), ("p4", 45), ("p5", 75))}
    text = _program("CPOFF ALWAYS", "MOVE p1", "MOVE p2", "CPON", "MOVE p3", "MOVE p4", "MOVE p5", "BREAK")
    sim, _, outcome, _ = run_on_cell(text, locations=arc)
    assert outcome.errors == []
    overlaps = [m.overlap_s > 0 for m in sim.controller.history]
    assert overlaps == [False, False, False, True, False]


def test_a_program_error_mid_motion_brings_the_robot_to_a_stop_on_its_path():
    """A program error while the robot is moving (here an undefined variable, 0.15 s into a
    slow motion): the program stops at that step and the robot decelerates to a stop on its
    path, short of the destination, instead of going on to it."""
    far = Location(300.0, 150.0, 250.0, *DOWN)
    program = _program("MOVE a", "BREAK", "SPEED 20", "MOVE b", "t0 = TIMER(1)", "WAIT TIMER(1) > t0 + 0.15",
                       "x = nothing + 1")
    sim, _, outcome, rows = run_on_cell(program, locations={"a": A, "b": far})
    (error,) = outcome.errors
    assert error["line"] == 8 and error["code"] == -406
    record = sim.controller.history[1]
    stop_time = next(t for t, _, _, _, moving in rows if t > record.start_s + 0.02 and not moving)
    assert stop_time < record.end_s - 0.1  # it did not go on to b
    here = sim.controller.here().position()
    p0, p1 = A.position(), far.position()
    d = (p1 - p0) / np.linalg.norm(p1 - p0)
    assert 0 < (here - p0) @ d < 0.8 * np.linalg.norm(p1 - p0)
    assert not sim.controller.moving


def test_monitor_speed_slows_the_same_motion_down_and_program_speed_replans_it():
    """Monitor speed 50: the same motion, every phase twice as long (V+ Operating System
    Reference Guide, SPEED monitor command: "the path is unaffected but the accelerations
    will be modified"); program speed 50 lowers the speed only, the accelerations stay,
    so the motion takes less than twice as long (V+ guide v17 "Robot Speed")."""
    times = {}
    for setting in ("SPEED 100 MONITOR", "SPEED 50 MONITOR", "SPEED 50 ALWAYS"):
        sim, _, outcome, _ = run_on_cell(_program(setting, "MOVE a", "MOVE b", "BREAK"), locations={"a": A, "b": B})
        assert outcome.errors == []
        times[setting] = sim.controller.history[1].end_s - sim.controller.history[1].start_s
    full = times["SPEED 100 MONITOR"]
    assert times["SPEED 50 MONITOR"] == pytest.approx(2 * full, abs=0.004)
    assert full < times["SPEED 50 ALWAYS"] < 2 * full - 0.02


def test_delay_stops_the_robot_for_that_long_between_motions():
    """DELAY t: the robot comes to a stop and stands still t seconds before the next motion
    (V+ guide v17 motion table, DELAY); a SPEED for the next motion is kept for the next
    real motion."""
    text = _program("MOVE a", "SPEED 25", "DELAY 0.5", "MOVE b", "MOVE a", "BREAK")
    sim, _, outcome, _ = run_on_cell(text, locations={"a": A, "b": B})
    assert outcome.errors == []
    move_a, still, move_b, back = sim.controller.history
    assert 0 <= still.start_s - move_a.end_s <= 0.0161  # no blend into a standstill
    assert still.end_s - still.start_s == pytest.approx(0.5, abs=0.002)
    assert move_b.start_s == pytest.approx(still.end_s, abs=0.016)
    assert move_b.duration_s > 2 * back.duration_s  # SPEED 25 went to MOVE b


def test_straight_line_with_an_offset_tool_keeps_the_tool_tip_on_the_line():
    """With TOOL set, MOVES moves the tool tip, not the flange, in a straight line: a tool
    50 mm off the quill axis and a 90 deg turn of the tool on the way, so the flange
    itself must swing off the line."""
    tool = Location(50.0, 0.0, 80.0, 0.0, 0.0, 0.0)
    a = Location(350.0, -100.0, 200.0, 0.0, 180.0, 180.0)
    b = Location(300.0, 100.0, 200.0, 0.0, 180.0, 90.0)
    sim, _, outcome, rows = run_on_cell(_program("TOOL t", "MOVE a", "BREAK", "MOVES b", "BREAK"),
                                        locations={"a": a, "b": b, "t": tool})
    assert outcome.errors == []
    start = sim.controller.history[1].start_s
    flange = [sim.kinematics.fk(qc) for t, _, qc, _, _ in rows if t >= start]
    T_tool = tool.matrix()
    T_tool[:3, 3] /= 1e3
    tips = np.array([(T @ T_tool)[:3, 3] * 1e3 for T in flange])
    flanges = np.array([T[:3, 3] * 1e3 for T in flange])

    def deviation(path):  # from the line through the path's own end points
        p0, p1 = path[0], path[-1]
        d = (p1 - p0) / np.linalg.norm(p1 - p0)
        off = path - p0
        return np.linalg.norm(off - np.outer(off @ d, d), axis=1).max()

    assert np.linalg.norm(tips[0] - a.position()) < 1e-3 and np.linalg.norm(tips[-1] - b.position()) < 1e-3
    assert deviation(tips) < 0.1
    assert deviation(flanges) > 5.0


def test_nonull_and_coarse_shorten_the_wait_at_a_break():
    """BREAK waits for the position errors to be nulled within FINE; after a COARSE motion
    within the looser COARSE band, after a NONULL motion not at all (V+ guide v17 "Robot
    Speed": "The location tolerance settings (COARSE/FINE, NULL/NONULL)")."""
    waits = {}
    for modifier in ("FINE", "COARSE", "NONULL"):
        text = _program("MOVE a", "BREAK", modifier, "MOVE b", "BREAK", "SIGNAL 1")
        sim, _, outcome, rows = run_on_cell(text, locations={"a": A, "b": B})
        assert outcome.errors == []
        end = sim.controller.history[1].end_s
        waits[modifier] = next(t for t, _, _, io, _ in rows if io.get(1)) - end
    # The program sees the end of the motion at the next 16 ms cycle, the probe 16 ms later.
    assert waits["NONULL"] <= 0.032 < waits["FINE"]
    assert waits["COARSE"] <= waits["FINE"]


def test_brake_stops_the_robot_on_its_path():
    """BRAKE: the robot decelerates to a stop at once, short of its destination, and the
    program goes on (V+ guide v17 L6458-6461)."""
    far = Location(300.0, 150.0, 250.0, *DOWN)
    program = _program("MOVE a", "BREAK", "SPEED 20", "MOVE b", "t0 = TIMER(1)", "WAIT TIMER(1) > t0 + 0.15",
                       "BRAKE", "BREAK", "SIGNAL 1")
    sim, _, outcome, rows = run_on_cell(program, locations={"a": A, "b": far})
    assert outcome.errors == []
    record = sim.controller.history[1]
    on = next(t for t, _, _, io, _ in rows if io.get(1))
    assert on < record.end_s - 0.1
    here = sim.controller.here().position()
    assert np.linalg.norm(here - far.position()) > 50.0
    assert np.linalg.norm(sim.controller.destination().position() - here) < 0.05  # DEST: where it stopped


def test_references_fed_in_chunks_are_those_of_step_by_step_feeding(monkeypatch):
    """The run loop feeds a cycle's servo references in chunks (`servo_chunk`, computed with
    numpy); they are the references `servo_step` gives one step at a time, blends, DELAY
    and the hand's actions at motion starts included, and the robot ends where it did."""
    from twin.controller.controller import VirtualController

    text = _program("APPRO a, 50", "MOVES a", "CLOSEI", "DEPARTS 50", "APPRO b, 50", "MOVE b", "DELAY 0.1",
                    "OPENI", "DEPART 50", "MOVE a", "BREAK")
    runs = []
    for stepwise in (False, True):
        with monkeypatch.context() as patch:
            references = _servo_references(patch)
            if stepwise:
                patch.setattr(VirtualController, "servo_chunk", lambda self, limit: (self.servo_step(), (1, None))[1])
            sim, _, outcome, _ = run_on_cell(text, locations={"a": A, "b": B})
        assert outcome.errors == []
        runs.append((references, sim.cell.robot_qpos(), [m.start_s for m in sim.controller.history],
                     [(e["t"], e["kind"]) for e in sim.cell.events]))
    (chunked, q_chunked, starts_chunked, events_chunked), (stepped, q_stepped, starts_stepped, events_stepped) = runs
    assert len(chunked) > 300
    # Standing still a chunk gets one reference (DELAY) or none; moving, every step gets its own.
    moving = [(t, qd) for t, qd, _ in stepped if np.any(qd)]
    fed = {round(t, 6): qd for t, qd, _ in chunked}
    assert len(moving) > 300 and all(np.array_equal(fed[round(t, 6)], qd) for t, qd in moving)
    assert starts_chunked == starts_stepped and events_chunked == events_stepped
    assert np.allclose(q_chunked, q_stepped, atol=1e-6)


def test_blended_motions_stay_within_the_joint_speed_and_acceleration_limits(monkeypatch):
    """Continuous path rounds a corner only as much as the joint limits allow (V+ Operating
    System Reference, SPEED monitor command: the path is "rounded" near intermediate
    destinations "to prevent excessive accelerations"): every reference the servos get is
    within each joint's maximum speed and acceleration; a joint that reverses (down to a,
    straight back up) gets no overlap at all."""
    references = _servo_references(monkeypatch)
    text = _program("APPRO a, 50", "MOVES a", "DEPARTS 50", "APPRO b, 50", "MOVE b", "DEPART 50", "MOVE a", "BREAK")
    sim, _, outcome, _ = run_on_cell(text, locations={"a": A, "b": B})
    assert outcome.errors == []
    kin = sim.kinematics
    qd = np.array([r[1] for r in references])
    qdd = np.array([r[2] for r in references if r[2] is not None])
    assert len(qd) > 300  # every step of the program's motions (0.8 s)
    assert np.all(np.abs(qd) <= kin.max_velocity * 1.03)
    assert np.all(np.abs(qdd) <= kin.max_acceleration * 1.03)
    overlaps = [m.overlap_s for m in sim.controller.history]
    assert overlaps[1] == 0.0 and overlaps[2] == 0.0  # down onto a, then straight back up
    assert overlaps[3] > 0 and overlaps[4] > 0  # up into the transfer, the transfer down to b


def test_a_robot_held_off_its_destination_times_out_nulling_rather_than_deadlocking():
    """BREAK waits for the joints to settle within FINE.  A robot held off its destination
    (here a 150 N push up on the quill; in the field, a part pressed onto a pile) never
    does: after the nulling time-out the program stops with V+'s *Time-out nulling errors*
    (-1003) at the BREAK, not with the watchdog's *Deadlock*, which confirms a fixed point in
    1 s but must leave a wait with a deadline to end by itself."""
    def push_the_quill(sim: Simulation) -> None:
        sim.cell.data.xfrc_applied[sim.cell.model.body("quill").id, 2] = 150.0

    console = Console(echo=None)
    _, _, outcome, _ = run_on_cell(_program("MOVE a", "BREAK", 'TYPE "settled"'), locations={"a": A},
                                   prepare=push_the_quill, console=console)
    assert [(e["code"], e["message"], e["line"]) for e in outcome.errors] == [(-1003, "*Time-out nulling errors*", 3)]
    assert "settled" not in "".join(console.text)
