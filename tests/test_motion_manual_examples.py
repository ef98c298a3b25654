"""The motion examples of the V+ Language User's Guide v17 ("Robot Motion" chapter; the eV+
guide has the same examples), run on the SCARA demo cell (scenes/scara_pick.toml) with
their locations moved within the Cobra's reach, and the motion keywords the chapter's
tables list (INRANGE, CONFIG, SPEED(), READY, MOVET, OVERLAP, PAYLOAD, BRAKE from another
task).  Line numbers are those of /work/shared/seeds/vplus-language-users-guide-v17.txt.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from test_motion_controller import DOWN, GANTRY, ROOT, _program, run_on_cell

from twin.controller.location import Location
from twin.physics.cell import Cell

LOC_1 = Location(400.0, -150.0, 280.0, *DOWN)
LOC_2 = Location(250.0, 250.0, 280.0, *DOWN)
# From the cell's start pose through CP_1 to CP_2 every joint keeps its direction: the
# corner at CP_1 can be blended (a joint that turns back cannot, docs/motion.md).
CP_1 = Location(450.0, -50.0, 280.0, *DOWN)
CP_2 = Location(510.0, 60.0, 270.0, *DOWN)


def _flange(sim, q) -> np.ndarray:
    """Flange position (mm, robot frame) for joints q."""
    return sim.kinematics.fk(q)[:3, 3] * 1e3


def _times_on(rows, signal: int) -> float:
    return next(t for t, _, _, io, _ in rows if io.get(signal))


def _tool_speeds(sim, rows) -> tuple[np.ndarray, np.ndarray]:
    """Times and commanded flange speeds (mm/s) between probe rows."""
    t = np.array([r[0] for r in rows])
    p = np.array([_flange(sim, r[2]) for r in rows])
    return t[1:], np.linalg.norm(np.diff(p, axis=0), axis=1) / np.diff(t)


def _global(task, name: str):
    return task.system.globals[name]


def _values_after(program: str, names: tuple[str, ...], **run) -> list:
    """The globals `names` after `program` ran on a cell without an error."""
    _, task, outcome, _ = run_on_cell(program, **run)
    assert outcome.errors == []
    return [_global(task, name) for name in names]


def _hand_commands(monkeypatch) -> list[tuple[float, bool]]:
    """(simulated time, closed) of every command to the gripper valves from now on."""
    commands = []
    original = Cell.set_gripper

    def recording(self, closed):
        commands.append((self.time, bool(closed)))
        original(self, closed)

    monkeypatch.setattr(Cell, "set_gripper", recording)
    return commands


# ---------------------------------------------------------------- forward processing
def test_forward_processing_signals_turn_on_as_each_motion_begins():
    """L6315-6324: MOVE part.1 / SIGNAL 1 / MOVE part.2 / SIGNAL 2.  Signal 1 turns on just
    after the robot begins moving to part.1; the second MOVE waits for the motion to part.1;
    signal 2 turns on just after the motion to part.2 begins, long before the robot gets
    there."""
    program = _program("SPEED 30 ALWAYS", "MOVE part.1", "SIGNAL 1", "MOVE part.2", "SIGNAL 2")
    sim, _, outcome, rows = run_on_cell(program, locations={"part.1": LOC_1, "part.2": LOC_2})
    assert outcome.errors == []
    first, second = sim.controller.history
    on1, on2 = _times_on(rows, 1), _times_on(rows, 2)
    assert first.start_s <= on1 <= first.start_s + 0.033
    assert on2 > first.end_s - first.duration_s / 2  # after the first motion neared its end
    assert second.start_s - 0.033 <= on2 <= second.start_s + 0.033  # as the second one begins
    assert on2 < second.end_s - 0.3
    at_on2 = next(_flange(sim, q) for t, q, _, io, _ in rows if io.get(2))
    assert np.linalg.norm(at_on2 - LOC_2.position()) > 200.0  # far from part.2


def test_break_holds_the_signal_until_the_robot_has_stopped():
    """L6436-6447: MOVE loc.1 / BREAK / SIGNAL 1: the signal is not turned on until the
    robot stops at loc.1."""
    sim, _, outcome, rows = run_on_cell(_program("MOVE loc.1", "BREAK", "SIGNAL 1"), locations={"loc.1": LOC_1})
    assert outcome.errors == []
    (move,) = sim.controller.history
    on = _times_on(rows, 1)
    assert on >= move.end_s
    q_on = next(q for t, q, _, io, _ in rows if io.get(1))
    assert np.linalg.norm(_flange(sim, q_on) - LOC_1.position()) < 0.05


# ---------------------------------------------------------------- continuous path
@pytest.mark.parametrize("cp", [True, False])
def test_continuous_path_passes_loc_1_without_stopping_and_disable_cp_stops_there(cp):
    """L6416-6440: with CP on, MOVE loc.1 / MOVE loc.2 does not stop at loc.1, the robot
    "smoothly changes its direction"; with the CP switch disabled it stops at loc.1.  Either
    way forward processing goes on: SIGNAL 1 turns on as the first motion begins."""
    program = _program("ENABLE CP" if cp else "DISABLE CP", "MOVE loc.1", "SIGNAL 1", "MOVE loc.2", "BREAK")
    sim, _, outcome, rows = run_on_cell(program, locations={"loc.1": CP_1, "loc.2": CP_2})
    assert outcome.errors == []
    first, second = sim.controller.history
    assert _times_on(rows, 1) <= first.start_s + 0.033
    closest = min(np.linalg.norm(_flange(sim, qc) - CP_1.position()) for _, _, qc, _, _ in rows)
    if cp:
        t, speed = _tool_speeds(sim, rows)
        near_loc_1 = (t > first.end_s - 0.1) & (t < second.start_s + 0.1)
        assert second.overlap_s > 0.05
        assert speed[near_loc_1].min() > 100.0  # mm/s: it never stops at loc.1 ...
        assert closest > 1.0  # ... and cuts the corner
    else:
        assert second.overlap_s == 0.0 and second.start_s >= first.end_s
        assert closest < 1e-6  # commanded to loc.1 exactly, at rest


@pytest.mark.parametrize("always", [False, True])
def test_motion_modifiers_apply_to_the_next_motion_or_with_always_to_all(always):
    """"Motion Modifiers" (L6636-6660): COARSE/FINE, NULL/NONULL (marked *) take ALWAYS;
    without it they apply to the next motion only.  NONULL: BREAK does not wait for the
    position errors to be nulled, so the signal after it comes at once."""
    modifier = "NONULL ALWAYS" if always else "NONULL"
    program = _program("MOVE a", "BREAK", modifier, "MOVE b", "BREAK", "SIGNAL 1", "MOVE a", "BREAK",
                       "SIGNAL 2")
    sim, _, outcome, rows = run_on_cell(program, locations={"a": CP_1, "b": CP_2})
    assert outcome.errors == []
    _, to_b, back_to_a = sim.controller.history
    assert _times_on(rows, 1) - to_b.end_s < 0.033  # no nulling wait after the NONULL motion
    wait_at_a = _times_on(rows, 2) - back_to_a.end_s
    assert (wait_at_a < 0.033) if always else (wait_at_a > 0.033)


# ---------------------------------------------------------------- procedural motion
def test_procedural_motion_through_a_path_array_at_0_75_ips():
    """L6491-6505: SPEED 0.75 IPS ALWAYS / FOR index = 0 TO LAST(path[]) / MOVES path[index]:
    "The robot tool moves at the constant speed of 0.75 inch per second through each
    location"; the path array is built with SHIFT (L6063-6070), 15 mm apart on a line."""
    program = _program(
        "FOR i = 0 TO 4", "SET path[i] = SHIFT(a BY 0, 15*i, 0)", "END",
        "MOVE path[0]", "BREAK",
        "SPEED 0.75 IPS ALWAYS",
        "FOR index = 0 TO LAST(path[])", "MOVES path[index]", "END",
        "BREAK")
    sim, _, outcome, rows = run_on_cell(program, locations={"a": LOC_1}, max_time=12.0)
    assert outcome.errors == []
    legs = sim.controller.history[2:]  # MOVES path[0] (already there), then path[1..4]
    assert len(legs) == 4
    t, speed = _tool_speeds(sim, rows)
    cruising = (t > legs[0].start_s + 0.3) & (t < legs[-1].end_s - 0.3)
    assert np.median(speed[cruising]) == pytest.approx(0.75 * 25.4, rel=0.02)
    assert speed[cruising].min() > 0.9 * 0.75 * 25.4  # no stop at the intermediate points
    here = sim.controller.here().position()
    assert np.linalg.norm(here - (LOC_1.position() + (0, 60, 0))) < 0.05


def test_procedural_circular_arc_moves_angle_step_every_0_5_s():
    """L6507-6530: the tool follows a computed arc, x = radius*COS(angle)+x.center,
    y = radius*SIN(angle)+y.center, MOVE TRANS(x, y, z, 0, 180, 0), one segment per
    angle.step, each lasting DURATION 0.5 s: "the program moves the robot tool angle.step
    degrees around the arc every 0.5 second" (DURATION 0.5 ALWAYS, as printed); z = 250
    instead of 0 (the Cobra's reach); `last` is LAST, a function name and so a reserved
    word (digest §15): the variable is `last.angle`."""
    program = _program(
        "radius = 60", "x.center = 350", "y.center = 0", "start = 0", "last.angle = 90", "angle.step = 15",
        "MOVE TRANS(radius*COS(start)+x.center, radius*SIN(start)+y.center, 250, 0, 180, 0)", "BREAK",
        "DURATION 0.5 ALWAYS",
        "FOR angle = start TO last.angle STEP angle.step",
        "x = radius*COS(angle)+x.center", "y = radius*SIN(angle)+y.center",
        "MOVE TRANS(x, y, 250, 0, 180, 0)",
        "END", "BREAK")
    sim, _, outcome, rows = run_on_cell(program, max_time=12.0)
    assert outcome.errors == []
    arc = sim.controller.history[2:]  # after the move to the start and the one to angle 0
    assert len(arc) == 6
    assert all(m.duration_s >= 0.5 - 1e-9 for m in arc)
    # DURATION lowers the speed, not the accelerations: the short deceleration of one segment
    # blends into the next one's acceleration, a new angle.step every 0.5 s.
    period = (arc[-1].start_s - arc[0].start_s) / (len(arc) - 1)
    assert period == pytest.approx(0.5, abs=0.01)
    for k, motion in enumerate(arc, start=1):
        angle = math.radians(15 * k)
        on_circle = (350 + 60 * math.cos(angle), 60 * math.sin(angle), 250.0)
        assert np.allclose(motion.destination.position(), on_circle, atol=1e-6)
    t, _ = _tool_speeds(sim, rows)
    p = np.array([_flange(sim, r[2]) for r in rows])[1:]
    on_arc = (t > arc[0].start_s) & (t < arc[-1].end_s)
    radial = np.linalg.norm(p[on_arc, :2] - (350.0, 0.0), axis=1)
    assert np.all(np.abs(radial - 60.0) < 3.0)  # joint moves between close points: near the arc
    assert np.linalg.norm(sim.controller.here().position() - (350, 60, 250)) < 0.05


def test_a_motion_takes_at_least_one_trajectory_cycle():
    """"The minimum motion times ... must be greater than or equal to the configured
    trajectory cycle time" (16 ms at 62.5 Hz, L6541-6553): a 0.05 mm move, which the robot
    could make in a few ms, takes one cycle; so do the segments of a loop of such moves."""
    program = _program("MOVE a", "BREAK", "FOR i = 1 TO 5", "MOVES SHIFT(a BY 0.05*i, 0, 0)", "END", "BREAK")
    sim, _, outcome, _ = run_on_cell(program, locations={"a": LOC_1})
    assert outcome.errors == []
    steps = sim.controller.history[1:]
    assert len(steps) == 5 and all(m.duration_s == pytest.approx(0.016) for m in steps)
    assert np.linalg.norm(sim.controller.here().position() - LOC_1.shifted(0.25, 0, 0).position()) < 0.05


# ---------------------------------------------------------------- locations
def test_relative_transformations_example():
    """L6134-6183 (the figure "Relative Transformation"), shifted by (0, -100, -70) mm to
    the Cobra's reach: MOVE loc_a:TRANS(-50, 20, 30) goes to (350, -30, 250); loc_b =
    -50, 20, 30, 0, 0, 0; loc_c = loc_a:loc_b; MOVE loc_c:loc_b, MOVE loc_a:loc_b:loc_d
    with loc_d = TRANS(0,50) ("x = -50, y = 70, z = 30 relative to loc_a") and
    MOVE loc_c:INVERSE(loc_b) back to loc_a.  HERE loc_a:loc_b as printed."""
    program = _program(
        "SET loc_a = TRANS(300,-50,280,0,180,0)",
        "MOVE loc_a", "BREAK", "SET h1 = HERE",
        "MOVE loc_a:TRANS(-50, 20, 30)", "BREAK", "SET h2 = HERE",
        "HERE loc_a:loc_b",
        "SET loc_c = loc_a:loc_b",
        "MOVE loc_c:loc_b", "BREAK", "SET h3 = HERE",
        "SET loc_d = TRANS(0,50)",
        "MOVE loc_a:loc_b:loc_d", "BREAK", "SET h4 = HERE",
        "MOVE loc_c:INVERSE(loc_b)", "BREAK", "SET h5 = HERE")
    sim, task, outcome, _ = run_on_cell(program)
    assert outcome.errors == []
    expected = {"h1": (300, -50, 280), "h2": (350, -30, 250), "h3": (400, -10, 220),
                "h4": (350, 20, 250), "h5": (300, -50, 280)}
    for name, position in expected.items():
        assert np.linalg.norm(_global(task, name).position() - position) < 0.05, name
    assert np.allclose(_global(task, "loc_b").components(), (-50, 20, 30, 0, 0, 0), atol=0.05)
    assert np.allclose(_global(task, "loc_c").components()[:5], (350, -30, 250, 0, 180), atol=0.05)


def test_pallet_frame_example_visits_the_twelve_cells():
    """L6200-6231: SET pallet.frame = FRAME(loc.origin, loc.x.axis, loc.pos.y, loc.origin),
    cell.space = 50, FOR i = 0 TO 3 / FOR J = 0 TO 2: APPRO 25, MOVE, BREAK, CLOSEI,
    DEPART 25.  The three taught points are given instead of taught with the pendant;
    the pallet's +y runs along the robot's -y, so its Z points down, as the tool does."""
    program = _program(
        "SET pallet.frame = FRAME(loc.origin, loc.x.axis,loc.pos.y, loc.origin)",
        "cell.space = 50",
        "FOR i = 0 TO 3", "FOR J = 0 TO 2",
        "APPRO pallet.frame:TRANS(i*cell.space, j*cell.space), 25",
        "MOVE pallet.frame:TRANS(i*cell.space, j*cell.space)",
        "BREAK", "CLOSEI", "DEPART 25",
        "END", "END", "BREAK")
    origin = Location(250.0, 40.0, 230.0, *DOWN)
    sim, _, outcome, rows = run_on_cell(program, max_time=30.0, locations={
        "loc.origin": origin, "loc.x.axis": origin.shifted(100, 0, 0), "loc.pos.y": origin.shifted(40, -80, 0)})
    assert outcome.errors == []
    at_rest = [_flange(sim, q) for t, q, _, _, moving in rows if not moving]
    for i in range(4):
        for j in range(3):
            cell = np.array([250 + 50 * i, 40 - 50 * j, 230])
            assert min(np.linalg.norm(p - cell) for p in at_rest) < 0.05, (i, j)
    assert len(sim.controller.history) == 36
    assert np.linalg.norm(sim.controller.here().position() - (400, -60, 255)) < 0.05


def test_locations_taught_relative_to_an_assembly_frame_follow_the_frame():
    """L6236-6278: locations recorded relative to assm.frame (HERE assm.frame:loc.1) are
    visited at the same place on the assembly wherever the frame is taught next ("the frame
    must be taught each time the assembly moves - the locations on the assembly must be
    taught only once").  HERE assm.frame:loc.n and the moves as printed, the second APPRO to
    loc.1 included."""
    teach = ["SET assm.frame = FRAME(o1, x1, y1, o1)",
             "MOVE p1", "BREAK", "HERE assm.frame:loc.1",
             "MOVE p2", "BREAK", "HERE assm.frame:loc.2"]
    visit = ["SET assm.frame = FRAME(o2, x2, y2, o2)",
             "APPRO assm.frame:loc.1, 25", "MOVE assm.frame:loc.1", "BREAK", "SET h1 = HERE", "DEPART 25",
             "APPRO assm.frame:loc.1, 25", "MOVE assm.frame:loc.2", "BREAK", "SET h2 = HERE", "DEPART 25", "BREAK"]
    o1 = Location(300.0, -100.0, 230.0, *DOWN)
    o2 = Location(350.0, -40.0, 230.0, *DOWN)  # the assembly moved 50, 60 mm and turned 30 deg
    turn = math.radians(30.0)
    x2 = o2.shifted(100 * math.cos(turn), 100 * math.sin(turn), 0)
    y2 = o2.shifted(100 * math.sin(turn), -100 * math.cos(turn), 0)  # the frame's +Y: Z down
    p1, p2 = o1.shifted(40, -20, 0), o1.shifted(80, -50, -10)
    _, task, outcome, _ = run_on_cell(_program(*teach, *visit), locations={
        "o1": o1, "x1": o1.shifted(100, 0, 0), "y1": o1.shifted(0, -100, 0), "p1": p1, "p2": p2,
        "o2": o2, "x2": x2, "y2": y2})
    assert outcome.errors == []

    def on_moved_assembly(p: Location) -> np.ndarray:  # p1, p2 carried along with the frame
        dx, dy = p.x - o1.x, -(p.y - o1.y)  # in the first frame (its +Y is the robot's -Y)
        return np.array([o2.x + dx * math.cos(turn) + dy * math.sin(turn),
                         o2.y + dx * math.sin(turn) - dy * math.cos(turn), p.z])

    assert np.linalg.norm(_global(task, "h1").position() - on_moved_assembly(p1)) < 0.05
    assert np.linalg.norm(_global(task, "h2").position() - on_moved_assembly(p2)) < 0.05


def test_def_tool_computes_the_new_tool_from_a_reference_location():
    """def.tool (L12424-12485), its tool arithmetic without the pendant: with the reference
    tool (here the bare flange, as L12486-12491 recommend) the robot records ref.loc; the
    new tool's tip is brought to ref.loc (here: a MOVE with the true tool, standing for the
    operator's jogging); then SET new.tool = ref.tool:INVERSE(HERE):ref.loc gives the new
    tool, and with TOOL new.tool, HERE reads ref.loc."""
    program = _program(
        "TOOL ref.tool", "MOVE ref.point", "BREAK", "SET ref.loc = HERE",
        "TOOL true.tool", "MOVE ref.loc", "BREAK",
        "TOOL ref.tool",
        "SET new.tool = ref.tool:INVERSE(HERE):ref.loc",
        "TOOL new.tool", "SET h = HERE")
    true_tool = Location(12.0, -30.0, 95.0, 25.0, 0.0, 0.0)
    reference = LOC_1.shifted(0, 0, -100)  # low enough for the flange to reach it with the tool
    _, task, outcome, _ = run_on_cell(program, locations={
        "ref.tool": Location(0, 0, 0, 0, 0, 0), "ref.point": reference, "true.tool": true_tool})
    assert outcome.errors == []
    new_tool = _global(task, "new.tool")
    assert np.linalg.norm(new_tool.position() - true_tool.position()) < 0.05
    assert np.allclose(new_tool.matrix()[:3, :3], true_tool.matrix()[:3, :3], atol=1e-3)
    assert np.linalg.norm(_global(task, "h").position() - reference.position()) < 0.05


def test_appro_move_depart_along_the_tool_z_axis():
    """L6343-6361: APPRO place, 50 / MOVE place / DEPART 50: 50 mm back along the tool Z axis
    (straight up for a tool pointing down), down to place, back up 50 mm."""
    program = _program("APPRO place, 50", "MOVE place", "DEPART 50", "BREAK")
    sim, _, outcome, rows = run_on_cell(program, locations={"place": LOC_1})
    assert outcome.errors == []
    appro, move, depart = sim.controller.history
    above = LOC_1.position() + (0, 0, 50)
    assert np.allclose(appro.destination.position(), above, atol=1e-6)
    assert np.allclose(depart.destination.position(), above, atol=1e-6)
    assert depart.overlap_s == 0.0 and depart.start_s >= move.end_s  # the quill turns back at place
    closest = min(np.linalg.norm(_flange(sim, q) - LOC_1.position()) for _, q, _, _, _ in rows)
    assert closest < 0.5  # measured, sampled every 16 ms
    assert np.linalg.norm(sim.controller.here().position() - above) < 0.05


def test_drive_moves_one_joint():
    """L6378-6388: DRIVE 2,50.0,100 turns joint 2 by 50 degrees, DRIVE 3,25,100 lowers the
    quill (joint 3) by 25 mm."""
    sim, _, outcome, _ = run_on_cell(_program("MOVE #p", "DRIVE 2,50.0, 100", "DRIVE 3,25, 100", "BREAK"),
                                     locations={"#p": (10.0, 30.0, 40.0, 0.0)})
    assert outcome.errors == []
    got = sim.controller.to_user_joints(sim.controller.joints())
    assert np.allclose(got, (10.0, 80.0, 65.0, 0.0), atol=0.02)


def test_sample_robot_program_moves_as_its_detailed_description_says(monkeypatch):
    """move.parts, the "Sample Robot Program" (listing L12078-12114, "Detailed Description"
    L12116-12257), with parts = 2 on the demo cell: OPEN acts during the MOVE start, the
    robot RIGHTY; per part APPRO pick 25.4 mm above (joint), MOVES pick (straight line),
    CLOSEI once the robot stands at pick and 160 ms before it goes on, DEPARTS 25.4; the
    same at place with 50.8 mm and OPENI; then "All done. 2 parts processed"."""
    hand = _hand_commands(monkeypatch)
    text = (ROOT / "programs" / "vplus" / "move_parts.pg").read_text().replace("parts = 100", "parts = 2")
    sim, task, outcome, rows = run_on_cell(text)
    assert outcome.errors == []
    assert task.system.console.output == "All done. 2 parts processed\n"
    start, *cycle = sim.controller.history
    assert hand[0] == (pytest.approx(start.start_s, abs=0.003), False)  # OPEN, as MOVE start begins
    taught = sim.taught_locations()
    up1, up2 = np.array([0, 0, 25.4]), np.array([0, 0, 50.8])
    expected = [(False, taught["pick"].position() + up1), (True, taught["pick"].position()),
                (True, taught["pick"].position() + up1), (False, taught["place"].position() + up2),
                (True, taught["place"].position()), (True, taught["place"].position() + up2)] * 2
    assert len(cycle) == len(expected)
    for motion, (straight, position) in zip(cycle, expected):
        assert motion.straight == straight
        assert np.allclose(motion.destination.position(), position, atol=1e-6)
    closes = [t for t, closed in hand if closed]
    opens = [t for t, closed in hand[1:] if not closed]
    for k in range(2):
        _, at_pick, leave_pick, _, at_place, leave_place = cycle[6 * k:6 * k + 6]
        assert at_pick.end_s <= closes[k] and closes[k] + 0.16 - 1e-9 <= leave_pick.start_s
        assert at_place.end_s <= opens[k] and opens[k] + 0.16 - 1e-9 <= leave_place.start_s
    assert all(sim.kinematics.is_righty(q) for _, q, _, _, _ in rows)


# ---------------------------------------------------------------- motion functions
def test_inrange_and_speed_2_guard_a_move():
    """L5394-5404: IF INRANGE(loc_1) == 0 THEN / IF SPEED(2) > 50 THEN SPEED 50 END /
    MOVE(loc_1) / END: a reachable loc_1 is moved to at program speed 50 (not the 80 set
    ALWAYS), an unreachable one is not moved to and is no error."""
    guarded = ["SPEED 80 ALWAYS", "IF INRANGE(loc_1) == 0 THEN", "IF SPEED(2) > 50 THEN", "SPEED 50", "END",
               "MOVE(loc_1)", "END", "BREAK"]
    sim, _, outcome, _ = run_on_cell(_program(*guarded), locations={"loc_1": LOC_1})
    assert outcome.errors == []
    (move,) = sim.controller.history
    assert np.linalg.norm(sim.controller.here().position() - LOC_1.position()) < 0.05
    reference, _, _, _ = run_on_cell(_program("SPEED 50", "MOVE loc_1", "BREAK"), locations={"loc_1": LOC_1})
    assert move.duration_s == pytest.approx(reference.controller.history[0].duration_s, rel=1e-6)
    far = Location(700.0, 0.0, 250.0, *DOWN)
    sim, _, outcome, _ = run_on_cell(_program(*guarded), locations={"loc_1": far})
    assert outcome.errors == [] and sim.controller.history == []


def test_inrange_says_why_a_location_cannot_be_reached():
    """INRANGE(loc) (V+ guide v17 L6876): 0 when reachable, otherwise bits saying why
    (docs/motion.md): joint n's limit 2^(n-1), too close 256, too far 512, a tilted tool
    1024.  LEFTY asks for the other configuration, where J1's limit is in the way."""
    program = _program(
        "r1 = INRANGE(a)", "r2 = INRANGE(TRANS(700, 0, 250, 0, 180, 180))",
        "r3 = INRANGE(TRANS(20, 0, 250, 0, 180, 180))", "r4 = INRANGE(TRANS(-300, -250, 250, 0, 180, 180))",
        "r5 = INRANGE(TRANS(350, 0, 250, 0, 150, 180))", "r6 = INRANGE(#PPOINT(0, 160, 0, 0))",
        "LEFTY", "r7 = INRANGE(TRANS(-100, 400, 250, 0, 180, 180))", "RIGHTY",
        "r8 = INRANGE(TRANS(-100, 400, 250, 0, 180, 180))")
    got = _values_after(program, tuple(f"r{k}" for k in range(1, 9)), locations={"a": LOC_1})
    assert got == [0, 512, 256, 1, 1024, 2, 1, 0]


def test_config_reports_the_arm_configuration():
    """CONFIG(select) (V+ guide v17 L6790): bit 1 set for RIGHTY, clear for LEFTY; 0 the
    robot now, 1 the last destination, 2 the next motion (after LEFTY)."""
    program = _program("MOVE a", "BREAK", "c0 = CONFIG(0)", "LEFTY", "c2 = CONFIG(2)", "MOVE a",
                       "c1 = CONFIG(1)", "BREAK", "c3 = CONFIG(0)")
    assert _values_after(program, ("c0", "c2", "c1", "c3"), locations={"a": LOC_1}) == [1, 0, 0, 0]


def test_speed_function_selectors():
    """SPEED(select) (V+ guide v17 L5397-5402 uses SPEED(2) as the program speed): 1 the
    monitor speed, 2 the permanent program speed, 3 the program speed of the next motion."""
    program = _program("SPEED 40 MONITOR", "SPEED 70 ALWAYS", "SPEED 20",
                       "s1 = SPEED(1)", "s2 = SPEED(2)", "s3 = SPEED(3)", "MOVE a", "s4 = SPEED(3)")
    assert _values_after(program, ("s1", "s2", "s3", "s4"), locations={"a": LOC_1}) == [40, 70, 20, 70]


def test_tool_and_base_functions_return_the_settings():
    """TOOL and BASE as functions (V+ guide v17 L6698-6722, E-V01 L286-295)."""
    program = _program("TOOL TRANS(0, 0, 100)", "BASE ,,300", "SET t = TOOL", "SET b = BASE")
    tool, base = _values_after(program, ("t", "b"))
    assert np.allclose(tool.components(), (0, 0, 100, 0, 0, 0))
    assert np.allclose(base.components(), (0, 0, 300, 0, 0, 0))


# ---------------------------------------------------------------- motion instructions
def test_movet_operates_the_hand_as_the_motion_starts(monkeypatch):
    """MOVET loc, hand (V+ guide v17 L6918-6925): the move and the hand at once; a pneumatic
    hand closes for an opening of 0 and opens for one above 0 (docs/motion.md)."""
    commands = _hand_commands(monkeypatch)
    program = _program("MOVET a, 0", "BREAK", "MOVEST b, 25", "BREAK")
    sim, _, outcome, _ = run_on_cell(program, locations={"a": LOC_1, "b": LOC_1.shifted(0, 60, 0)})
    assert outcome.errors == []
    movet, movest = sim.controller.history
    assert not movet.straight and movest.straight
    (t_close, closed), (t_open, opened) = commands
    assert closed and abs(t_close - movet.start_s) < 0.005
    assert not opened and abs(t_open - movest.start_s) < 0.005


def test_ready_moves_to_the_ready_location_in_the_standard_configuration():
    """READY (V+ guide v17 L6986-6988): a move to the READY location above the workspace,
    whatever configuration the robot was in (the Cobra: arm straight out, quill up)."""
    program = _program("LEFTY", "MOVE a", "BREAK", "READY", "BREAK", "c = CONFIG(0)")
    sim, task, outcome, _ = run_on_cell(program, locations={"a": LOC_1})
    assert outcome.errors == []
    assert np.allclose(sim.controller.to_user_joints(sim.controller.joints()), (0, 0, 0, 0), atol=0.02)
    assert np.linalg.norm(sim.controller.here().position() - (600, 0, 341)) < 0.5
    assert _global(task, "c") == 1  # RIGHTY: the stretched arm


def test_gantry_ready_config_and_inrange():
    """The same keywords on the Cartesian robot: READY at mid-stroke with Z up, no arm
    configuration (CONFIG 0), INRANGE 512 outside its box."""
    program = _program("READY", "BREAK", "c = CONFIG(0)", "r1 = INRANGE(a)",
                       "r2 = INRANGE(TRANS(900, 300, 250, 0, 180, 180))")
    sim, task, outcome, _ = run_on_cell(program, scene=GANTRY, locations={"a": Location(500.0, 500.0, 300.0, *DOWN)})
    assert outcome.errors == []
    assert np.allclose(sim.controller.to_user_joints(sim.controller.joints()), (350, 400, 0, 0), atol=0.02)
    assert [_global(task, n) for n in ("c", "r1", "r2")] == [0, 0, 512]


def test_overlap_refuses_a_wrist_turn_of_more_than_180_degrees():
    """OVERLAP (V+ guide v17 L6957-6960): a program error when a multi-turn axis would turn
    more than 180 degrees to avoid a limit stop; NOOVERLAP (the start-up state here) lets
    MULTIPLE take the long way round.  J4 at 350 deg, the target's nearest turn 380 deg is
    past the +360 limit: MULTIPLE goes back to 20 deg."""
    wrist_350 = (0.0, 60.0, 50.0, 350.0)
    sim, _, _, _ = run_on_cell(_program("BREAK"))
    target = sim.controller.location_of_joints((0.0, 60.0, 50.0, 20.0))

    def run(modifier: str):
        sim, _, outcome, _ = run_on_cell(_program("MOVE #p", "BREAK", modifier, "MOVE a", "BREAK"),
                                         locations={"#p": wrist_350, "a": target})
        return sim.controller.to_user_joints(sim.controller.joints())[3], outcome.errors

    wrist, errors = run("NOOVERLAP")
    assert errors == [] and wrist == pytest.approx(20.0, abs=0.05)
    wrist, (error,) = run("OVERLAP")
    assert (error["code"], error["message"], error["line"]) == (-1021, "*Joint 4 limit stop*", 5)
    assert wrist == pytest.approx(350.0, abs=0.05)


def test_payload_accepts_a_percentage():
    """PAYLOAD (V+ guide v17 L6962): the payload indication, 0-100 % of the maximum payload;
    anything else is *Illegal value* at the program line."""
    sim, _, outcome, _ = run_on_cell(_program("PAYLOAD 40"))
    assert outcome.errors == [] and sim.controller.settings.payload == 40.0
    _, _, outcome, _ = run_on_cell(_program("PAYLOAD 40", "PAYLOAD 140"))
    (error,) = outcome.errors
    assert (error["code"], error["line"]) == (-402, 3)
    # Like ACCEL and DURATION, a robot setting: a task without the robot may not change it.
    other_task = _program("EXECUTE 1 other()") + ".PROGRAM other()\n    PAYLOAD 30\n.END\n"
    sim, _, outcome, _ = run_on_cell(other_task)
    (error,) = outcome.errors
    assert (error["code"], error["program"]) == (-601, "other") and sim.controller.settings.payload == 0.0


def test_brake_from_another_task_stops_the_robot_on_its_path():
    """BRAKE "executed (by any program task)" stops the robot mid-segment (V+ guide v17
    L6455-6461): task 1 brakes the motion task 0 started; task 0's BREAK then returns."""
    text = _program("go = FALSE", "EXECUTE 1 braker()", "SPEED 20", "MOVE b", "go = TRUE", "BREAK",
                    "SIGNAL 1") + ".PROGRAM braker()\n    WAIT go\n    BRAKE\n.END\n"
    far = Location(300.0, 150.0, 250.0, *DOWN)
    sim, _, outcome, rows = run_on_cell(text, locations={"b": far})
    assert outcome.errors == []
    (move,) = sim.controller.history
    assert _times_on(rows, 1) < move.end_s - 0.3
    here = sim.controller.here().position()
    assert np.linalg.norm(here - far.position()) > 50.0
    assert np.linalg.norm(sim.controller.destination().position() - here) < 0.05


# ---------------------------------------------------------------- collisions
def test_driving_the_gantry_into_the_belt_is_a_collision_error_at_the_program_line():
    """A program that drives the gantry's gripper into the outfeed belt: *Collision
    detected* (-1020) at the line the program was on, the robot halted on the belt, and
    the program goes no further (docs/motion.md, "Collisions")."""
    into_belt = Location(500.0, 650.0, 150.0, *DOWN)  # gantry frame: the belt is at x 500, y 430-1050
    program = _program("MOVE a", "MOVE belt", "BREAK", "SIGNAL 1")
    sim, _, outcome, rows = run_on_cell(program, scene=GANTRY, locations={"a": Location(500.0, 500.0, 300.0, *DOWN),
                                                                          "belt": into_belt})
    (error,) = outcome.errors
    assert error["code"] == -1020 and error["message"].startswith("*Collision detected*")
    assert error["line"] == 4 and "belt" in error["message"]
    assert not any(io.get(1) for _, _, _, io, _ in rows)
    assert sim.controller.here().z > into_belt.z + 20
