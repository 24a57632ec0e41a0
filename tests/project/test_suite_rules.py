"""The suite passes wherever the code is right (issue 46, item 1): no test reads the clock or sleeps.
Speed is measured in ``benchmarks/`` (ratios side by side); a test that waits for another process
does it with :mod:`process_helpers` (a condition, a lock or the process's exit, with a generous
timeout), the one module allowed a deadline. Tests are filed by package (issue 52): ``tests/<package>/``."""

import re

from path_helpers import ROOT

TESTS = ROOT / "tests"
#: a call that reads the wall clock or sleeps
CLOCK = re.compile(r"\btime\.(sleep|time|monotonic|perf_counter)\s*\(|\bfrom time import\b")
WAITING = {"process_helpers.py"}


def test_no_test_reads_the_clock_or_sleeps():
    found = [f"{p.relative_to(TESTS)}:{k}: {line.strip()}" for p in sorted(TESTS.rglob("*.py"))
             if p.name not in WAITING for k, line in enumerate(p.read_text().splitlines(), 1) if CLOCK.search(line)]
    assert not found, "\n".join(found)


def test_tests_are_filed_by_package():
    """A test file lies in ``tests/<package>/`` (a folder per vistrack package, ``models/<family>/`` for a
    family, ``project/`` for the repository's own rules), under a name no other test file has, with no
    ``__init__.py``; tests/ itself holds the shared helpers (``conftest.py``, ``*_helpers.py``) only (issue 55
    filed the fault sweeps by what they break: ``tests/<package>/test_faults_*.py``)."""
    code = ROOT / "vistrack"
    folders = {p.parent.relative_to(code).as_posix() for p in code.rglob("__init__.py")} - {"."} | {"project"}
    files = sorted(TESTS.rglob("test_*.py"))
    misplaced = [p.relative_to(TESTS).as_posix() for p in files
                 if p.parent == TESTS
                 or (p.parent != TESTS and p.parent.relative_to(TESTS).as_posix() not in folders)]
    names = [p.name for p in files]
    assert misplaced == []
    assert sorted({n for n in names if names.count(n) > 1}) == []
    assert list(TESTS.rglob("__init__.py")) == []
    loose = sorted(p.name for p in TESTS.glob("*.py"))
    assert all(n == "conftest.py" or n.endswith("_helpers.py") for n in loose), loose
