"""Belt tracking in the servo loop: the moving targets the robot follows.

A motion to or from a belt-relative location (V+ ``MOVES %belt:loc``, a GPL Location
on a conveyor RefFrame) is planned like any straight-line motion, between where its
two ends are when it is planned.  Every servo step the belts' travel since then is
added back, in Cartesian space, weighted by how far along the line the planned
motion is (sigma, 0 at the start, 1 at the end):

    p(t) = p_planned(t) + (1 - sigma) * dA(t) + sigma * dB(t)

dA, dB: how far the start and the end have moved with their belts (zero for a fixed
location).  The motion thus leaves its start riding with the start's belt and arrives
on the end's belt at the belt's speed, and the tool keeps tracking the end location
afterwards (`Tracking`) until a motion takes it off the belt.  The joints come from
the inverse kinematics of the moved pose, the velocity feed-forward from the
Jacobian.  `lead_s` lets the reference run ahead of the encoder reading (the controller
uses none: see BELT_LEAD_STEPS).
"""

from __future__ import annotations

import numpy as np

from .belt import BeltLocation
from .kinematics import RobotKinematics
from .location import Location

MM = 1000.0
SHORT_LINE_M = 1e-4  # a motion shorter than this (a pure turn) spreads sigma over time instead


class _BeltEnd:
    """One end of a motion that rides on a belt: its belt travel when planned, and the
    travel direction in the robot base frame."""

    def __init__(self, where: BeltLocation, base: Location):
        self.where = where
        self.travel0 = where.belt.travel()
        self.direction = base.rotation() @ where.belt.direction()

    def shift(self, lead_s: float) -> tuple[np.ndarray, np.ndarray]:
        """Displacement since planning and velocity, metres and m/s, base frame."""
        belt = self.where.belt
        speed = belt.speed()
        moved = belt.travel() + speed * lead_s - self.travel0
        return self.direction * (moved / MM), self.direction * (speed / MM)


class BeltPath:
    """The belt correction of one planned straight-line motion (see the module doc)."""

    def __init__(self, kin: RobotKinematics, q: np.ndarray, dt: float, base: Location,
                 start: BeltLocation | None, end: BeltLocation | None):
        self.kin = kin
        self.start = None if start is None else _BeltEnd(start, base)
        self.end_belt = None if end is None else _BeltEnd(end, base)
        self.end = end  # what the tool tracks when the motion is over (None: a fixed location)
        p = kin.fk_positions(q)
        line = p[-1] - p[0]
        length2 = float(line @ line)
        if length2 > SHORT_LINE_M ** 2:
            sigma = np.clip((p - p[0]) @ line / length2, 0.0, 1.0)
        else:
            sigma = np.linspace(0.0, 1.0, len(p))
        self.sigma = sigma
        self.sigma_rate = np.gradient(sigma, dt) if len(sigma) > 1 else np.zeros(1)
        # The planned motion starts and ends at rest: so does sigma (a one-sided difference
        # at the last sample would leave a speed in the servos' velocity reference).
        self.sigma_rate[0] = self.sigma_rate[-1] = 0.0

    def reference(self, k: int, q: np.ndarray, qd: np.ndarray, q_seed: np.ndarray,
                  lead_s: float) -> tuple[np.ndarray, np.ndarray]:
        """The planned joints q, qd at sample k moved with the belts."""
        s, s_rate = self.sigma[k], self.sigma_rate[k]
        shift, velocity = np.zeros(3), np.zeros(3)
        d_start, d_end = np.zeros(3), np.zeros(3)
        if self.start is not None:
            d_start, v_start = self.start.shift(lead_s)
            shift += (1.0 - s) * d_start
            velocity += (1.0 - s) * v_start
        if self.end_belt is not None:
            d_end, v_end = self.end_belt.shift(lead_s)
            shift += s * d_end
            velocity += s * v_end
        velocity += s_rate * (d_end - d_start)
        if not shift.any() and not velocity.any():
            return q, qd
        T = self.kin.fk(q).copy()
        T[:3, 3] += shift
        q_moved = self.kin.ik(T, q_seed, continuous=True)
        return q_moved, qd + self.kin.translation_rates(q_moved, velocity)


class Tracking:
    """The tool following a belt location once a motion has brought it there."""

    def __init__(self, kin: RobotKinematics, where: BeltLocation, flange_m: np.ndarray, base: Location):
        self.kin = kin
        self.where = where
        self.end = _BeltEnd(where, base)
        self.flange0 = np.array(flange_m, dtype=float)  # the flange pose at travel0 (base frame, m)

    def reference(self, q_seed: np.ndarray, lead_s: float) -> tuple[np.ndarray, np.ndarray]:
        shift, velocity = self.end.shift(lead_s)
        T = self.flange0.copy()
        T[:3, 3] += shift
        q = self.kin.ik(T, q_seed, continuous=True)
        return q, self.kin.translation_rates(q, velocity)
