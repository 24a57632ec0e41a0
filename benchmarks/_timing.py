"""Per-part timers for the benchmarks (exclusive time: a timed call inside another
timed call is counted once, in its own part)."""

import time
from collections import defaultdict


class Timer:
    """Accumulates seconds per part; ``wrap`` times a method of an object or class."""

    def __init__(self):
        self.t = defaultdict(float)
        self._stack = []  # [part, seconds of nested timed calls]

    def wrap(self, owner, name, part):
        """Time ``owner.name`` as ``part``; returns the original (restore with ``setattr``)."""
        fn = getattr(owner, name)
        setattr(owner, name, self.timed(fn, part))
        return fn

    def timed(self, fn, part):
        def timed(*a, **k):
            self._stack.append([part, 0.0])
            t0 = time.perf_counter()
            try:
                return fn(*a, **k)
            finally:
                dt = time.perf_counter() - t0
                _, nested = self._stack.pop()
                self.t[part] += dt - nested
                if self._stack:
                    self._stack[-1][1] += dt

        return timed
