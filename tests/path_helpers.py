"""Shared by the tests: where the repository and its real clips are, wherever a test file lies under tests/."""

from pathlib import Path

#: the repository's root (README.md, docs/, vistrack/)
ROOT = Path(__file__).resolve().parents[1]
#: the real clips with ground truth beside the repository (a clone beside ../shared)
REAL = ROOT.parent / "shared" / "data" / "real"
