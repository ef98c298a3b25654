"""Interpreter throughput: simple GPL statements per wall-clock second.

A compute-only procedure (a loop of assignments, arithmetic, an array element,
a field of a user object and a procedure call) runs on the interpreter alone,
without a cell.  Statements counted: the body's statements plus the loop's own
step (the Next line).  The V+ figure (bench/interpreter.py) is the reference.

    .venv/bin/python bench/gpl_interpreter.py [iterations]
"""

from __future__ import annotations

import io
import statistics
import sys
import time

from twin.controller.io import DigitalIO
from twin.controller.scheduler import Scheduler
from twin.language.gpl.runtime import GplSystem
from twin.language.vplus.runtime import MAJOR_CYCLE, Console

PROJECT = """
Class Counter
    Public value As Integer
End Class
Module Bench
    Public n As Integer = ITERATIONS
    Function Half(ByVal x As Double) As Double
        Return x / 2
    End Function
    Public Sub Main()
        Dim i, a As Integer
        Dim b, c As Double
        Dim cells(9) As Double
        Dim k As New Counter
        b = 1
        For i = 1 To n
            a = a + 1
            b = b * 1.000001
            c = a - b / 2
            a = a Mod 1000
            cells(a Mod 10) = c
            k.value += 1
        Next
    End Sub
    Public Sub Calls()
        Dim i As Integer
        Dim c As Double
        For i = 1 To n
            c = Half(i)
        Next
    End Sub
End Module
"""
BODY_STATEMENTS = 7  # six statements and the Next of the loop
CALL_STATEMENTS = 3  # the assignment, the called Return and the Next


class _NoRobot:
    pass


def run_once(start: str, iterations: int, statements: int) -> float:
    clock = [0.0]
    scheduler = Scheduler()
    system = GplSystem(_NoRobot(), DigitalIO(), lambda: clock[0], scheduler,
                       Console(stdin=io.StringIO(), echo=None))
    system.load_text(PROJECT.replace("ITERATIONS", str(iterations)), "bench.gpl")
    thread = system.start(start)
    begin = time.perf_counter()
    while scheduler.alive:
        scheduler.run_cycle()
        clock[0] += MAJOR_CYCLE
    elapsed = time.perf_counter() - begin
    assert thread.error is None, thread.error
    return iterations * statements / elapsed


def main() -> None:
    iterations = int(sys.argv[1]) if len(sys.argv) > 1 else 200_000
    for start, statements, what in (("Main", BODY_STATEMENTS, "loop body"), ("Calls", CALL_STATEMENTS, "calls")):
        rates = [run_once(start, iterations, statements) for _ in range(5)]
        print(f"GPL interpreter ({what}): {statistics.median(rates):,.0f} statements/s "
              f"(median of 5 runs of {iterations:,} iterations x {statements} statements)")


if __name__ == "__main__":
    main()
