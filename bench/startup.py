"""Start-up time of `twin run`: importing the package and loading the demo cell and a
one-line V+ program (everything before the first simulated step), in a fresh
interpreter each time, median of a few.

    .venv/bin/python bench/startup.py [--runs 5]
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys

PROBE = """
import json, tempfile, time
t0 = time.perf_counter()
from twin.runner import start_program
t1 = time.perf_counter()
with tempfile.NamedTemporaryFile("w", suffix=".pg", delete=False) as f:
    f.write('.PROGRAM hello()\\n    TYPE "hello"\\n.END\\n')
start_program(f.name)
t2 = time.perf_counter()
print(json.dumps({"import_s": t1 - t0, "load_s": t2 - t1}))
"""


def measure(runs: int = 5) -> dict[str, float]:
    """Median import and load seconds over `runs` fresh interpreters."""
    samples = [json.loads(subprocess.run([sys.executable, "-c", PROBE], check=True, capture_output=True,
                                         text=True).stdout.splitlines()[-1]) for _ in range(runs)]
    return {key: statistics.median(s[key] for s in samples) for key in ("import_s", "load_s")}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    m = measure(parser.parse_args().runs)
    print(f"start-up: import {m['import_s']:.2f} s + load {m['load_s']:.2f} s = "
          f"{m['import_s'] + m['load_s']:.2f} s (median)")


if __name__ == "__main__":
    main()
