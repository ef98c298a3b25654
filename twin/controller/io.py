"""Digital I/O as the controller numbers it (V+ guide v17, "Digital I/O"):
outputs 1-512, inputs 1001-1512, soft signals 2001-2512 and 3001-3004 (V+ guide
v17 L328-331, L11979-11980: "soft signals (2000-2512 and 3001-3004)").  A negative number
means the signal's off state.  Inputs are written by the cell's sensors.
"""

from __future__ import annotations

from ..errors import ProgramError

ILLEGAL_SIGNAL = -403  # V+ "*Illegal digital signal*"

OUTPUTS = range(1, 513)
INPUTS = range(1001, 1513)
SOFT = range(2001, 2513)
SHARED_SOFT = range(3001, 3005)  # soft signals shared by all processors


class DigitalIO:
    def __init__(self) -> None:
        self.state: dict[int, bool] = {}
        self.changes: list[tuple[int, bool]] = []  # (signal, value) in order, for the recorder
        self.watched: set[int] = set()  # inputs a program has read (the watchdog's progress)

    @staticmethod
    def _check(number: int, writable: bool) -> None:
        if number in OUTPUTS or number in SOFT or number in SHARED_SOFT or (not writable and number in INPUTS):
            return
        raise ProgramError(f"*Illegal digital signal* {number}", ILLEGAL_SIGNAL)

    def signal(self, signed: int) -> None:
        """SIGNAL n turns n on; SIGNAL -n turns it off."""
        number = abs(signed)
        self._check(number, writable=True)
        self.set(number, signed > 0)

    def set(self, number: int, value: bool) -> None:
        if self.state.get(number, False) != value:
            self.state[number] = value
            self.changes.append((number, value))

    def sig(self, signed: int) -> bool:
        """SIG(n) is true when n is on; SIG(-n) when it is off."""
        number = abs(signed)
        self._check(number, writable=False)
        value = self.read(number)
        return value if signed > 0 else not value

    def read(self, number: int) -> bool:
        """A program reads signal `number` (checked by the caller)."""
        self.watched.add(number)
        return self.state.get(number, False)
