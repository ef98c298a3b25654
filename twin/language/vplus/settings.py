"""System parameters and switches with the manuals' defaults and limits
(V+ guide v17, "System Parameters" and "System Switches"; eV+ guide, same
tables).  Neither ZERO nor a program start resets them; a new VPlusSystem
starts from these values.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class ParameterSpec:
    default: float
    low: float
    high: float


PARAMETERS: dict[str, ParameterSpec] = {
    "BELT.MODE": ParameterSpec(0.0, 0.0, 14.0),
    "HAND.TIME": ParameterSpec(0.05, 0.0, 1e18),  # s; the wait is rounded to 16 ms
    # The guides give 7 (no robot calibrated); the twin's robot comes up
    # calibrated, as after CALIBRATE, so programs that test it may move.
    "NOT.CALIBRATED": ParameterSpec(0.0, 0.0, 7.0),
    "KERMIT.RETRY": ParameterSpec(15.0, 1.0, 1000.0),
    "KERMIT.TIMEOUT": ParameterSpec(8.0, 1.0, 95.0),
    "SCREEN.TIMEOUT": ParameterSpec(0.0, 0.0, 16383.0),
    "TERMINAL": ParameterSpec(4.0, 0.0, 4.0),
    "VTIMEOUT": ParameterSpec(30.0, 0.0, 1e18),  # s a vision wait may take (0: no limit); docs/vision.md
}
PARAMETER_DEFAULTS = {name: spec.default for name, spec in PARAMETERS.items()}

SWITCH_DEFAULTS = {
    "AUTO.POWER.OFF": False,
    "BELT": False,
    "CP": True,
    "DECEL.100": False,
    "DRY.RUN": False,
    "FORCE": False,
    "INTERACTIVE": True,
    "MCP.MESSAGES": False,
    "MCP.NO.POT": False,
    "MCS.MESSAGES": False,
    "MESSAGES": True,
    "MONITORS": False,
    # The guides start with POWER off; the twin's cell starts with high power
    # on, as after ENABLE POWER, so programs run without operator action.
    "POWER": True,
    "ROBOT": True,
    "SCALE.ACCEL": True,
    "SCALE.ACCEL.ROT": True,
    "SET.SPEED": True,
    "TRACE": False,
    "UPPER": True,
}


def in_range(name: str, value: float) -> bool:
    spec = PARAMETERS.get(name)
    return spec is None or spec.low <= value <= spec.high
