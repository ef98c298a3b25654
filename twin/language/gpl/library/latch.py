"""The Latch class (User Manual ch. 12, L2189-2215): positions captured by
latching digital inputs.  The twin's cells have no latch inputs configured (no
photo-eye wired to latch the robot or a belt encoder), so every member raises
-3103 with that reason instead of pretending an always-empty queue."""

from __future__ import annotations

from . import codes, gpl_class

NO_LATCH = "the cell has no latch inputs"


@gpl_class("Latch")
class Latch:
    Count = codes.unsupported("Latch.Count", NO_LATCH)
    Flush = codes.unsupported("Latch.Flush", NO_LATCH)
    Result = codes.unsupported("Latch.Result", NO_LATCH)
    ThreadEvent = codes.unsupported("Latch.ThreadEvent", NO_LATCH)
