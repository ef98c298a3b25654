"""`twin run ... --seeds N`: the same cell and program with N feeder seeds, in parallel
processes, and a summary of which seeds failed and why.

Each run is a separate process (MuJoCo and the interpreters are single-threaded; a process
per core is the only way to use the others), with its TYPE output captured rather than
interleaved on the terminal.  A run fails when its program stopped on an error or, with
expectations, when one of them does not hold.
"""

from __future__ import annotations

import io
import multiprocessing
import os
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

__all__ = ["SeedOutcome", "failures_of", "run_seeds", "seed_report_path"]


@dataclass
class SeedOutcome:
    seed: int
    failures: list[str]          # empty when the run passed
    sim_time_s: float
    report_path: str | None


def seed_report_path(report: str | Path | None, seed: int) -> Path | None:
    """out/report.json -> out/report-seed3.json (None stays None)."""
    if report is None:
        return None
    report = Path(report)
    return report.with_name(f"{report.stem}-seed{seed}{report.suffix or '.json'}")


def _one(program: str | list[str], scene: str | None, main: str | None, seed: int, max_sim_time: float,
         report: str | None, expect: dict | None) -> SeedOutcome:
    from .errors import ProgramError
    from .language.vplus.runtime import Console
    from .runner import run_program

    path = seed_report_path(report, seed)
    try:
        result = run_program(program, scene=scene, main=main, report_path=path, max_sim_time=max_sim_time,
                             seed=seed, console=Console(stdin=io.StringIO(""), echo=None))
    except ProgramError as err:
        return SeedOutcome(seed, [str(err)], 0.0, None)
    rep = result.report
    return SeedOutcome(seed, failures_of(rep, expect), rep.sim_time_s, str(path) if path else None)


def failures_of(report, expect: dict | None) -> list[str]:
    """Why a run failed (empty when it passed): the expectations that do not hold, or
    without expectations the errors that stopped it."""
    from .check import evaluate
    from .errors import ProgramError

    if expect is not None:
        return [o.failure for o in evaluate(report, expect) if o.failure is not None]
    return [str(ProgramError.from_dict(e)) for e in report.errors]


def run_seeds(program: str | list[str], seeds: list[int], *, scene: str | None = None, main: str | None = None,
              max_sim_time: float = 3600.0, report: str | None = None, expect: dict | None = None,
              workers: int | None = None) -> list[SeedOutcome]:
    """Run every seed (in parallel, one process per CPU core at most); outcomes in seed order."""
    workers = max(1, min(len(seeds), workers or os.cpu_count() or 1))
    args = [(program, scene, main, seed, max_sim_time, report, expect) for seed in seeds]
    if workers == 1:
        return [_one(*a) for a in args]
    # spawn, not fork: a forked MuJoCo / rendering context is not safe to reuse.
    with ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn")) as pool:
        return list(pool.map(_one, *zip(*args)))


def summarise(outcomes: list[SeedOutcome]) -> str:
    """'seeds 0-4: 4 passed, 1 failed' and one line per failed seed."""
    failed = [o for o in outcomes if o.failures]
    lines = [f"twin: {len(outcomes)} seeds: {len(outcomes) - len(failed)} passed, {len(failed)} failed"]
    for o in failed:
        lines.append(f"  seed {o.seed}: " + "; ".join(o.failures[:3])
                     + (f" (and {len(o.failures) - 3} more)" if len(o.failures) > 3 else "")
                     + (f" [{o.report_path}]" if o.report_path else ""))
    return "\n".join(lines)
