"""V+ conveyor tracking (eV+ Language User's Guide, "Conveyor Tracking"; the V+ guide v17
has the same chapter), on the SCARA demo cell with belt encoders driven by simulated
time (tests/belt_helpers.py): the belt runs along the robot's +Y at 100 mm/s.

The chapter's sample programs are run as printed; their locations (belt, window.1,
window.2, p1, p2, wait.location) are taught within the Cobra's reach.
"""

from __future__ import annotations

import numpy as np
import pytest
from belt_helpers import ClockEncoder
from test_motion_controller import SCARA

from twin.controller.location import Location
from twin.language.vplus.runtime import Console, VPlusSystem
from twin.simulation import Simulation

SPEED = 100.0  # mm/s
SCALE = 0.03067  # mm/count: the sample program's belt.scale
NOMINAL = Location(300.0, -250.0, 230.0, 90.0, 0.0, 0.0)  # belt frame: X along the robot's +Y
ON_BELT = Location(0.0, 0.0, 0.0, -90.0, 180.0, 180.0)  # tool down, jaws as in the demo cells
LOCATIONS = {
    "belt": NOMINAL,
    "window.1": Location(300.0, -300.0, 230.0, 0.0, 180.0, 180.0),
    "window.2": Location(300.0, 320.0, 230.0, 0.0, 180.0, 180.0),
    "p1": ON_BELT,
    "p2": Location(250.0, 0.0, 0.0, -90.0, 180.0, 180.0),  # 250 mm further down the belt
    "wait.location": Location(350.0, -150.0, 280.0, 0.0, 180.0, 180.0),
    "loc": ON_BELT,
    "fixed.location": Location(350.0, -150.0, 280.0, 0.0, 180.0, 180.0),
    "location3": ON_BELT,
}

RELOCATE = """.PROGRAM relocate()
; *** PROGRAM TO RELOCATE PART ON CONVEYOR ***
; Set up belt parameters

    ENABLE BELT
    PARAMETER BELT.MODE = 0
    belt.scale = 0.03067          ;Encoder scale factor

; Define belt twice, for two stations

    DEFBELT %b1 = belt, 1, 32, belt.scale
    WINDOW %b1 = window.1, window.2, window.error
    DEFBELT %b2 = belt, 2, 32, belt.scale
    WINDOW %b2 = window.1, window.2, window.error

    WHILE TRUE DO                      ;Loop indefinitely
        WAIT part.ready                ;Wait for signal that part present
        bx = BELT(%b1)                 ;Read present belt position
        SETBELT %b1 = bx                ;Set encoder offset for pick-up...
        SETBELT %b2 = bx                ;... and drop-off stations
        APPROX %b1:p1, 50               ;Move to the part and pick it up
        MOVES %b1:p1
        CLOSEI
        DEPARTS 50
        APPROX %b2:p2, 50               ;Carry part to drop-off location
        MOVES %b2:p2
        OPENI
        DEPARTS 50
        MOVES wait.location             ;Return to rest location
        END                             ;Wait for the next part
; *** End of program ***
.END
"""

WINDOW_ERROR = """.PROGRAM window.error()
; *** WINDOW VIOLATION ROUTINE ***
      TYPE /B, /C1, "*** WINDOW ERROR OCCURRED **", /C1

; Find out which end of window was violated

      IF DISTANCE(HERE,window.1) < DISTANCE(HERE,window.2) THEN

; Error occurred at window.2

      TYPE "Part moved downstream out of reach"

;...(Respond to downstream window error) .

      ELSE                                     ; Error occurred at window.1
      TYPE "Part moved upstream out of reach"
;...(Respond to upstream window error) .
      END

      MOVES wait.location           ;Move robot to rest location

; Use digital output signals to sound alarm and stop belt

      SIGNAL alarm, stop.belt
      HALT                          ;Halt program execution
.END
"""


class _Rows:
    """Recorder hook: (time, measured joints, tracking?) every major cycle."""

    def __init__(self, sim: Simulation):
        self.sim, self.rows = sim, []

    def wants_frame(self, t: float) -> bool:
        return True

    def sample(self, t: float, data) -> None:
        c = self.sim.controller
        self.rows.append((t, c.joints(), c.following_belt))

    def log_scalar(self, *args) -> None:
        """Signals are not needed here."""

    def log_text(self, *args, **kwargs) -> None:
        """Events are not needed here."""


def run_belt(text: str, locations: dict | None = None, reals: dict | None = None, max_time: float = 20.0,
             speed: float = SPEED, latch_times=()):
    sim = Simulation(SCARA)
    encoders = {n: ClockEncoder(sim.cell, n, 1.0 / SCALE, speed, latch_times=latch_times if n == 1 else ())
                for n in (1, 2)}
    sim.cell.encoders = encoders
    probe = _Rows(sim)
    sim.recorder = probe
    sim.controller.settings.monitor_speed = 100.0
    system = VPlusSystem(sim.controller, sim.io, sim.clock, console=Console(echo=None))
    for name, loc in {**LOCATIONS, **(locations or {})}.items():
        system.define_location(name, loc)
    system.globals.update(reals or {})
    name = system.load_text(text, "test.pg")[0]
    task = system.start(name)
    sim.scheduler.add(task)
    outcome = sim.run(max_sim_time=max_time)
    return sim, task, outcome, probe.rows, system


def _belt_target(sim, travel_mm: float, relative: Location = ON_BELT) -> np.ndarray:
    return (NOMINAL * Location(travel_mm, 0, 0, 0, 0, 0) * relative).position()


def _flange(sim, q) -> np.ndarray:
    return sim.kinematics.fk(q)[:3, 3] * 1e3


def _program(*lines: str) -> str:
    return ".PROGRAM t()\n" + "\n".join(f"    {line}" for line in lines) + "\n.END\n"


SETUP = ("ENABLE BELT", "DEFBELT %b = belt, 1, 32, 0.03067", "WINDOW %b = window.1, window.2",
         "SETBELT %b = BELT(%b)")


def test_tracking_error_while_the_robot_follows_a_belt_location_is_below_half_a_millimetre():
    sim, task, outcome, rows, _ = run_belt(_program(*SETUP, "MOVES %b:loc", "DELAY 2.00", "MOVES fixed.location"))
    assert outcome.errors == []
    encoder = sim.cell.encoders[1]
    offset_travel = encoder.travel_mm(0.0)  # SETBELT at t = 0: the belt frame is nominal then
    errors = [np.linalg.norm(_flange(sim, q) - _belt_target(sim, encoder.travel_mm(t) - offset_travel))
              for t, q, following in rows if following]
    assert len(errors) > 100  # two seconds of tracking, sampled every 16 ms
    assert max(errors) < 0.5
    # The tool really moves with the belt: 2 s at 100 mm/s.
    tracked = [q for _, q, following in rows if following]
    assert np.linalg.norm(_flange(sim, tracked[-1]) - _flange(sim, tracked[0])) == pytest.approx(200.0, abs=5.0)


def test_the_relocate_sample_program_picks_at_the_moving_p1_and_places_at_p2_cycle_after_cycle():
    sim, task, outcome, rows, system = run_belt(RELOCATE + WINDOW_ERROR, reals={"part.ready": -1.0},
                                                max_time=12.0)
    assert [e["code"] for e in outcome.errors] == [None]  # only the time limit stops the endless loop
    assert "WINDOW ERROR" not in system.console.output
    # Each cycle re-zeroes both belts; the robot follows p1 while it closes the hand there.
    following = [(t, q) for t, q, f in rows if f]
    assert following
    ys = np.array([_flange(sim, q)[1] for _, q in following])
    xs = np.array([_flange(sim, q)[0] for _, q in following])
    assert np.all(np.abs(xs - 300.0) < 0.5)  # across the belt the tool stays on the parts' line
    cycles = sum(1 for a, b in zip(following, following[1:]) if b[0] - a[0] > 0.1)
    assert cycles >= 4  # picks and places of two or more parts in 12 s
    assert ys.min() > -260.0 and ys.max() < 320.0  # inside the window


def test_a_window_violation_runs_the_windows_error_routine_of_the_sample():
    # window.2 just downstream of p2's station: the drop-off destination leaves the window.
    sim, task, outcome, rows, system = run_belt(
        RELOCATE + WINDOW_ERROR, reals={"part.ready": -1.0, "alarm": 1.0, "stop.belt": 2.0},
        locations={"window.2": Location(300.0, 60.0, 230.0, 0.0, 180.0, 180.0)}, max_time=12.0)
    assert outcome.errors == []  # the routine HALTs the program
    out = system.console.output
    assert "*** WINDOW ERROR OCCURRED **" in out
    assert "Part moved downstream out of reach" in out
    assert sim.io.sig(1) and sim.io.sig(2)  # the alarm and stop.belt outputs
    assert np.linalg.norm(_flange(sim, sim.controller.joints()) - LOCATIONS["wait.location"].position()) < 1.0


def test_without_a_window_routine_a_violation_stops_the_program_with_the_error():
    program = _program(*SETUP, "MOVES %b:loc", "DELAY 10", "BREAK")
    sim, task, outcome, rows, _ = run_belt(program, locations={"window.2": Location(300, -100, 230, 0, 180, 180)})
    (error,) = outcome.errors
    assert error["code"] == -1014 and error["message"].startswith("*Belt window violation*")
    assert error["line"] == 8  # the BREAK the program was waiting in
    # The part reached the downstream limit (y = -100) about 1.5 s after SETBELT.
    assert error["time"] == pytest.approx(1.5, abs=0.1)


def test_a_destination_upstream_of_the_window_is_waited_for():
    # p1 starts 150 mm upstream of window.1: the motion waits 1.5 s for it to come in.
    upstream = Location(-200.0, 0.0, 0.0, -90.0, 180.0, 180.0)
    program = _program(*SETUP, "t0 = TIMER(-3)", "MOVES %b:up", "BREAK", "waited = TIMER(-3)")
    sim, task, outcome, rows, system = run_belt(program, locations={"up": upstream})
    assert outcome.errors == []
    assert system.globals["waited"] > 1.4
    program = _program("PARAMETER BELT.MODE = 2", *SETUP, "MOVES %b:up")  # bit 2: an error instead
    _, _, outcome, _, _ = run_belt(program, locations={"up": upstream})
    assert outcome.errors[0]["code"] == -1014 and "upstream" in outcome.errors[0]["message"]


@pytest.mark.parametrize("motion", ["MOVE %b:loc", "APPRO %b:loc, 50"])
def test_joint_interpolated_motion_relative_to_a_belt_is_an_error(motion):
    _, _, outcome, _, _ = run_belt(_program(*SETUP, motion))
    assert outcome.errors[0]["code"] == -1015 and outcome.errors[0]["line"] == 6


def test_belt_instructions_need_the_belt_switch():
    _, _, outcome, _, _ = run_belt(_program("DEFBELT %b = belt, 1, 32, 0.03067"))
    assert outcome.errors[0]["code"] == -1016 and outcome.errors[0]["line"] == 2


def test_a_belt_variable_must_be_leftmost_and_cannot_be_set():
    _, _, outcome, _, _ = run_belt(_program(*SETUP, "MOVES loc:%b"))
    assert outcome.errors[0]["code"] == -411


def test_belt_window_and_status_functions():
    program = _program(*SETUP, "c0 = BELT(%b)", "DELAY 1.0", "BREAK", "c1 = BELT(%b)", "v = BELT(%b, 1)",
                       "d0 = WINDOW(%b:loc)", "u0 = WINDOW(%b:loc, 0, 1)", "d1 = WINDOW(%b:loc, 1000)",
                       "s = BSTATUS", "MOVES %b:loc", "BREAK", "s1 = BSTATUS")
    sim, task, outcome, rows, system = run_belt(program)
    assert outcome.errors == []
    g = system.globals
    counts_per_s = SPEED / SCALE
    assert g["c1"] - g["c0"] == pytest.approx(counts_per_s * 1.0, rel=0.02)
    assert g["v"] == pytest.approx(counts_per_s * 0.016, rel=0.02)  # counts per 16-ms cycle
    # After 1 s the part is 100 mm down the belt: 570 - 100 = 470 mm from window.2 (y = 320),
    # 50 + 100 = 150 mm past window.1 (y = -300); one more second is 100 mm less room.
    assert g["d0"] == pytest.approx(470.0, abs=2.0)
    assert g["u0"] == pytest.approx(150.0, abs=2.0)
    assert g["d1"] == pytest.approx(370.0, abs=2.0)
    assert g["s"] == 0 and g["s1"] == 1


def test_here_relative_to_a_belt_and_the_latched_encoder_values():
    program = _program(*SETUP, "MOVES %b:loc", "BREAK", "HERE %b:taught", "n = LATCHED(-1)",
                       "first = BELT(%b, 2)", "left = LATCHED(-1)",
                       "SETDEVICE (0, 0, , 0)", "SETDEVICE (0, 0, , 8) 0.03067", "mm = DEVICE(0, 0, , 4)",
                       "x = DX(taught)", "y = DY(taught)")
    sim, task, outcome, rows, system = run_belt(program, latch_times=(0.1, 0.2))
    assert outcome.errors == []
    g = system.globals
    assert (g["n"], g["left"]) == (2.0, 1.0)
    assert g["first"] == pytest.approx(0.1 * SPEED / SCALE, abs=1.0)
    assert g["mm"] == pytest.approx(0.2 * SPEED, abs=0.05)  # the latest latch, in mm
    # The tool is on loc, so the taught location relative to the belt is loc itself.
    assert abs(g["x"]) < 0.5 and abs(g["y"]) < 0.5
