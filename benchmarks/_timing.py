"""Per-part timers for the benchmarks (exclusive time: a timed call inside another
timed call is counted once, in its own part)."""

import time
import warnings

from vistrack.loop import Timer

#: the benchmarks import ``Timer`` from here
__all__ = ["Timer", "PARTS", "run_timed", "stepper", "split_table"]

PARTS = ["decode", "features", "likelihood", "proposal", "resampling"]


def run_timed(source, timer, features, step):
    """Decode ``source`` (``(index, frame)`` pairs) frame by frame and time, per frame,
    the decode, ``features(frame) -> maps`` and ``step(maps)`` (the filter) into
    ``timer``; warnings are silenced. Returns the number of frames."""
    frames, it = 0, iter(source)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        while True:
            t0 = time.perf_counter()
            try:
                _, frame = next(it)
            except StopIteration:
                return frames
            t1 = time.perf_counter()
            maps = features(frame)
            t2 = time.perf_counter()
            step(maps)
            t3 = time.perf_counter()
            timer.t["decode"] += t1 - t0
            timer.t["features"] += t2 - t1
            timer.t["filter"] += t3 - t2
            frames += 1


def stepper(filt, n, rng):
    """``step(maps)``: the filter's first step on the first call, its ordinary step after."""
    state = {"p": None}

    def step(maps):
        p = state["p"]
        state["p"] = filt.first_step(maps, n, rng) if p is None else filt.step(p, maps, rng)

    return step


def split_table(timers, frames, decode_in_total=True):
    """Rows of ms per frame per part, ``other`` (the rest of the filter step), total and frames/s;
    the last column is the total over the first entry's."""
    rows, base = [], None
    for e, tm in timers.items():
        k = 1e3 / frames[e]
        total = (tm.t["features"] + tm.t["filter"] + (tm.t["decode"] if decode_in_total else 0.0)) * k
        base = base or total
        other = (tm.t["filter"] - tm.t["likelihood"] - tm.t["proposal"] - tm.t["resampling"]) * k
        rows.append(f"{e[0]:<10} {e[1]:>5} " + " ".join(f"{tm.t[p] * k:>10.2f}" for p in PARTS)
                    + f" {other:>7.2f} {total:>7.2f} {1e3 / total:>9.0f} {total / base:>8.2f}")
    head = (f"{'algo':<10} {'N':>5} " + " ".join(f"{p:>10}" for p in PARTS)
            + f" {'other':>7} {'total':>7} {'frames/s':>9} {'x first':>8}")
    return [head] + rows
