"""Planning time per motion on the Cobra s600: MOVE (IK + joint-space toppra) and MOVES
(straight line: waypoints by IK, spline, toppra with a TCP speed limit), ~50 random moves
each, plus the cost of sampling a planned move at a 2 ms physics step; then the same two
on the Cartesian gantry (damped least-squares IK).  Not a test.

    .venv/bin/python bench/planning.py [--moves 50] [--seed 0]
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import numpy as np

from twin.controller.kinematics import KinematicsError, RobotKinematics
from twin.controller.trajectory import plan_joint_move, plan_straight_move

ROBOT = Path(__file__).resolve().parents[1] / "models" / "robots" / "cobra_s600.xml"
GANTRY = ROBOT.with_name("cartesian_gantry.xml")


def _random_q(kin, rng):
    q = rng.uniform(kin.lower * 0.85, kin.upper * 0.85)
    q[1] = np.sign(q[1] or 1.0) * max(abs(q[1]), 0.4)
    q[1] = abs(q[1])  # RIGHTY, as the demo cell
    q[3] = rng.uniform(-3.0, 3.0)
    return q


def _row(name, times_s, extra=""):
    ms = sorted(t * 1e3 for t in times_s)
    p90 = ms[int(0.9 * (len(ms) - 1))]
    print(f"{name:<22}{len(ms):>4}{statistics.median(ms):>10.2f}{p90:>10.2f}{ms[-1]:>10.2f}  {extra}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--moves", type=int, default=50)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    kin = RobotKinematics.from_mjcf(ROBOT)
    vmax, amax = kin.max_velocity, kin.max_acceleration
    rng = np.random.default_rng(args.seed)

    # warm up imports and caches
    q = _random_q(kin, rng)
    plan_joint_move(q, _random_q(kin, rng), vmax, amax)

    move_t, moves_t, sample_t, durations, durations_s, rejected = [], [], [], [], [], 0
    while len(move_t) < args.moves:
        q0, q1 = _random_q(kin, rng), _random_q(kin, rng)
        T1 = kin.fk(q1)
        t0 = time.perf_counter()
        qt = kin.ik(T1, q0, righty=True)
        traj = plan_joint_move(q0, qt, vmax, amax)
        move_t.append(time.perf_counter() - t0)
        durations.append(traj.duration)
        t0 = time.perf_counter()
        traj.sample(0.002)
        sample_t.append(time.perf_counter() - t0)
    while len(moves_t) < args.moves:
        q0, q1 = _random_q(kin, rng), _random_q(kin, rng)
        T1 = kin.fk(q1)
        t0 = time.perf_counter()
        try:
            traj = plan_straight_move(kin, q0, T1, vmax, amax, 1.0)
        except KinematicsError:
            rejected += 1  # line leaves the workspace / a joint range: not timed
            continue
        moves_t.append(time.perf_counter() - t0)
        durations_s.append(traj.duration)
    # the demo's 25 / 305 / 25 mm cycle leg, straight
    q_a = kin.ik(np.array([[1, 0, 0, 0.35], [0, -1, 0, -0.15], [0, 0, -1, 0.2], [0, 0, 0, 1.0]]),
                 np.array([0, 1, 0, 0]), righty=True)
    T_b = kin.fk(q_a)
    T_b[1, 3] += 0.305
    leg = [time.perf_counter()]
    for _ in range(20):
        plan_straight_move(kin, q_a, T_b, vmax, amax, 1.0)
        leg.append(time.perf_counter())

    print(f"{'planning (ms)':<22}{'n':>4}{'median':>10}{'p90':>10}{'max':>10}")
    _row("MOVE (IK + toppra)", move_t, f"motion median {statistics.median(durations):.3f} s")
    _row("MOVES (straight line)", moves_t,
         f"motion median {statistics.median(durations_s):.3f} s; {rejected} random lines rejected")
    _row("MOVES 305 mm leg", np.diff(leg).tolist())
    _row("sample(0.002) of MOVE", sample_t)
    _gantry(args.moves, rng)


def _gantry(moves: int, rng) -> None:
    kin = RobotKinematics.from_mjcf(GANTRY)
    vmax, amax = kin.max_velocity, kin.max_acceleration
    move_t, moves_t = [], []
    for _ in range(moves):
        q0, q1 = rng.uniform(kin.lower, kin.upper), rng.uniform(kin.lower, kin.upper)
        q1[3] = q0[3] + rng.uniform(-2.0, 2.0)  # within the wrist range of the start
        q1[3] = min(max(q1[3], kin.lower[3]), kin.upper[3])
        T1 = kin.fk(q1)
        t0 = time.perf_counter()
        plan_joint_move(q0, kin.ik(T1, q0), vmax, amax)
        move_t.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        plan_straight_move(kin, q0, T1, vmax, amax, 1.0)
        moves_t.append(time.perf_counter() - t0)
    _row("gantry MOVE", move_t)
    _row("gantry MOVES", moves_t)


if __name__ == "__main__":
    main()
