"""`twin sweep SCENE PROGRAM --seeds N [--param key=v1,v2,...] [--workers K] [--ray ADDRESS]`:
the same cell and program over seeds and scene parameters, in parallel.

Every combination of the seeds and the parameter values (their Cartesian product) is one
run: the scene with those values set (dotted keys, `physics.scene.apply_overrides`) and
that seed.  Runs go to local processes by default (one per core at most), or to a Ray
cluster with ``--ray ADDRESS`` (Ray's own ``ray.init(address=...)``: ``auto`` or
``host:port`` of a running cluster whose workers have twin installed, ``local`` for a
cluster started in this process).  Each run writes its report into the output folder
(``run0007-seed3.json``); the summary, one row per run with the failures first, is
written as ``summary.json`` and ``summary.csv`` beside them.

A run fails when its program or cell stopped it with an error, when it could not start
(a load error, a scene value the schema refuses), or, with ``--expect``, when one of the
expectations does not hold.
"""

from __future__ import annotations

import csv
import io
import itertools
import json
import multiprocessing
import os
import statistics
import sys
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

if sys.version_info >= (3, 11):
    import tomllib
else:  # Python 3.10
    import tomli as tomllib

__all__ = ["Case", "cases", "parse_param", "run_case", "run_sweep", "summarise", "write_summary"]

CSV_FIELDS = ["run", "status", "seed", "params", "placed", "dropped", "missed", "cycle_time_s", "errors",
              "first_failure", "sim_time_s", "wall_time_s", "report"]


@dataclass(frozen=True)
class Case:
    """One run of a sweep: its number, seed and scene values."""

    run: int
    seed: int
    params: dict[str, object] = field(default_factory=dict)


def parse_param(text: str) -> tuple[str, list[object]]:
    """``key=v1,v2,...`` -> (key, values); each value is read as a TOML value (``100``,
    ``2.5``, ``true``, ``"text"``), a bare word as a string."""
    key, sep, values = text.partition("=")
    key = key.strip()
    if not sep or not key or not values.strip():
        raise ValueError(f"--param {text!r}: expected key=value[,value...]")
    return key, [_value(v.strip()) for v in values.split(",")]


def _value(text: str) -> object:
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text


def cases(seeds: list[int], params: list[tuple[str, list[object]]]) -> list[Case]:
    """Every seed with every combination of the parameter values, numbered from 1."""
    keys = [key for key, _ in params]
    grid = list(itertools.product(*(values for _, values in params)))
    return [Case(n, seed, dict(zip(keys, combo)))
            for n, (seed, combo) in enumerate(itertools.product(seeds, grid), start=1)]


def run_case(program: str | list[str], scene: str | None, case: Case, out_dir: str, main: str | None = None,
             max_sim_time: float = 3600.0, expect: dict | None = None) -> dict:
    """Run one case (in whichever process or Ray worker it lands) and return its summary row."""
    from .errors import ProgramError
    from .language.vplus.runtime import Console
    from .runner import run_program
    from .seeds import failures_of

    report_path = Path(out_dir) / f"run{case.run:04d}-seed{case.seed}.json"
    row = {"run": case.run, "seed": case.seed, "params": case.params, "placed": None, "dropped": None,
           "missed": None, "cycle_time_s": None, "errors": 0, "sim_time_s": None, "wall_time_s": None,
           "report": None}
    try:
        report = run_program(program, scene=scene, main=main, report_path=report_path,
                             max_sim_time=max_sim_time, seed=case.seed, scene_overrides=case.params,
                             console=Console(stdin=io.StringIO(""), echo=None)).report
    except ProgramError as err:  # the run could not start: a load error or a refused scene value
        return {**row, "status": "fail", "errors": 1, "failures": [str(err)]}
    failures = failures_of(report, expect)
    counts = report.counts or {}
    return {**row, "status": "fail" if failures else "pass", "failures": failures,
            "placed": counts.get("placed"), "dropped": counts.get("dropped"), "missed": counts.get("missed"),
            "cycle_time_s": statistics.median(report.cycle_times_s) if report.cycle_times_s else None,
            "errors": len(report.errors), "sim_time_s": report.sim_time_s, "wall_time_s": report.wall_time_s,
            "report": str(report_path)}


def run_sweep(program: str | list[str], scene: str | None, all_cases: list[Case], out_dir: str | Path, *,
              main: str | None = None, max_sim_time: float = 3600.0, expect: dict | None = None,
              workers: int | None = None, ray_address: str | None = None) -> list[dict]:
    """Run every case; rows in case order."""
    out_dir = str(out_dir)
    Path(out_dir).mkdir(parents=True, exist_ok=True)
    args = [(program, scene, case, out_dir, main, max_sim_time, expect) for case in all_cases]
    if ray_address is not None:
        return _on_ray(ray_address, args)
    workers = max(1, min(len(all_cases), workers or os.cpu_count() or 1))
    if workers == 1:
        return [run_case(*a) for a in args]
    # spawn, not fork: a forked MuJoCo / rendering context is not safe to reuse.
    with ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn")) as pool:
        return list(pool.map(run_case, *zip(*args)))


def _on_ray(address: str, args: list[tuple]) -> list[dict]:
    try:
        import ray
    except ImportError:
        from .errors import ProgramError

        raise ProgramError("--ray needs Ray: pip install 'twin[ray]'") from None
    ray.init(address=None if address == "local" else address, log_to_driver=False,
             include_dashboard=False, configure_logging=False)
    try:
        remote = ray.remote(run_case)
        return ray.get([remote.remote(*a) for a in args])
    finally:
        ray.shutdown()


def write_summary(rows: list[dict], out_dir: str | Path) -> tuple[Path, Path]:
    """summary.json and summary.csv in `out_dir`, failed runs first, then by run number."""
    ordered = sorted(rows, key=lambda r: (r["status"] != "fail", r["run"]))
    out_dir = Path(out_dir)
    json_path, csv_path = out_dir / "summary.json", out_dir / "summary.csv"
    passed = sum(r["status"] == "pass" for r in rows)
    json_path.write_text(json.dumps({"runs": len(rows), "passed": passed, "failed": len(rows) - passed,
                                     "rows": ordered}, indent=2) + "\n")
    with csv_path.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=CSV_FIELDS, extrasaction="ignore")
        writer.writeheader()
        for r in ordered:
            writer.writerow({**r, "params": ";".join(f"{k}={v}" for k, v in r["params"].items()),
                             "first_failure": (r["failures"] or [""])[0]})
    return json_path, csv_path


def summarise(rows: list[dict]) -> str:
    """'twin sweep: 12 runs: 11 passed, 1 failed' and a line per failed run."""
    failed = [r for r in rows if r["status"] == "fail"]
    lines = [f"twin sweep: {len(rows)} runs: {len(rows) - len(failed)} passed, {len(failed)} failed"]
    for r in sorted(failed, key=lambda r: r["run"]):
        params = "".join(f" {k}={v}" for k, v in r["params"].items())
        lines.append(f"  run {r['run']} seed {r['seed']}{params}: {'; '.join(r['failures'][:2])}")
    return "\n".join(lines)
