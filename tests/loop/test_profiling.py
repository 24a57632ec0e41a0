"""The stage split ``run`` prints: exclusive per-stage times, and the same track with or without it."""

from __future__ import annotations

import numpy as np
import pytest

from box_helpers import clip_frames, obj_box, path
from vistrack.loop import Timer
from vistrack.registry import make_filter
from vistrack.registry.builders import model_from_box
from vistrack.session.recording import record_video


def test_timer_counts_nested_calls_once():
    """A stage's time excludes the timed calls nested in it (a fake clock: no wall time)."""
    now = [0.0]
    t = Timer(clock=lambda: now[0])

    def inner():
        now[0] += 0.02

    inner = t.timed(inner, "likelihood")

    def outer():
        now[0] += 0.01
        inner()
        now[0] += 0.005

    t.timed(outer, "proposal")()
    assert t.t["likelihood"] == pytest.approx(0.02, abs=1e-12)
    assert t.t["proposal"] == pytest.approx(0.015, abs=1e-12)
    items = list(t.timed_iter(iter([1, 2]), "decode"))
    assert items == [1, 2] and t.t["decode"] == 0.0


@pytest.mark.parametrize("model, algo", [("contour", "lis"), ("box", "lis"), ("box", "ls-n-ips")])
def test_profiling_leaves_the_track_unchanged(model, algo):
    frames = clip_frames(8)
    runs = []
    for profile in (True, False):
        m = model_from_box(model, frames[0], obj_box(*path(0)))
        f = make_filter(algo, m)
        runs.append(record_video(enumerate(frames), m, f, 60, np.random.default_rng(3), profile=profile))
    with_p, without = runs
    assert [r["cx"] for r in with_p.rows] == [r["cx"] for r in without.rows]
    split = with_p.stage_split()
    assert split["likelihood"] > 0 and split["features"] > 0 and split["total"] >= sum(
        split[s] for s in ("decode", "features", "likelihood", "proposal", "resampling", "adapt")) - 1e-9
    assert without.stage_split() is None
