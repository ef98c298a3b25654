"""V+ keywords for hardware or monitor features the twin's cell does not have.

A field program that names them must still load and run as far as the cell allows
(issue #10): each one is in the keyword table, so the program loads, and executing it
stops the program with *Device not ready* naming what is missing (an error REACTE can
trap), as the other absent devices do (docs/vplus.md, "Absent hardware").
"""

from __future__ import annotations

from .. import messages as msg
from ..values import fail
from . import Any, function, instruction

# keyword -> what the cell lacks for it
ABSENT_INSTRUCTIONS = {
    "MCS": "no monitor to run commands ([000] MCS; twin run has no monitor prompt)",
    "INT.EVENT": "no VME interrupts or high-speed inputs",
    "WAIT.START": "no pendant START key",
    "ALTON": "no external path-modification source (ALTON/ALTER)",
    "ALTER": "no external path-modification source (ALTON/ALTER)",
    "ALTOFF": "no external path-modification source (ALTON/ALTER)",
    "AMOVE": "no extra axes",
    "MOVEF": "MOVEF/MOVESF door-to-door motions are not modelled",
    "MOVESF": "MOVEF/MOVESF door-to-door motions are not modelled",
    # Shared memory of other processor boards on the controller's bus, and third-party
    # digital I/O boards: the cell's controller is a single CPU with its own I/O only.
    **{f"IOPUT{kind}": "no bus memory of other processor boards (IOPUT_)" for kind in "BWLFDS"},
    "DEF.DIO": "no third-party digital I/O board (DEF.DIO)",
    "DEVICES": "no device takes block commands (DEVICES)",
}
ABSENT_FUNCTIONS = {
    "TIME": "no calendar clock in the packed TIME() form ($TIME gives the simulated clock)",
    "STATUS": "no monitor STATUS information for programs",
    **{f"IOGET{kind}": "no bus memory of other processor boards (IOGET_)" for kind in "BWLFD"},
    "$IOGETS": "no bus memory of other processor boards ($IOGETS)",
    "IOTAS": "no bus memory of other processor boards (IOTAS)",
    # The arm's own position latch: no latch input is wired to its encoders
    # (LATCHED(robot) is 0), so there is no latched location to return.
    "LATCH": "no latch input on the arm's encoders (LATCH)",
    "#PLATCH": "no latch input on the arm's encoders (#PLATCH)",
}


def _absent(what: str):
    def refuse(rt, *args: Any, unit: Any = None):
        raise fail(msg.DEVICE_NOT_READY, what)

    return refuse


for _name, _what in ABSENT_INSTRUCTIONS.items():
    instruction(_name)(_absent(_what))
for _name, _what in ABSENT_FUNCTIONS.items():
    function(_name)(_absent(_what))
