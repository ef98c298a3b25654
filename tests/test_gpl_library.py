"""The GPL built-in classes, called directly from Python on a real Simulation
(scenes/scara_pick.toml): Location math and frames, Profile, Move, Robot,
Controller, Signal, Console.  Manual references are lines of
/work/shared/seeds/gpl-user-manual.txt (digest §14 numbers the examples)."""

from __future__ import annotations

import socket
import socketserver
import struct
import threading
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from twin.language.gpl.errors import GplError
from twin.language.gpl.library import CLASSES, member
from twin.simulation import Simulation

Location, Profile, Move, Robot, Controller, Signal, RefFrame, Console = (
    CLASSES[n] for n in ("location", "profile", "move", "robot", "controller", "signal", "refframe", "console")
)
GplThread, File, StreamReader, StreamWriter, XmlDoc = (
    CLASSES[n] for n in ("thread", "file", "streamreader", "streamwriter", "xmldoc")
)
IPEndPoint, TcpListener, TcpClient, UdpClient, Modbus = (
    CLASSES[n] for n in ("ipendpoint", "tcplistener", "tcpclient", "udpclient", "modbus")
)


class Thread:
    """A scheduler task running one generator, as a GPL thread would."""

    SLICE = object()

    def __init__(self, generator):
        self.generator = generator
        self.finished = False
        self.gpl_error = None

    @property
    def alive(self) -> bool:
        return not self.finished


class Runtime:
    """What a running GPL project offers the library (library/__init__.py GplRuntime)."""

    def __init__(self, sim: Simulation, sandbox: Path):
        self.sim = sim
        self.robot = sim.controller
        self.io = sim.io
        self.sandbox = sandbox
        self.text: list[str] = []
        self.console = type("ConsoleOut", (), {"write": lambda _, s: self.text.append(s)})()
        self.clock = sim.clock
        self.thread = None

    def current_thread(self):
        return self.thread

    def start_thread(self, procedure, name):
        """`procedure` is a Python generator function body(rt) standing in for a GPL procedure."""
        thread = Thread(None)
        thread.name = name
        thread.generator = self._wrap(thread, procedure)
        self.sim.scheduler.add(thread)
        return thread

    def run(self, *bodies, max_time: float = 30.0):
        """Run each generator function body(rt) as a thread until all end; re-raise the first error."""
        threads = []
        for body in bodies:
            thread = Thread(None)
            thread.generator = self._wrap(thread, body)
            threads.append(thread)
            self.sim.scheduler.add(thread)
        self.sim.run(max_sim_time=self.sim.clock() + max_time)
        for thread in threads:
            if thread.gpl_error is not None:
                raise thread.gpl_error
        return threads

    def _wrap(self, thread, body):
        def generator():
            self.thread = thread
            inner = body(self)
            try:
                wait = next(inner)
                while True:
                    self.thread = None
                    yield wait
                    self.thread = thread
                    wait = inner.send(None)
            except StopIteration:
                pass
            except GplError as err:
                thread.gpl_error = err

        return generator()


@pytest.fixture
def rt(tmp_path):
    return Runtime(Simulation(), tmp_path)


def xyz(rt, *values):
    return Location.XYZValue(rt, *values)


def ready(rt):
    Controller.set_PowerEnabled(rt, True)
    Robot.set_Attached(rt, 1)
    Robot.Home(rt)


def assert_pose(loc, expected, tol=1e-6):
    got = [loc.X, loc.Y, loc.Z, loc.Yaw, loc.Pitch, loc.Roll]
    assert np.allclose(got, expected, atol=tol), got


# ------------------------------------------------------------ Location math
def test_mul_is_the_manuals_worked_example(rt):
    """Manual L1877 (E26): A=(10,25,-40), B=(0,5,0) combine to (10,30,-40); with A turned
    90 deg about Z, (10,25,-40,0,0,90), the same B gives (5,25,-40,0,0,90)."""
    b = xyz(rt, 0, 5, 0)
    assert_pose(xyz(rt, 10, 25, -40).Mul(b), [10, 30, -40, 0, 0, 0])
    assert_pose(xyz(rt, 10, 25, -40, 0, 0, 90).Mul(b), [5, 25, -40, 0, 0, 90])


def test_inverse_unwinds_a_combination(rt):
    """Manual L1879 and L907-909 (E9): the inverse of a pure translation is its negation,
    and A.Inverse.Mul(A.Mul(B)) is B."""
    a = xyz(rt, 10, 25, -40, 30, 60, 90)
    b = xyz(rt, 1, 2, 3, 0, 90, 0)
    assert xyz(rt, 7, 0, 0).Inverse().X == pytest.approx(-7)
    assert_pose(a.Inverse().Mul(a.Mul(b)), [1, 2, 3, 0, 90, 0], tol=1e-9)


def test_clone_is_independent_assignment_is_not(rt):
    """Manual L945-960 (E11): after Clone a change to the original leaves the copy alone."""
    loc1 = xyz(rt, 10, 0, 0)
    loc2 = loc1.Clone()
    alias = loc1
    loc1.X = 20
    assert loc2.X == 10 and alias.X == 20


def test_refframe_basic_frame(rt):
    """Manual L2027-2034 (E27): a location on ref1 with PosWrtRef zero has ref1's pose as
    its total position, and follows the frame when the frame changes (L1996)."""
    loc1 = Location(rt)
    ref1 = RefFrame(rt)
    loc1.RefFrame = ref1
    ref1.Loc.XYZ(10, 20, 30, 0, 180, 20)
    assert_pose(loc1.Pos, [10, 20, 30, 0, 180, 20])
    assert_pose(loc1.PosWrtRef, [0, 0, 0, 0, 0, 0])
    ref1.Loc.XYZInc(5, 0, 0)
    assert loc1.Pos.X == pytest.approx(15)
    assert_pose(ref1.Pos(), [15, 20, 30, 0, 180, 20])


def test_frame_of_a_frame_and_pos_assignment(rt):
    """A frame relative to another frame (L1839); assigning Pos stores frame^-1 * total."""
    outer, inner = RefFrame(rt), RefFrame(rt)
    outer.Loc.XYZ(100, 0, 0, 0, 0, 90)
    inner.Loc.XYZ(10, 0, 0)
    inner.Loc.RefFrame = outer
    loc = Location(rt)
    loc.RefFrame = inner
    assert_pose(loc.Pos, [100, 10, 0, 0, 0, 90])
    loc.Pos = xyz(rt, 100, 20, 5, 0, 0, 90)
    assert_pose(loc.PosWrtRef, [10, 0, 5, 0, 0, 0], tol=1e-9)


def test_frame_loop_is_an_error(rt):
    a, b = RefFrame(rt), RefFrame(rt)
    a.Loc.RefFrame = b
    with pytest.raises(GplError) as err:
        b.Loc.RefFrame = a
    assert err.value.code == -809


def test_pallet_frame_steps_rows_then_columns_and_wraps(rt):
    """Pallet frames (L2048-2072): item (1,1,1) at Loc, rows along Loc's X, columns along
    its Y, PalletNextPos steps the row first and wraps after the last item."""
    pallet = RefFrame(rt)
    pallet.Type = 1
    pallet.Loc.XYZ(100, 200, 0, 0, 0, 90)  # turned: rows run along world +Y
    pallet.set_PalletMaxIndex(1, 3)
    pallet.set_PalletMaxIndex(2, 2)
    pallet.set_PalletPitch(1, 10)
    pallet.set_PalletPitch(2, 20)
    seen = []
    for _ in range(7):
        p = pallet.Pos()
        seen.append((round(p.X, 9), round(p.Y, 9)))
        pallet.PalletNextPos()
    assert seen == [(100, 200), (100, 210), (100, 220), (80, 200), (80, 210), (80, 220), (100, 200)]
    pallet.PalletOrder = 2  # GPL Dictionary: column, row, layer
    pallet.PalletRowColLay(1, 1)
    pallet.PalletNextPos()
    assert (pallet.PalletIndex(1), pallet.PalletIndex(2)) == (1, 2)


def test_cartesian_members_on_angles_location_are_errors(rt):
    loc = Location(rt)
    loc.Type = 1
    loc.Angles(10, 20, 30, 40)
    assert loc.Angle(3) == 30
    for touch in (lambda: loc.X, lambda: loc.Mul(loc), lambda: loc.XYZ(1, 2, 3)):
        with pytest.raises(GplError) as err:
            touch()
        assert err.value.code == -762  # Location not a Cartesian type
    with pytest.raises(GplError):
        xyz(rt, 1, 2, 3).Angle(1)


def test_distance_and_here3(rt):
    """Location.Distance uses the XYZ of the total positions; Here3 builds a frame whose X
    axis points from the origin to the second point and whose XY plane holds the third."""
    assert Location.Distance(rt, xyz(rt, 0, 0, 0), xyz(rt, 3, 4, 12, 0, 90, 0)) == pytest.approx(13)
    frame = Location(rt)
    frame.Here3(xyz(rt, 10, 10, 0), xyz(rt, 10, 20, 0), xyz(rt, 0, 15, 0))
    assert_pose(frame.Mul(xyz(rt, 5, 0, 0)), [10, 15, 0, 0, 0, 90], tol=1e-9)


def test_member_lookup_is_case_insensitive(rt):
    assert member(Location, "xyzvalue") == "XYZValue"
    assert member(Move, "WAITFOREOM") == "WaitForEOM"


# ------------------------------------------------------------ motion
def test_motion_preconditions(rt):
    """Manual L1954-1959: power, homing and attachment are required, in that order."""
    start = xyz(rt, 300, 0, 300, 0, 180, 180)
    expected = []

    def attempt(rt):
        try:
            yield from Move.Loc(rt, start, Profile(rt))
        except GplError as err:
            expected.append(err.code)

    def body(rt):
        yield from attempt(rt)  # power off
        Controller.set_PowerEnabled(rt, True)
        yield from attempt(rt)  # not homed
        Robot.set_Attached(rt, 1)
        yield from attempt(rt)  # attached, still not homed
        Robot.Home(rt)
        Robot.set_Attached(rt, 0)
        yield from attempt(rt)  # homed, detached

    rt.run(body)
    assert expected == [-1046, -1021, -1021, -1009]


def test_only_one_thread_can_attach(rt):
    """Robot.Attached gives one thread exclusive control (L2151)."""
    codes = []

    def first(rt):
        Robot.set_Attached(rt, 1)
        yield from Controller.SleepTick(rt, 50)
        Robot.set_Attached(rt, 0)

    def second(rt):
        try:
            Robot.set_Attached(rt, 1)
        except GplError as err:
            codes.append(err.code)
        assert Robot.Attached(rt) == 0
        yield from Controller.SleepTick(rt, 100)
        Robot.set_Attached(rt, 1)
        codes.append(Robot.Attached(rt))

    rt.run(first, second)
    assert codes == [-1006, 1]


def test_move_loc_reaches_the_location_and_waitforeom_settles(rt):
    pick = xyz(rt, 300, -180, 218, 0, 180, 180)
    fine = Profile(rt)
    fine.InRange = 1
    where = {}

    def body(rt):
        ready(rt)
        yield from Move.Loc(rt, pick, fine)
        yield from Move.WaitForEOM(rt)
        where["loc"] = Robot.Where(rt)
        where["dest"] = Robot.Dest(rt)

    rt.run(body)
    assert Location.Distance(rt, where["loc"], pick) < 0.05
    assert_pose(where["dest"], [300, -180, 218, 0, 180, 180], tol=1e-6)


def _timed_move(rt, profile, target):
    times = {}

    def body(rt):
        ready(rt)
        t0 = Controller.Timer(rt)
        yield from Move.Loc(rt, target, profile)
        yield from Move.WaitForEOM(rt)
        times["t"] = Controller.Timer(rt) - t0

    rt.run(body)
    return times["t"]


def test_profile_speed_and_accel_change_the_motion_time(tmp_path):
    """Profile.Speed and Accel are percentages of nominal (Table 12-4): a slower or gentler
    profile takes longer for the same joint move."""
    target = (350, 150, 250, 0, 180, 180)

    def time_with(**settings):
        rt = Runtime(Simulation(), tmp_path)
        profile = Profile(rt)
        for name, value in settings.items():
            setattr(profile, name, value)
        return _timed_move(rt, profile, xyz(rt, *target))

    fast = time_with()
    assert time_with(Speed=25) > 1.5 * fast
    assert time_with(Accel=10, Decel=10) > 1.5 * fast


def test_approach_clearance_along_tool_and_world_z(rt):
    """ZClearance with ZWorld False backs off along the tool Z (up, for a tool pointing down);
    with ZWorld True it rises along world Z.  Both give the point 30 mm above here."""
    pick = xyz(rt, 300, -180, 218, 0, 180, 180)
    pick.ZClearance = 30
    heights = []

    def body(rt):
        ready(rt)
        for world in (False, True):
            pick.ZWorld = world
            yield from Move.Approach(rt, pick, Profile(rt))
            yield from Move.WaitForEOM(rt)
            heights.append(Robot.Dest(rt).Z)

    rt.run(body)
    assert heights == pytest.approx([248, 248])
    tilted = xyz(rt, 0, 0, 0, 0, 90, 0)
    tilted.ZClearance = 10
    assert np.allclose(tilted.clearance().position(), [-10, 0, 0])


def test_angles_location_one_axis_and_rel(rt):
    """An Angles location moves the axes to its values; OneAxis moves one axis (J3, mm);
    Rel with a Cartesian offset moves in the destination's tool frame."""
    got = {}

    def body(rt):
        ready(rt)
        joints = Location(rt)
        joints.Type = 1
        joints.Angles(-60, 90, 100, 10)
        fine = Profile(rt)
        fine.InRange = 1
        yield from Move.Loc(rt, joints, fine)
        yield from Move.WaitForEOM(rt)
        got["angles"] = Robot.WhereAngles(rt).joint_values()
        yield from Move.OneAxis(rt, 3, -20, True, Profile(rt))
        yield from Move.WaitForEOM(rt)
        got["j3"] = Robot.DestAngles(rt).Angle(3)
        before = Robot.Dest(rt)
        yield from Move.Rel(rt, xyz(rt, 0, 0, 15), Profile(rt))  # tool Z points down
        got["dz"] = Robot.Dest(rt).Z - before.Z

    rt.run(body)
    assert np.allclose(got["angles"], [-60, 90, 100, 10], atol=0.05)
    assert got["j3"] == pytest.approx(80)
    assert got["dz"] == pytest.approx(-15)


def test_kinesol_round_trip(rt):
    cart = xyz(rt, 320, 60, 200, 0, 180, 135)
    cart.Config = 0x02  # GPL_Lefty
    angles = cart.Kinesol()
    assert angles.Type == 1
    back = angles.Kinesol()
    assert Location.Distance(rt, back, cart) < 1e-6
    assert back.Roll == pytest.approx(135)


def test_unreachable_location_is_a_gpl_error(rt):
    def body(rt):
        ready(rt)
        yield from Move.Loc(rt, xyz(rt, 2000, 0, 200, 0, 180, 0), Profile(rt))

    with pytest.raises(GplError) as err:
        rt.run(body)
    assert err.value.code == -1033


def test_tool_offset_applies_to_where_and_moves(rt):
    """Robot.Where = Base * flange * Tool: with a 100 mm tool along the flange Z, moving
    the tool tip to a point puts the flange 100 mm above it (tool pointing down)."""
    got = {}

    def body(rt):
        ready(rt)
        Robot.set_Tool(rt, xyz(rt, 0, 0, 100))
        yield from Move.Loc(rt, xyz(rt, 300, 0, 150, 0, 180, 180), Profile(rt))
        yield from Move.WaitForEOM(rt)
        got["flange"] = rt.robot.destination()
        got["where"] = Robot.Where(rt)

    rt.run(body)
    assert got["flange"].z == pytest.approx(250)
    assert got["where"].Z == pytest.approx(150, abs=0.05)


def test_here_on_a_framed_location_stores_the_pose_relative_to_the_frame(rt):
    """Location.Here sets the total position to the robot's (L1897): on a location with a
    frame, PosWrtRef becomes frame^-1 * Where, so Pos equals Robot.Where."""
    got = {}

    def body(rt):
        ready(rt)
        fine = Profile(rt)
        fine.InRange = 1
        yield from Move.Loc(rt, xyz(rt, 320, 40, 200, 0, 180, 90), fine)
        yield from Move.WaitForEOM(rt)
        frame = RefFrame(rt)
        frame.Loc.XYZ(100, 50, 0, 0, 0, 30)
        loc = Location(rt)
        loc.RefFrame = frame
        loc.Here()
        got["loc"], got["where"] = loc, Robot.Where(rt)
        got["speed"] = Robot.SpeedAngles(rt).joint_values()

    rt.run(body)
    loc, where = got["loc"], got["where"]
    assert Location.Distance(rt, loc.Pos, where) < 1e-9
    expected = frame_inverse_times(rt, loc.RefFrame, where)
    assert_pose(loc.PosWrtRef, expected, tol=1e-6)
    assert np.allclose(got["speed"], 0, atol=1.0)  # settled: joint speeds near zero


def frame_inverse_times(rt, frame, where):
    p = frame.Pos().Inverse().Mul(where)
    return [p.X, p.Y, p.Z, p.Yaw, p.Pitch, p.Roll]


def test_delay_queues_a_pause_and_softestop_stops_the_robot(rt):
    """Move.Delay pauses the motion queue, not the thread (Table 12-5): the call returns
    at once and WaitForEOM waits it out.  A soft E-stop stops the motion short of its
    destination and turns power off, so the next motion raises -1046."""
    got = {}

    def body(rt):
        ready(rt)
        t0 = Controller.Timer(rt)
        yield from Move.Delay(rt, 0.5)
        got["returned"] = Controller.Timer(rt) - t0
        yield from Move.WaitForEOM(rt)
        got["ended"] = Controller.Timer(rt) - t0
        target = xyz(rt, 350, 150, 250, 0, 180, 180)
        yield from Move.Loc(rt, target, Profile(rt))
        yield from Controller.SleepTick(rt, 20)
        Controller.set_SoftEStop(rt, True)
        yield from Move.WaitForEOM(rt)
        got["short"] = Location.Distance(rt, Robot.Where(rt), target)
        try:
            yield from Move.Loc(rt, xyz(rt, 300, 0, 300, 0, 180, 180), Profile(rt))
        except GplError as err:
            got["code"] = err.code

    rt.run(body)
    assert got["returned"] == 0.0
    assert 0.5 <= got["ended"] < 0.5 + 0.017
    assert got["short"] > 50 and got["code"] == -1046


def test_profile_values_are_checked_and_cloned(rt):
    p = Profile(rt)
    assert (p.Speed, p.Accel, p.Decel, p.InRange, p.Straight) == (100, 100, 100, 0, False)
    with pytest.raises(GplError):
        p.Speed = 0
    with pytest.raises(GplError):
        p.AccelRamp = -1
    p.Speed = 40
    q = p.Clone()
    p.Speed = 60
    assert q.Speed == 40


def test_nothing_arguments_raise_null_object(rt):
    def body(rt):
        ready(rt)
        yield from Move.Loc(rt, None, Profile(rt))

    with pytest.raises(GplError) as err:
        rt.run(body)
    assert err.value.code == -782


# ------------------------------------------------------------ controller, signals, console
def test_sleeptick_timer_and_system_speed(rt):
    out = {}

    def body(rt):
        t0 = Controller.Timer(rt)
        yield from Controller.SleepTick(rt, 100)
        out["slept"] = Controller.Timer(rt) - t0

    rt.run(body)
    assert Controller.Tick(rt) == pytest.approx(0.002)
    assert out["slept"] == pytest.approx(0.2, abs=0.016)  # resumed at the next 16 ms cycle
    Controller.set_SystemSpeed(rt, 25)
    assert rt.robot.settings.monitor_speed == 25
    with pytest.raises(GplError):
        Controller.set_SystemSpeed(rt, 150)


def test_show_dialog_answers_the_first_button_headless(rt):
    """Manual L2110-2118 (E29), headless: the dialog's answer is button 1 and both
    messages reach the system message log."""
    button = SimpleNamespace(value=0)  # what the interpreter passes for a ByRef argument
    Controller.SystemMessage(rt, "Sample output to Operator Control Panel")
    Controller.ShowDialog(rt, "Yes,No", "Do you like this pop-up?", button)
    Controller.SystemMessage(rt, "Operator pressed button " + str(button.value))
    assert button.value == 1
    assert "Operator pressed button 1" in "".join(rt.text)


def test_signal_numbers_and_gripper_output(rt):
    """Signal.DIO (L1808): outputs 1-512 read back; inputs 10001-10512 are read-only; the
    gripper follows output 1, so closing it at the nest grasps the part there."""
    Signal.set_DIO(rt, 5, True)
    assert Signal.DIO(rt, 5) is True and rt.io.state[5] is True
    assert Signal.DIO(rt, 10001) is False
    with pytest.raises(GplError) as err:
        Signal.set_DIO(rt, 10001, True)
    assert err.value.code == -1517
    with pytest.raises(GplError):
        Signal.DIO(rt, 9999)
    Signal.set_AIO(rt, 2, 3.5)
    assert Signal.AIO(rt, 2) == 3.5

    pick = xyz(rt, 300, -180, 218, 0, 180, 180)
    pick.ZClearance = 25
    fine = Profile(rt)
    fine.InRange = 1
    fine.Straight = True
    held = {}

    def body(rt):
        ready(rt)
        yield from Move.Approach(rt, pick, Profile(rt))
        yield from Controller.SleepTick(rt, 300)  # the feeder presents a part
        yield from Move.Loc(rt, pick, fine)
        yield from Move.WaitForEOM(rt)
        Signal.set_DIO(rt, 1, True)
        yield from Controller.SleepTick(rt, 80)
        yield from Move.Approach(rt, pick, fine)
        yield from Move.WaitForEOM(rt)
        held["part"] = rt.sim.cell.gripper_holding()

    rt.run(body)
    assert held["part"] is not None


def test_console_write_formats(rt):
    Console.Write(rt, "a = ")
    Console.WriteLine(rt, 3.0)
    Console.WriteLine(rt, 2.34 + 1.01)  # manual L1217: 3.35
    Console.WriteLine(rt, True)
    assert "".join(rt.text) == "a = 3\n3.35\nTrue\n"


# ------------------------------------------------------------ threads
def _counting_threads(rt, locked: bool, threads: int = 3, increments: int = 20) -> float:
    """Manual L3309-3367 (Table 18-2, E43): `total = total + 1` in several threads.  The
    read and the write are separated by a Thread.Sleep(0), where the scheduler may switch."""
    shared_data = {"total": 0}
    lock = SimpleNamespace(value=0)  # the ByRef variable TestAndSet reads and writes

    def worker(rt):
        for _ in range(increments):
            if locked:
                while GplThread.TestAndSet(rt, lock, 1) != 0:  # acquire_sem
                    yield from GplThread.Sleep(rt, 0)
            value = shared_data["total"]
            yield from GplThread.Sleep(rt, 0)
            shared_data["total"] = value + 1
            if locked:
                lock.value = 0  # release_sem

    def main(rt):
        started = [GplThread(rt, worker, "", f"w{i}") for i in range(threads)]
        for t in started:
            t.Start()
        for t in started:
            assert (yield from t.Join(-1)) is True

    rt.run(main)
    return shared_data["total"]


def test_testandset_lock_makes_read_modify_write_safe(rt, tmp_path):
    """Without a lock the interleaving of Table 18-2 loses updates; with the TestAndSet
    lock of E43 the total is exactly threads x increments."""
    assert _counting_threads(rt, locked=True) == 60
    assert _counting_threads(Runtime(Simulation(), tmp_path), locked=False) < 60


def test_sleep_join_events_and_thread_state(rt):
    """Thread.Sleep is in milliseconds of simulated time (L2880); Join times out; events
    wake a waiting thread; ThreadState follows the thread's life."""
    log = {}

    def sleeper(rt):
        t0 = rt.clock()
        yield from GplThread.Sleep(rt, 500)
        log["slept"] = rt.clock() - t0

    def waiter(rt):
        log["polled"] = yield from GplThread.WaitEvent(rt, 0x2, 0)
        log["event"] = yield from GplThread.WaitEvent(rt, 0x2, -1)
        log["timeout"] = yield from GplThread.WaitEvent(rt, 0x2, 50)
        log["me"] = GplThread.CurrentThread(rt) is GplThread.CurrentThread(rt)

    def main(rt):
        s = GplThread(rt, sleeper, "", "sleeper")
        w = GplThread(rt, waiter, "", "waiter")
        log["before"] = s.ThreadState
        s.Start()
        w.Start()
        log["running"] = s.ThreadState
        log["join50"] = yield from s.Join(50)
        w.SendEvent(0x2 | 0x4)
        log["join"] = yield from s.Join(-1)
        log["after"] = s.ThreadState
        yield from w.Join(-1)

    rt.run(main)
    assert 0.5 <= log["slept"] < 0.5 + 0.017
    assert (log["before"], log["running"], log["after"]) == (-1, 2, 0)
    assert (log["join50"], log["join"]) == (False, True)
    assert (log["polled"], log["event"], log["timeout"]) == (0, 2, 0)
    assert log["me"] is True


# ------------------------------------------------------------ files
def test_file_write_read_example(rt):
    """Manual L2835-2853 (E37): ten lines written with StreamWriter come back, in order,
    through Peek / ReadLine."""
    out = StreamWriter(rt, "/ROMDISK/test.txt")
    for ii in range(1, 11):
        out.WriteLine("Line " + str(ii))
    out.Close()
    reader = StreamReader(rt, "/ROMDISK/test.txt")
    lines = []
    while reader.Peek() >= 0:
        lines.append(reader.ReadLine())
    reader.Close()
    assert lines == [f"Line {i}" for i in range(1, 11)]
    assert (rt.sandbox / "ROMDISK" / "test.txt").read_bytes().startswith(b"Line 1\r\nLine 2")
    assert list(File.GetFiles(rt, "/ROMDISK")) == ["test.txt"]
    assert File.Length(rt, "/ROMDISK/test.txt") == 9 * 6 + 7 + 10 * 2


def test_nvram_device_full_and_wrap(rt):
    """Manual L2983-3014 (E40, E41): a 64-byte NVRAM file takes "Record 1".."Record 5" and
    the sixth write raises -323 Device full; with -wrap, after 100 records it holds
    "Record 96".."Record 100"."""
    full_at = None
    out = StreamWriter(rt, "/NVRAM/file2 -size 64")
    for ii in range(1, 11):
        try:
            out.WriteLine("Record " + str(ii))
        except GplError as err:
            assert err.code == -323
            full_at = ii
            break
    out.Close()
    assert full_at == 6
    reader = StreamReader(rt, "/NVRAM/file2")
    assert [reader.ReadLine() for _ in range(5)] == [f"Record {i}" for i in range(1, 6)]
    assert reader.Peek() == -1

    out = StreamWriter(rt, "/NVRAM/file3 -size 64 -wrap")
    for ii in range(1, 101):
        out.WriteLine("Record " + str(ii))
    out.Close()
    reader = StreamReader(rt, "/NVRAM/file3")
    lines = []
    while reader.Peek() >= 0:
        lines.append(reader.ReadLine())
    assert lines == [f"Record {i}" for i in range(96, 101)]


def test_file_paths_stay_in_the_sandbox(rt):
    for bad in ("/etc/passwd", "/flash/../../x", "flash/x", "/flash/.hidden", "/NVRAM/file17"):
        with pytest.raises(GplError):
            StreamWriter(rt, bad)
    with pytest.raises(GplError) as err:
        StreamReader(rt, "/flash/missing.txt")
    assert err.value.code == -3110
    with pytest.raises(GplError) as err:
        StreamWriter(rt, "/dev/com1")
    assert err.value.code == -204
    File.CreateDirectory(rt, "/flash/a/b")
    assert list(File.GetDirectories(rt, "/flash/a")) == ["b"]
    File.DeleteDirectory(rt, "/flash/a/b")
    assert list(File.GetDirectories(rt, "/flash/a")) == []


# ------------------------------------------------------------ XML
def _procedure_control(rt):
    """XmlCreate, manual L3703-3717 (E51)."""
    doc = XmlDoc(rt, "procedureControl")
    root = doc.DocumentElement
    root.AddAttribute("cellId", "TestCell")
    root.AddElement("command", "start")
    elem = root.AddElementNode("procedure")
    elem.AddAttribute("jobId", "090507001")
    elem.AddAttribute("name", "INS")
    elem.AddElement("type", "protocol")
    elem.AddElement("testSet", "INS_#_090507001")
    elem.AddElement("index", "0")
    return doc


def test_xml_create_save_load_and_parse(rt):
    """E51 builds the document, SaveString/LoadString round-trips it, and XmlParse
    (L3638-3669, E49) reads exactly the manual's five values from it."""
    text = SimpleNamespace(value="")
    _procedure_control(rt).SaveString(text)
    doc = XmlDoc.LoadString(rt, text.value)
    assert doc.ErrorCode == 0
    root = doc.DocumentElement
    command = root.GetElementNode("command")
    procedure = root.GetElementNode("procedure")
    got = [root.GetAttribute("cellId"), command.Value, procedure.GetAttribute("jobId"),
           procedure.GetElement("type"), procedure.GetElement("testSet")]
    assert got == ["TestCell", "start", "090507001", "protocol", "INS_#_090507001"]
    assert root.GetElementNode("missing") is None
    with pytest.raises(GplError) as err:
        root.GetElement("missing")
    assert err.value.code == -799


def test_xml_search_tree_and_freed_nodes(rt):
    """XmlSearchTree (L3675-3697, E50) walks FirstChild/NextSibling and finds "type";
    a removed node's handle raises -801 "No XML node" (L3731)."""
    doc = _procedure_control(rt)

    def search(node, name):
        if node.Name == name and node.Type == "element":
            return node
        child = node.FirstChild
        while child is not None:
            found = search(child, name)
            if found is not None:
                return found
            child = child.NextSibling
        return None

    found = search(doc.DocumentElement, "type")
    assert found is not None and found.Value == "protocol"
    assert found.ParentNode is doc.DocumentElement.GetElementNode("procedure")
    found.ParentNode.RemoveChild(found)
    with pytest.raises(GplError) as err:
        found.Value
    assert err.value.code == -801


def test_xml_errors_and_entities(rt):
    """Malformed text does not throw: ErrorCode is -799 (L3727).  Values are taken as
    encoded character data (L3441): EncodeEntities then Value round-trips."""
    bad = XmlDoc.LoadString(rt, "<a><b></a>")
    assert bad.ErrorCode == -799 and bad.DocumentElement is None
    doc = XmlDoc(rt, "r")
    doc.DocumentElement.AddElement("v", XmlDoc.EncodeEntities(rt, 'a<b & "c"'))
    assert doc.DocumentElement.GetElement("v") == 'a<b & "c"'
    assert "a&lt;b &amp;" in doc.text()


# ------------------------------------------------------------ networking
def _free_port(kind=socket.SOCK_STREAM) -> int:
    with socket.socket(socket.AF_INET, kind) as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def test_telnet_echo_server_and_tcp_client(rt):
    """The manual's Telnet server (L2330-2364, E31; repaired: IPEndPoint("", port) and the
    missing AcceptSocket) in one thread, a TcpClient (L2383-2411, E32, its address
    192.168.0.2 replaced by 127.0.0.1: the twin refuses non-loopback peers) in another:
    the client gets each line echoed, the server sees the close as a receive count of 0."""
    port = _free_port()
    replies = []

    def server(rt):
        tl = TcpListener(rt, IPEndPoint(rt, "", port))
        tl.Start()
        while not tl.Pending():
            yield from GplThread.Sleep(rt, 50)
        Console.WriteLine(rt, "Connection request...")
        ts = yield from tl.AcceptSocket()
        tl.Stop()
        recv = SimpleNamespace(value="")
        while True:
            ii = yield from ts.Receive(recv, 1000)
            Console.WriteLine(rt, "Receive count: " + str(ii))
            if ii == 0:
                break
            ts.Send("Received: " + recv.value)
        Console.WriteLine(rt, "Connection closed")
        ts.Close()

    def client(rt):
        yield from GplThread.Sleep(rt, 100)
        tc = TcpClient(rt, IPEndPoint(rt, "127.0.0.1", port))
        sock = tc.Client
        reply = SimpleNamespace(value="")
        for message in ("hello", "world"):
            sock.Send(message)
            yield from sock.Receive(reply, 100)
            replies.append(reply.value)
        tc.Close()

    rt.run(server, client)
    assert replies == ["Received: hello", "Received: world"]
    assert "".join(rt.text) == ("Connection request...\nReceive count: 5\nReceive count: 5\n"
                               "Receive count: 0\nConnection closed\n")


def test_udp_datagrams_and_receive_timeout(rt):
    """UDP (L2415-2422): SendTo / ReceiveFrom with the sender's endpoint; a receive with
    a ReceiveTimeout times out in simulated time."""
    port = _free_port(socket.SOCK_DGRAM)
    got = {}

    def body(rt):
        server = UdpClient(rt, IPEndPoint(rt, "", port))
        client = UdpClient(rt)
        client.Client.SendTo("ping", 0, IPEndPoint(rt, "127.0.0.1", port))
        data, sender = SimpleNamespace(value=""), SimpleNamespace(value=None)
        got["n"] = yield from server.Client.ReceiveFrom(data, 100, sender)
        got["data"] = data.value
        server.Client.SendTo("pong", 0, sender.value)
        got["reply"] = yield from client.Client.ReceiveFrom(data, 100, sender)
        server.Client.ReceiveTimeout = 200
        t0 = rt.clock()
        try:
            yield from server.Client.ReceiveFrom(data, 100, sender)
        except GplError as err:
            got["timeout"] = (err.code, rt.clock() - t0)
        server.Close()
        client.Close()

    rt.run(body)
    assert (got["n"], got["data"], got["reply"]) == (4, "ping", 4)
    assert got["timeout"][0] == -1705 and 0.2 <= got["timeout"][1] < 0.22


class _ModbusSlave(socketserver.ThreadingTCPServer):
    """A small Modbus/TCP slave for the tests: 64 coils, 64 discrete inputs (input n is
    on for odd n), 64 holding registers, 64 input registers (register n holds 100 + n)."""

    allow_reuse_address = True
    daemon_threads = True

    def __init__(self):
        super().__init__(("127.0.0.1", 0), _ModbusHandler)
        self.coils = [False] * 64
        self.inputs = [bool(a % 2 == 0) for a in range(64)]  # address a = input a + 1
        self.holding = [0] * 64
        self.input_registers = [101 + a for a in range(64)]


class _ModbusHandler(socketserver.BaseRequestHandler):
    def handle(self):
        slave = self.server
        while True:
            header = self.request.recv(7)
            if len(header) < 7:
                return
            tid, _, length, unit = struct.unpack(">HHHB", header)
            pdu = self.request.recv(length - 1)
            fc = pdu[0]
            if fc in (1, 2):
                addr, n = struct.unpack(">HH", pdu[1:5])
                bits = (slave.coils if fc == 1 else slave.inputs)[addr: addr + n]
                packed = bytearray((n + 7) // 8)
                for i, on in enumerate(bits):
                    packed[i // 8] |= int(on) << (i % 8)
                answer = bytes([fc, len(packed)]) + packed
            elif fc in (3, 4):
                addr, n = struct.unpack(">HH", pdu[1:5])
                if addr + n > 64:
                    answer = bytes([fc | 0x80, 2])
                else:
                    regs = (slave.holding if fc == 3 else slave.input_registers)[addr: addr + n]
                    answer = bytes([fc, 2 * n]) + struct.pack(f">{n}H", *regs)
            elif fc in (5, 6):
                addr, value = struct.unpack(">HH", pdu[1:5])
                if fc == 5:
                    slave.coils[addr] = value == 0xFF00
                else:
                    slave.holding[addr] = value
                answer = pdu[:5]
            elif fc in (15, 16):
                addr, n, _ = struct.unpack(">HHB", pdu[1:6])
                if fc == 15:
                    for i in range(n):
                        slave.coils[addr + i] = bool(pdu[6 + i // 8] >> (i % 8) & 1)
                else:
                    slave.holding[addr: addr + n] = struct.unpack(f">{n}H", pdu[6: 6 + 2 * n])
                answer = pdu[:5]
            else:
                answer = bytes([fc | 0x80, 1])
            self.request.sendall(struct.pack(">HHHB", tid, 0, len(answer) + 1, unit) + answer)


@pytest.fixture
def modbus_slave():
    slave = _ModbusSlave()
    thread = threading.Thread(target=slave.serve_forever, daemon=True)
    thread.start()
    yield slave
    slave.shutdown()
    slave.server_close()


def test_modbus_write_and_read_examples(rt, modbus_slave):
    """Modbus_Write_Example (L2668-2689, E36): coil ii+1 = (ii And 2), register ii+1 =
    ii*ii, then the multiple-item writes; Modbus_Read_Example (L2641-2662, E35) reads the
    coils and inputs back into unallocated arrays.  Items are 1-based."""
    port = modbus_slave.server_address[1]
    got = {}

    def body(rt):
        mb = Modbus(rt, IPEndPoint(rt, "127.0.0.1", port))
        yield from mb.WriteSingleRegister(1, 600)
        for ii in range(16):
            yield from mb.WriteSingleCoil(ii + 1, ii & 1)
        yield from mb.WriteMultipleCoils(1, [bool(ii & 2) for ii in range(16)])
        yield from mb.WriteMultipleRegisters(1, [ii * ii for ii in range(16)])
        coils, inputs, registers = (SimpleNamespace(value=None) for _ in range(3))
        yield from mb.ReadCoils(1, 16, coils)
        yield from mb.ReadDiscreteInputs(1, 16, inputs)
        yield from mb.ReadInputRegisters(3, 2, registers)
        got["coils"], got["inputs"], got["input_regs"] = (list(r.value) for r in (coils, inputs, registers))
        try:
            yield from mb.ReadHoldingRegisters(60, 10, registers)
        except GplError as err:
            got["exception"] = err.code
        mb.Close()

    rt.run(body)
    assert modbus_slave.holding[:16] == [ii * ii for ii in range(16)]
    assert got["coils"] == [bool(ii & 2) for ii in range(16)]
    assert got["inputs"] == [n % 2 == 1 for n in range(1, 17)]
    assert got["input_regs"] == [103, 104]
    assert got["exception"] == -1730


def test_hardware_members_say_why_they_are_missing(rt):
    """What needs hardware the twin lacks raises -204 with the reason (docs/gpl.md)."""
    for call, reason in ((lambda: Move.Arc(rt, None, None, None), "circular"),
                         (lambda: CLASSES["latch"].ThreadEvent(rt, 2), "latch thread events"),
                         (lambda: Robot.MotorTempStatus(rt, 1), "temperatures")):
        with pytest.raises(GplError) as err:
            call()
        assert err.value.code == -204 and reason in err.value.message


# ------------------------------------------------------------ through the interpreter
def test_refframe_and_clone_examples_as_gpl_source():
    """E27 (L2027-2034, `refl` read as `ref1`) and E11 (L951-960) run as GPL source:
    indexed and chained members, Clone, reference assignment."""
    from gpl_helpers import output_of

    out = output_of("""
Module Test
    Public Sub Main()
        Dim loc1 As New Location            ' loc1 set to Cartesian Loc
        Dim ref1 As New RefFrame
        loc1.RefFrame = ref1                ' loc1 with respect to ref1
        ref1.Loc.XYZ(10,20,30,0,180,20)     ' Set ref1 Pos
        Console.WriteLine(CStr(loc1.Pos.X) & " " & CStr(loc1.Pos.Pitch) & " " & CStr(loc1.Pos.Roll))
        Dim My_Loc1 As New Location
        Dim My_Loc2, alias As Location
        My_Loc1.X = 10
        My_Loc2 = My_Loc1.Clone
        alias = My_Loc1
        My_Loc1.X = 20
        Console.WriteLine(CStr(My_Loc2.X) & " " & CStr(alias.X))
        Dim joints As New Location
        joints.Type = 1
        joints.Angle(2) = 45
        Console.WriteLine(joints.Angle(2))
        Signal.DIO(7) = True
        Console.WriteLine(Signal.DIO(7))
    End Sub
End Module
""")
    assert out == "10 180 20\n10 20\n45\nTrue\n"


def test_show_dialog_and_xml_byref_as_gpl_source(tmp_path):
    """ByRef arguments of built-ins through the interpreter: E29 (L2110-2118, `but-ton`
    rejoined) and XmlCreate (E51, ByRef doc) + SaveString(ByRef s) + XmlParse (E49)."""
    from gpl_helpers import output_of

    out = output_of("""
Module Test
    Public Sub Main()
        Dim button As Integer
        Controller.ShowDialog("Yes,No", "Do you like this pop-up?", button)
        Controller.SystemMessage("Operator pressed button " & CStr(button))
        Dim doc As XmlDoc
        Dim text As String
        XmlCreate(doc)
        doc.SaveString(text)
        doc = XmlDoc.LoadString(text)
        XmlParse(doc)
        doc.SaveFile("/flash/out.xml")
    End Sub

    Public Sub XmlParse(ByVal doc As XmlDoc)
        Dim root As XmlNode
        Dim command As XmlNode
        Dim procedure As XmlNode
        Dim ss As String
        root = doc.DocumentElement
        command = root.GetElementNode("command")
        procedure = root.GetElementNode("procedure")
        ss = root.GetAttribute("cellId")
        Console.Writeline("cellId = " & ss)
        ss = command.Value
        Console.Writeline("command = " & ss)
        ss = procedure.GetAttribute("jobId")
        Console.Writeline("jobId = " & ss)
        ss = procedure.GetElement("type")
        Console.Writeline("type = " & ss)
        ss = procedure.GetElement("testSet")
        Console.Writeline("typeSet = " & ss)
    End Sub

    Public Sub XmlCreate(ByRef doc As XmlDoc)
        Dim root As XmlNode
        Dim elem As XmlNode
        doc = New XmlDoc("procedureControl")
        root = doc.DocumentElement
        root.AddAttribute("cellId", "TestCell")
        root.AddElement("command", "start")
        elem = root.AddElementNode("procedure")
        elem.AddAttribute("jobId", "090507001")
        elem.AddAttribute("name", "INS")
        elem.AddElement("type", "protocol")
        elem.AddElement("testSet", "INS_#_090507001")
        elem.AddElement("index", "0")
    End Sub
End Module
""", sandbox=tmp_path)
    assert out.splitlines() == [
        "[SystemMessage] Do you like this pop-up? [Yes,No] -> 1",
        "[SystemMessage] Operator pressed button 1",
        "cellId = TestCell", "command = start", "jobId = 090507001", "type = protocol",
        "typeSet = INS_#_090507001",
    ]
    assert "<procedureControl cellId=\"TestCell\">" in (tmp_path / "flash" / "out.xml").read_text()


def test_telnet_server_as_gpl_source():
    """E31 (L2330-2364) as GPL source, repaired as digest §14 says, with an E32-style
    client in a second thread started by name; Socket.Receive fills its ByRef String."""
    from gpl_helpers import output_of

    port = _free_port()
    out = output_of(f"""
Module Net
    Public Sub Main()
        Dim client As New Thread("Net.Client")
        client.Start()
        Telnet()
        client.Join(-1)
    End Sub

    Public Sub Telnet
        Dim ep As New IPEndPoint("", {port})
        Dim tl As New TcpListener(ep)
        Dim ts As Socket
        Dim recv As String
        Dim send As String
        Dim ii As Integer
        tl.Start()
        While Not tl.Pending()
            Thread.Sleep(50)
        End While
        Console.Writeline("Connection request...")
        ts = tl.AcceptSocket()
        tl.Stop()
        While True
            ii = ts.Receive(recv, 1000)
            Console.Writeline("Receive count: " & CStr(ii))
            If ii = 0 Then
                Exit While
            End If
            send = "Received: " & recv
            ts.Send(send)
        End While
        Console.Writeline("Connection closed")
        ts.Close()
    End Sub

    Public Sub Client()
        Dim ep As New IPEndPoint("127.0.0.1", {port})
        Dim tc As TcpClient
        Dim sock As Socket
        Dim reply As String
        Thread.Sleep(100)
        tc = New TcpClient(ep)
        sock = tc.Client
        sock.Send("abc")
        sock.Receive(reply, 100)
        Console.WriteLine("Reply: " & reply)
        tc.Close()
    End Sub
End Module
""")
    assert out.splitlines() == ["Connection request...", "Receive count: 3", "Reply: Received: abc",
                                "Receive count: 0", "Connection closed"]


def test_modbus_examples_as_gpl_source(modbus_slave):
    """Modbus_Write_Example (L2668-2689, E36; name joined with underscores, End Sub added)
    then Modbus_Read_Example (L2641-2662, E35; its truncated input loop completed) as GPL
    source, the slave's port added to the endpoints: ByRef fills unallocated arrays."""
    from gpl_helpers import output_of

    port = modbus_slave.server_address[1]
    out = output_of(f"""
Module Mb
    Public Sub Main()
        Modbus_Write_Example()
        Modbus_Read_Example()
    End Sub

    Public Sub Modbus_Read_Example
        Dim ep As New IPEndPoint("127.0.0.1", {port})
        Dim mb As New Modbus(ep)
        Dim ii As Integer
        Dim bool() As Boolean
        mb.ReadCoils(1, 16, bool)
        For ii = 1 To 16
            Console.Write("Coil " & CStr(ii) & ": ")
            Console.Writeline(bool(ii-1))
        Next ii
        mb.ReadDiscreteInputs(1, 16, bool)
        For ii = 1 To 16
            Console.Write("Input " & CStr(ii) & ": ")
            Console.Writeline(bool(ii-1))
        Next ii
        mb.Close
    End Sub

    Public Sub Modbus_Write_Example
        Dim ep As New IPEndPoint("127.0.0.1", {port})
        Dim mb As New Modbus (ep)
        Dim ii As Integer
        Dim output() As Integer
        Dim bool() As Boolean
        For ii = 1 To 16
            mb.WriteSingleCoil(ii, ii And 1)
        Next ii
        mb.WriteSingleRegister(1, 600)
        ReDim bool(15)
        For ii = 0 To 15
            bool(ii) = ii And 2
        Next ii
        mb.WriteMultipleCoils(1, bool)
        ReDim output (15)
        For ii = 0 To 15
            output(ii) = ii*ii
        Next ii
        mb.WriteMultipleRegisters(1, output)
        mb.Close
    End Sub
End Module
""")
    lines = out.splitlines()
    assert lines[:16] == [f"Coil {n}: {bool((n - 1) & 2)}" for n in range(1, 17)]
    assert lines[16:] == [f"Input {n}: {n % 2 == 1}" for n in range(1, 17)]
    assert modbus_slave.holding[:16] == [ii * ii for ii in range(16)]


def _tftp_server(port_box: list, content: bytes, done: threading.Event) -> None:
    """A one-transfer TFTP server (RFC 1350 read request) on loopback: answers from a new
    port (the transfer ID), 512-byte blocks, waits for each ACK."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as listen:
        listen.bind(("127.0.0.1", 0))
        listen.settimeout(20)
        port_box.append(listen.getsockname()[1])
        done.set()
        request, client = listen.recvfrom(1500)
        assert request[:2] == b"\x00\x01" and request[2:].split(b"\x00")[:2] == [b"testfile.txt", b"octet"]
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as transfer:
            transfer.bind(("127.0.0.1", 0))
            transfer.settimeout(20)
            for block in range(1, len(content) // 512 + 2):
                data = content[(block - 1) * 512: block * 512]
                transfer.sendto(struct.pack(">HH", 3, block) + data, client)
                ack, _ = transfer.recvfrom(1500)
                assert ack == struct.pack(">HH", 4, block)


def test_tftp_client_example_as_gpl_source():
    """TftpClient (L2432-2485, E33) as GPL source against a TFTP server on loopback:
    repaired as digest §14 says (`srv_ep`, `rem_ep`, the split Substring, the server's port
    instead of 69, the lost End While).  Chr(0) strings, ByRef endpoint of ReceiveFrom."""
    from gpl_helpers import output_of

    content = bytes((ord("a") + i % 26) for i in range(700))
    port_box: list = []
    ready_event = threading.Event()
    server = threading.Thread(target=_tftp_server, args=(port_box, content, ready_event), daemon=True)
    server.start()
    ready_event.wait(5)
    out = output_of(f"""
Module Tftp
    Public Sub TftpClient
        ' Access a TFTP server using UDP, open a file,
        ' and display it on the console.
        Dim file As String = "testfile.txt"
        Dim srv_ep As New IPEndPoint("127.0.0.1", {port_box[0]})
        Dim rem_ep, ep As IPEndPoint
        Dim out, inp As String
        Dim uc As New UdpClient()
        Dim us As Socket
        Dim count, op, block As Integer
        us = uc.Client
        ' Build "open for read" command
        out = Chr(0) & Chr(1) & file & Chr(0) & "octet" & Chr(0)
        us.SendTo(out, 0, srv_ep)
        count = us.ReceiveFrom(inp, 1500, rem_ep)
        Console.Writeline("Remote ip: " & rem_ep.IPAddress & _
                          ", port: " & CStr(rem_ep.Port))
        op = Asc(inp.Substring(0,1))*256 + Asc(inp.Substring(1,1))
        block = Asc(inp.Substring(2,1))*256 + Asc(inp.Substring(3,1))
        Console.Writeline("Block: " & CStr(Block))
        If (count>4) Then
            Console.Writeline(inp.Substring(4))
        End If
        While True
            out = Chr(0) & Chr(4) & Chr(block/256) & Chr(block)
            us.SendTo(out, 0, rem_ep)
            If (count<512) Then
                ' End if less than 512 bytes
                Exit While
            End If
            count = us.ReceiveFrom(inp, 1500, ep)
            If (ep.IPAddress<>rem_ep.IPAddress) Or _
                (ep.Port<>rem_ep.Port) Then
                Console.Writeline("Address mismatch")
                Exit While
            End If
            block = Asc(inp.Substring(2,1))*256 + _
                    Asc(inp.Substring(3,1))
            Console.Writeline("Block: " & CStr(Block))
            If (count>4) Then
                Console.Writeline(inp.Substring(4))
            End If
        End While
        Console.Writeline("Transfer complete")
        us.Close
    End Sub
End Module
""", start="TftpClient")
    server.join(5)
    lines = out.splitlines()
    assert lines[0].startswith("Remote ip: 127.0.0.1, port: ")
    assert lines[1:] == ["Block: 1", content[:512].decode(), "Block: 2", content[512:].decode(),
                         "Transfer complete"]


def test_nvram_examples_as_gpl_source():
    """E40 (L2983-2990) stops with -323 Device full at ii = 6 on the WriteLine line; E41
    (L2998-3006, `tfile.Clos` read as Close) runs to the end; reading both files back
    gives the manual's records."""
    from gpl_helpers import error_of, output_of

    error = error_of("""
Module Nv
    Public Sub Main()
        Dim tfile As New StreamWriter("/NVRAM/file2 -size 64", True)
        Dim ii As Integer
        For ii = 1 To 100
            tfile.WriteLine("Record " & CStr(ii))
        Next ii
        tfile.Close
    End Sub
End Module
""")
    assert (error.code, error.line) == (-323, 7)
    out = output_of("""
Module Nv
    Public Sub Main()
        Dim tfile As New StreamWriter("/NVRAM/file3 -size 64 -wrap", True)
        Dim ii As Integer
        For ii = 1 To 100
            tfile.WriteLine("Record " & CStr(ii))
        Next ii
        tfile.Close
        Dim rfile As New StreamReader("/NVRAM/file3")
        While rfile.Peek() >= 0
            Console.WriteLine(rfile.ReadLine())
        End While
    End Sub
End Module
""")
    assert out.splitlines() == [f"Record {i}" for i in range(96, 101)]


def test_xml_write_file_example_as_gpl_source(tmp_path):
    """XmlWriteFile (L3530-3548, E47; continuation after `&` restored): a good path writes
    the file; a path into a missing folder prints "Output error <code>, <message>" from
    the document and rethrows, stopping the thread with that code."""
    from gpl_helpers import run_gpl

    system, thread = run_gpl("""
Module X
    Public Sub Main()
        Dim doc As New XmlDoc("root")
        XmlWriteFile("/flash/good.xml", doc)
        XmlWriteFile("/flash/missing/bad.xml", doc)
    End Sub

    Public Sub XmlWriteFile(ByVal file As String, ByVal doc As XmlDoc)
        Dim exc As Exception
        Try
            doc.SaveFile(file)
        Catch exc
            If doc.ErrorCode <> 0 Then
                Console.Writeline("Output error " & _
                                  CStr(doc.ErrorCode) & _
                                  ", " & doc.Message)
            End If
            Throw exc
        End Try
    End Sub
End Module
""", sandbox=tmp_path)
    assert (tmp_path / "flash" / "good.xml").read_text().endswith("<root/>")
    assert system.console.output == "Output error -799, XML error: cannot write /flash/missing/bad.xml: no such folder\n"
    assert thread.error.code == -799


def test_stream_reader_bytes_and_line_ends(rt):
    """StreamReader.Read returns bytes one by one and -1 at the end; ReadLine accepts LF,
    CR and CR LF (Table 15-3); StreamWriter.NewLine changes WriteLine's terminator."""
    out = StreamWriter(rt, "/flash/mixed.txt")
    out.NewLine = "\n"
    out.WriteLine("a")
    out.Write("b\rc\r\n")
    out.Write("d")
    out.Close()
    reader = StreamReader(rt, "/flash/mixed.txt")
    assert [reader.ReadLine() for _ in range(4)] == ["a", "b", "c", "d"]
    assert reader.Read() == -1
    reader = StreamReader(rt, "/flash/mixed.txt")
    assert [reader.Read() for _ in range(3)] == [ord("a"), 10, ord("b")]
    assert reader.Peek() == 13
    out = StreamWriter(rt, "/flash/mixed.txt", True)
    out.Write("e")
    out.Close()
    assert (rt.sandbox / "flash" / "mixed.txt").read_bytes() == b"a\nb\rc\r\nde"
