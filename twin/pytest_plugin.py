"""pytest plugin (entry point ``pytest11``, loaded whenever twin is installed): the
``twin_run`` fixture runs a program on a cell and returns the run, whose ``expect``
asserts on its report with twin check's expectations and failure sentences::

    def test_three_parts_reach_the_bin(twin_run):
        run = twin_run("examples/pick_three.pg", scene="scenes/scara_pick.toml")
        run.expect("examples/pick_three.expect.toml")            # a file ...
        run.expect({"parts": {"pose": {"id": 3, "position": [300, -180, 860], "tolerance_mm": 2}}})

The report (and the recording with ``rrd=True``) is written into the test's tmp_path; the
run's program, scene, seed and simulated time go into pytest's JUnit XML as properties
(``record_property``).  See docs/ci.md.
"""

from __future__ import annotations

import io
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import pytest

__all__ = ["CellRun", "twin_run"]


@dataclass
class CellRun:
    """A finished run: its report, the report's path and the simulation (for inspection)."""
    report: "object"        # twin.report.Report
    report_path: Path
    simulation: "object"    # twin.simulation.Simulation
    rrd_path: Path | None = None

    def failures(self, expectations: dict | str | Path) -> list[str]:
        """twin check's failure sentences for these expectations (a dict or a TOML file)."""
        from .check import check, load_expect

        expect = expectations if isinstance(expectations, dict) else load_expect(expectations)
        return check(self.report, expect)

    def expect(self, expectations: dict | str | Path) -> None:
        """Assert that every expectation holds; the message lists each one that does not."""
        __tracebackhide__ = True
        failed = self.failures(expectations)
        if failed:
            pytest.fail(f"{len(failed)} expectation(s) failed for {self.report_path}:\n"
                        + "\n".join(f"  - {f}" for f in failed), pytrace=False)


@pytest.fixture
def twin_run(tmp_path: Path, record_property) -> Callable[..., CellRun]:
    """Call with (program, scene=None, *, seed=None, max_sim_time=3600.0, rrd=False, main=None)."""
    from .language.vplus.runtime import Console
    from .runner import run_program

    count = 0

    def run(program: str | Path, scene: str | Path | None = None, *, seed: int | None = None,
            max_sim_time: float = 3600.0, rrd: bool = False, main: str | None = None) -> CellRun:
        nonlocal count
        count += 1
        folder = tmp_path / f"twin-run-{count}"
        report_path = folder / "report.json"
        rrd_path = folder / "run.rrd" if rrd else None
        result = run_program(program, scene=scene, main=main, report_path=report_path, rrd_path=rrd_path,
                             max_sim_time=max_sim_time, seed=seed,
                             console=Console(stdin=io.StringIO(""), echo=None))
        report = result.report
        for key in ("program", "scene", "seed", "sim_time_s"):
            record_property(f"twin_{key}", getattr(report, key))
        return CellRun(report, report_path, result.simulation, rrd_path)

    return run
