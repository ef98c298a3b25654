"""Interpreter throughput: simple V+ statements per wall-clock second.

A compute-only program (a loop of assignments and arithmetic) runs on the
interpreter alone, without a cell.  Statements counted: the body's
assignments plus the loop's own step (the FOR ... END line).

    .venv/bin/python bench/interpreter.py [iterations]
"""

from __future__ import annotations

import io
import statistics
import sys
import time

from twin.controller.io import DigitalIO
from twin.controller.scheduler import Scheduler
from twin.language.vplus.runtime import MAJOR_CYCLE, Console, VPlusSystem

PROGRAM = """
.PROGRAM bench(n)
    AUTO i, a, b, c
    a = 0
    b = 1
    FOR i = 1 TO n
        a = a + 1
        b = b * 1.000001
        c = a - b / 2
        a = a MOD 1000
    END
.END
"""
BODY_STATEMENTS = 5  # four assignments and the END of the loop


def run_once(iterations: int) -> float:
    clock = [0.0]
    system = VPlusSystem(None, DigitalIO(), lambda: clock[0], Console(stdin=io.StringIO(), echo=None))
    system.load_text(PROGRAM, "bench.pg")
    task = system.start("bench", args=[float(iterations)])
    scheduler = Scheduler()
    scheduler.add(task)
    start = time.perf_counter()
    while scheduler.alive:
        scheduler.run_cycle()
        clock[0] += MAJOR_CYCLE
    elapsed = time.perf_counter() - start
    assert task.error is None, task.error
    return iterations * BODY_STATEMENTS / elapsed


def main() -> None:
    iterations = int(sys.argv[1]) if len(sys.argv) > 1 else 200_000
    rates = [run_once(iterations) for _ in range(5)]
    print(f"V+ interpreter: {statistics.median(rates):,.0f} statements/s "
          f"(median of 5 runs of {iterations:,} iterations x {BODY_STATEMENTS} statements)")


if __name__ == "__main__":
    main()
