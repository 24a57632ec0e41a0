"""The suite passes wherever the code is right (issue 46, item 1): no test reads the clock or sleeps.
Speed is measured in ``benchmarks/`` (ratios side by side); a test that waits for another process
does it with :mod:`process_helpers` (a condition, a lock or the process's exit, with a generous
timeout), the one module allowed a deadline."""

import re
from pathlib import Path

TESTS = Path(__file__).resolve().parent
#: a call that reads the wall clock or sleeps
CLOCK = re.compile(r"\btime\.(sleep|time|monotonic|perf_counter)\s*\(|\bfrom time import\b")
WAITING = {"process_helpers.py"}


def test_no_test_reads_the_clock_or_sleeps():
    found = [f"{p.name}:{k}: {line.strip()}" for p in sorted(TESTS.glob("*.py")) if p.name not in WAITING
             for k, line in enumerate(p.read_text().splitlines(), 1) if CLOCK.search(line)]
    assert not found, "\n".join(found)

