"""Where a vision pick run put the parts, against the cell's ground truth: the check the
tests and bench/vision.py apply (every upright plate in its tray cell, in order, within
1 mm and 1 degree; every wrong or upside-down part in the reject bin)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

TOLERANCE_MM = 1.0
TOLERANCE_DEG = 1.0


@dataclass
class VisionOutcome:
    plates: int = 0  # upright plates on the mat at the start
    wrong: int = 0  # wrong type or upside down
    worst_mm: float = 0.0  # the largest distance of a placed plate from its cell centre
    worst_deg: float = 0.0  # the largest yaw error in its cell
    failures: list[str] = field(default_factory=list)


def _yaw_deg(quat) -> float:
    w, x, y, z = quat
    return math.degrees(math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)))


def check_vision_run(result, tray: str = "tray", reject: str = "reject") -> VisionOutcome:
    sim, report = result.simulation, result.report
    layout = [p for c in sim.cell.components if c.section == "scatter" and c.name == "mat" for p in c.layout]
    out = VisionOutcome()
    good = [p for p in layout if p["type"] == "plate" and not p["upside_down"]]
    out.plates, out.wrong = len(good), len(layout) - len(good)
    centres = sim.cell.trays[tray].report()["cell_centres_mm"]
    by_time = [e["part"] for e in report.events if e["kind"] == "release"]
    parts = {p["id"]: p for p in report.parts}
    cell = 0
    for iid in by_time:
        p = parts[iid]
        if p.get("type") == "plate" and p["region"] == tray:
            x, y = p["pose"][:2]
            cx, cy = centres[cell][:2]
            err = math.hypot(x - cx, y - cy)
            yaw = abs((_yaw_deg(p["pose"][3:7]) + 180) % 360 - 180)
            out.worst_mm, out.worst_deg = max(out.worst_mm, err), max(out.worst_deg, yaw)
            if p.get("cell") != cell or err > TOLERANCE_MM or yaw > TOLERANCE_DEG:
                out.failures.append(f"part {iid}: cell {p.get('cell')} (expected {cell}), {err:.2f} mm, {yaw:.2f} deg")
            cell += 1
    if cell != out.plates:
        out.failures.append(f"{cell} plates in the tray, {out.plates} upright plates on the mat")
    rejected = sum(1 for p in report.parts if p["region"] == reject)
    if rejected != out.wrong:
        out.failures.append(f"{rejected} parts in the reject bin, {out.wrong} wrong or upside down")
    return out
