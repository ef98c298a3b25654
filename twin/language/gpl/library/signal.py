"""The global Signal class (User Manual ch. 12, L1802-1822): digital and analog I/O.

GPL signal numbers on the twin (the manual gives none; docs/gpl.md):
  outputs 1-512, inputs 10001-10512, soft signals 20001-20512,
on the same DigitalIO as V+ (V+ outputs 1-512, inputs 1001-1512, soft
2001-2512), so a V+ task and a GPL thread see the same signals.  The gripper's
valve follows one output: on = close, off = open; output 1 unless the scene's
``[gripper]`` table sets ``gpl_signal``.  Writing it acts at once, like
``Signal.DIO(n) = True`` on a real controller driving a solenoid.
Analog channels are plain stored values: the cell has no analog devices.
"""

from __future__ import annotations

from . import codes
from . import gpl_class, shared
from .state import robot_state

GRIPPER_SIGNAL = 1  # default output driving the gripper valve
_RANGES = (  # (first GPL number, last, offset to the DigitalIO number, writable)
    (1, 512, 0, True),
    (10001, 10512, 1001 - 10001, False),
    (20001, 20512, 2001 - 20001, True),
)


def _io_number(number, write: bool) -> int:
    n = int(number)
    for first, last, offset, writable in _RANGES:
        if first <= n <= last:
            if write and not writable:
                raise codes.fail(codes.INVALID_SIGNAL, f"{n} is an input")
            return n + offset
    raise codes.fail(codes.INVALID_SIGNAL, str(number))


def gripper_signal(rt) -> int | None:
    """The output wired to the gripper valve; None in a run without a cell."""
    cell = getattr(rt.robot, "cell", None)
    if cell is None:
        return None
    return int(cell.scene.get("gripper", {}).get("gpl_signal", GRIPPER_SIGNAL))


@gpl_class("Signal")
class Signal:
    """The global Signal class."""

    @shared
    def DIO(rt, number) -> bool:
        return bool(rt.io.read(_io_number(number, write=False)))

    @shared
    def set_DIO(rt, number, value) -> None:
        io_number = _io_number(number, write=True)
        on = bool(value)
        rt.io.set(io_number, on)
        if int(number) == gripper_signal(rt):
            rt.robot.hand("close" if on else "open")

    @shared
    def AIO(rt, channel) -> float:
        return robot_state(rt).analog.get(int(channel), 0.0)

    @shared
    def set_AIO(rt, channel, value) -> None:
        robot_state(rt).analog[int(channel)] = float(value)

