"""Interpreter throughput: simple V+ statements per wall-clock second.

Compute-only programs run on the interpreter alone, without a cell: a FOR
loop of assignments and arithmetic (structured code), and the same loop
written with a label and IF ... GOTO (the jump-table form the compiler uses
for programs with GOTO).  Statements counted: the body's assignments plus the
loop's own step (the FOR's END line; the counter update and the IF ... GOTO).

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

PROGRAMS = {
    "FOR loop": ("""
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
""", 5),  # four assignments and the END of the loop
    "GOTO loop": ("""
.PROGRAM bench(n)
    AUTO i, a, b, c
    a = 0
    b = 1
    i = 1
10  a = a + 1
    b = b * 1.000001
    c = a - b / 2
    a = a MOD 1000
    i = i + 1
    IF i <= n GOTO 10
.END
""", 6),  # five assignments and the IF ... GOTO
}


def run_once(text: str, statements: int, iterations: int) -> float:
    clock = [0.0]
    system = VPlusSystem(None, DigitalIO(), lambda: clock[0], Console(stdin=io.StringIO(), echo=None))
    system.load_text(text, "bench.pg")
    task = system.start("bench", args=[float(iterations)])
    scheduler = Scheduler()
    scheduler.add(task)
    start = time.perf_counter()
    while scheduler.alive:
        scheduler.run_cycle()
        clock[0] += MAJOR_CYCLE
    elapsed = time.perf_counter() - start
    assert task.error is None, task.error
    return iterations * statements / elapsed


def main() -> None:
    iterations = int(sys.argv[1]) if len(sys.argv) > 1 else 200_000
    for name, (text, statements) in PROGRAMS.items():
        rates = [run_once(text, statements, iterations) for _ in range(5)]
        print(f"V+ interpreter, {name}: {statistics.median(rates):,.0f} statements/s "
              f"(median of 5 runs of {iterations:,} iterations x {statements} statements)")


if __name__ == "__main__":
    main()
