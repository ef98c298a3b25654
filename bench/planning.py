"""Planning time per motion on the Cobra s600: MOVE (IK + joint-space toppra) and MOVES
(straight line: waypoints by IK, spline, toppra with a TCP speed limit), ~50 random moves
each, plus the cost of sampling a planned move at a 2 ms physics step; then the same two
on the Cartesian gantry (damped least-squares IK).  With --grid-error, instead: how much
longer than on a fine toppra grid the motions come out on the planner's grid (the figure
that chose `N_GRID_JOINT`, `REFINE_CELLS` and `N_GRID_STRAIGHT`).  Not a test.

    .venv/bin/python bench/planning.py [--moves 50] [--seed 0] [--grid-error]
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import numpy as np

from twin.controller.kinematics import KinematicsError, RobotKinematics
from twin.controller import trajectory
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
    print(f"{name:<22}{len(ms):>4}{statistics.median(ms):>10.2f}{percentile(ms, 95):>10.2f}{ms[-1]:>10.2f}  {extra}")


def measure(moves: int = 50, seed: int = 0) -> dict[str, list[float]]:
    """Planning times in seconds of `moves` random, non-repeating MOVEs (IK + toppra) and
    MOVESs on the Cobra, the demo's 305 mm straight leg, and sampling a MOVE at 2 ms;
    plus the motions' durations."""
    kin = RobotKinematics.from_mjcf(ROBOT)
    vmax, amax = kin.max_velocity, kin.max_acceleration
    rng = np.random.default_rng(seed)

    # warm up imports and caches
    q = _random_q(kin, rng)
    plan_joint_move(q, _random_q(kin, rng), vmax, amax)

    out: dict[str, list[float]] = {k: [] for k in ("move", "moves", "leg", "sample", "move_s", "moves_s")}
    rejected = 0
    while len(out["move"]) < moves:
        q0, q1 = _random_q(kin, rng), _random_q(kin, rng)
        T1 = kin.fk(q1)
        t0 = time.perf_counter()
        qt = kin.ik(T1, q0, righty=True)
        traj = plan_joint_move(q0, qt, vmax, amax)
        out["move"].append(time.perf_counter() - t0)
        out["move_s"].append(traj.duration)
        t0 = time.perf_counter()
        traj.sample(0.002)
        out["sample"].append(time.perf_counter() - t0)
    while len(out["moves"]) < moves:
        q0, q1 = _random_q(kin, rng), _random_q(kin, rng)
        T1 = kin.fk(q1)
        t0 = time.perf_counter()
        try:
            traj = plan_straight_move(kin, q0, T1, vmax, amax, 1.0)
        except KinematicsError:
            rejected += 1  # line leaves the workspace / a joint range: not timed
            continue
        out["moves"].append(time.perf_counter() - t0)
        out["moves_s"].append(traj.duration)
    out["rejected"] = [rejected]
    # the demo's 25 / 305 / 25 mm cycle leg, straight
    q_a = kin.ik(np.array([[1, 0, 0, 0.35], [0, -1, 0, -0.15], [0, 0, -1, 0.2], [0, 0, 0, 1.0]]),
                 np.array([0, 1, 0, 0]), righty=True)
    T_b = kin.fk(q_a)
    T_b[1, 3] += 0.305
    for _ in range(20):
        t0 = time.perf_counter()
        plan_straight_move(kin, q_a, T_b, vmax, amax, 1.0)
        out["leg"].append(time.perf_counter() - t0)
    return out


def percentile(values: list[float], p: float) -> float:
    ordered = sorted(values)
    return ordered[round(p / 100 * (len(ordered) - 1))]


def grid_error(moves: int = 200, seed: int = 0, fine: int = 400) -> dict[str, np.ndarray]:
    """Relative duration error (planner's grid / `fine`-point grid - 1) of `moves` random
    Cobra MOVEs and MOVESs."""
    kin = RobotKinematics.from_mjcf(ROBOT)
    vmax, amax = kin.max_velocity, kin.max_acceleration
    rng = np.random.default_rng(seed)
    joint, straight = [], []
    while len(joint) < moves:
        q0, q1 = _random_q(kin, rng), _random_q(kin, rng)
        joint.append((q0, kin.ik(kin.fk(q1), q0, righty=True)))
    while len(straight) < moves:
        q0, T1 = _random_q(kin, rng), kin.fk(_random_q(kin, rng))
        try:
            plan_straight_move(kin, q0, T1, vmax, amax, 1.0)
        except KinematicsError:
            continue
        straight.append((q0, T1))

    def durations() -> tuple[np.ndarray, np.ndarray]:
        return (np.array([plan_joint_move(q0, q1, vmax, amax).duration for q0, q1 in joint]),
                np.array([plan_straight_move(kin, q0, T1, vmax, amax, 1.0).duration for q0, T1 in straight]))

    chosen = durations()
    saved = trajectory.N_GRID_JOINT, trajectory.N_GRID_STRAIGHT
    trajectory.N_GRID_JOINT = trajectory.N_GRID_STRAIGHT = fine
    try:
        reference = durations()
    finally:
        trajectory.N_GRID_JOINT, trajectory.N_GRID_STRAIGHT = saved
    return {"MOVE": chosen[0] / reference[0] - 1, "MOVES": chosen[1] / reference[1] - 1}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--moves", type=int, default=50)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--grid-error", action="store_true", help="duration error of the grid against a 400-point one")
    args = ap.parse_args()
    if args.grid_error:
        for kind, err in grid_error(max(args.moves, 200), args.seed).items():
            print(f"{kind:<6} duration vs a 400-point grid: mean {np.mean(err):+.3%}, max {np.max(err):+.3%}, "
                  f"min {np.min(err):+.3%} ({len(err)} motions)")
        return
    m = measure(args.moves, args.seed)
    print(f"{'planning (ms)':<22}{'n':>4}{'median':>10}{'p95':>10}{'max':>10}")
    _row("MOVE (IK + toppra)", m["move"], f"motion median {statistics.median(m['move_s']):.3f} s")
    _row("MOVES (straight line)", m["moves"],
         f"motion median {statistics.median(m['moves_s']):.3f} s; {m['rejected'][0]} random lines rejected")
    _row("MOVES 305 mm leg", m["leg"])
    _row("sample(0.002) of MOVE", m["sample"])
    _gantry(args.moves, np.random.default_rng(args.seed + 1))


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
