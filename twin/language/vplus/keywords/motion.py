"""Motion and hand instructions; they drive the shared virtual controller (rt.robot)."""

from __future__ import annotations

from ....controller.location import approach
from . import instruction
from .locations import location_arg


@instruction("MOVE", waits=True)
def _move(rt, loc):
    yield from rt.robot.move(location_arg(loc), straight=False)


@instruction("MOVES", waits=True)
def _moves(rt, loc):
    yield from rt.robot.move(location_arg(loc), straight=True)


@instruction("APPRO", waits=True)
def _appro(rt, loc, distance=None):
    yield from rt.robot.move(approach(location_arg(loc), distance or 0.0), straight=False)


@instruction("APPROS", waits=True)
def _appros(rt, loc, distance=None):
    yield from rt.robot.move(approach(location_arg(loc), distance or 0.0), straight=True)


@instruction("DEPART", waits=True)
def _depart(rt, distance):
    yield from rt.robot.move(approach(rt.robot.destination(), distance), straight=False)


@instruction("DEPARTS", waits=True)
def _departs(rt, distance):
    yield from rt.robot.move(approach(rt.robot.destination(), distance), straight=True)


@instruction("BREAK", waits=True)
def _break(rt):
    yield from rt.robot.wait_stopped()


@instruction("DELAY", waits=True)
def _delay(rt, seconds):
    yield from rt.robot.dwell(float(seconds))


@instruction("RIGHTY")
def _righty(rt):
    rt.robot.request_configuration(righty=True)


@instruction("LEFTY")
def _lefty(rt):
    rt.robot.request_configuration(righty=False)


# Hand: OPEN/CLOSE/RELAX act at the start of the next motion; the I forms wait
# for the robot to stop, act at once and then wait HAND.TIME (V+ guide v17,
# "Hand Control").
@instruction("OPEN")
def _open(rt):
    rt.robot.hand_at_next_motion("open")


@instruction("CLOSE")
def _close(rt):
    rt.robot.hand_at_next_motion("close")


@instruction("RELAX")
def _relax(rt):
    rt.robot.hand_at_next_motion("relax")


def _hand_now(rt, state: str):
    yield from rt.robot.wait_stopped()
    rt.robot.hand(state)
    yield from rt.sleep(rt.hand_time())


@instruction("OPENI", waits=True)
def _openi(rt):
    yield from _hand_now(rt, "open")


@instruction("CLOSEI", waits=True)
def _closei(rt):
    yield from _hand_now(rt, "close")


@instruction("RELAXI", waits=True)
def _relaxi(rt):
    yield from _hand_now(rt, "relax")
