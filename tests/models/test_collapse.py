"""A track whose estimate collapses is reported visible=0 with a reason (vistrack.models.collapse)."""

import csv

import cv2
import numpy as np
import pytest

import vistrack
from cli_helpers import run
from clip_helpers import BOX, GONE, vanishing_frames
from vistrack.appearance.features import FeatureMaps
from vistrack.io.clips import read_groundtruth_csv
from vistrack.models.collapse import REASONS, CollapseWatch
from vistrack.registry.builders import model_from_box


def test_watch_reasons_known_answers():
    w = CollapseWatch(drop=10.0, warmup=3, window=4)
    frame = (100, 80)
    assert [w.check(v, 1.0, (50, 40), frame) for v in (5.0, 7.0, 6.0)] == [("", "")] * 3
    assert w.level == 6.0
    reason, detail = w.check(-4.5, 1.0, (50, 40), frame)  # 10.5 below the level 6
    assert reason == "collapse" and "more than 10 below its running level 6.0" in detail
    assert w.level == 6.0  # a lost frame does not enter the level
    assert w.check(-3.5, 1.0, (50, 40), frame) == ("", "")  # 9.5 below: reported again
    assert w.check(6.0, 0.29, (50, 40), frame)[0] == "collapse"  # below 0.3 of the first frame's scale 1
    assert w.check(6.0, 1.0, (100, 40), frame)[0] == "out-of-frame"
    assert w.check(-np.inf, 1.0, (50, 40), frame)[0] == "collapse"
    r = CollapseWatch(ratio=0.25, warmup=2)
    assert r.check(100.0, 2.0, (1, 1), frame) == r.check(90.0, 2.0, (1, 1), frame) == ("", "")
    assert r.check(23.0, 2.0, (1, 1), frame)[0] == "collapse"  # under 0.25 * 95
    assert r.check(24.0, 0.61, (1, 1), frame) == ("", "")  # scale 0.61 >= 0.3 * 2
    assert w.check(6.0, 1.0, (50, 40), frame, low="confidence 0.1") == ("low-confidence", "confidence 0.1")
    assert set(REASONS) == {"low-confidence", "collapse", "out-of-frame", "not found"}


@pytest.mark.slow
@pytest.mark.parametrize("model", ["box", "contour"])
def test_object_that_vanishes_is_lost_with_a_reason(model):
    frames = vanishing_frames()
    t = vistrack.Tracker(model=model, algo="lis", particles=60, seed=0)
    t.init(frames[0], BOX)
    seen = [(t.visible, t.lost_reason)]
    seen += [(t.update(f)[0], t.lost_reason) for f in frames[1:]]
    assert all(ok and reason == "" for ok, reason in seen[:GONE])  # a normal track stays visible
    after = seen[GONE + 1:]  # one frame to notice
    assert not any(ok for ok, _ in after) and {reason for _, reason in after} == {"collapse"}


def test_contour_shrunk_to_a_point_is_lost_by_scale():
    frames = vanishing_frames()
    model = model_from_box("contour", frames[0], BOX)
    maps = FeatureMaps(frames[0])
    assert model.check_lost(maps, model.prior_mean) == ("", "")
    tiny = model.prior_mean.copy()
    tiny[2] = tiny[6] = -0.8  # scale 0.2 of the first frame's
    reason, detail = model.check_lost(maps, tiny)
    assert reason == "collapse" and detail.startswith("scale 0.2, below 0.3 of the first frame's 1")


def test_run_writes_lost_reason_and_says_when_it_loses_the_object(tmp_path, capsys):
    video = tmp_path / "gone"  # an image folder: lossless
    video.mkdir()
    for k, f in enumerate(vanishing_frames()):
        cv2.imwrite(str(video / f"{k:04d}.png"), f)
    track = tmp_path / "t.csv"
    code, out, err = run(["run", str(video), "--init", ",".join(map(str, BOX)), "-n", "60", "--track", str(track)],
                         capsys)
    assert code == 0, err
    with open(track, newline="") as f:
        rows = list(csv.DictReader(f))
    assert list(rows[0])[:2] == ["frame", "visible"]
    assert list(rows[0])[-4:] == ["ess", "ms", "lost_reason", "confidence"]
    first = next(int(r["frame"]) for r in rows if r["visible"] == "0")
    assert GONE <= first <= GONE + 1
    assert all(r["lost_reason"] == "" for r in rows if r["visible"] == "1")
    assert {r["lost_reason"] for r in rows if r["visible"] == "0"} == {"collapse"}
    assert f"frame {first}: lost the object (collapse: log r at the estimate" in err
    lost = sum(r["visible"] == "0" for r in rows)
    assert (f"object not reported (visible=0) in {lost} of 34 frames (collapse {lost}); "
            f"first lost at frame {first}") in out
    t = read_groundtruth_csv(track)  # the text column reads back beside the numbers
    assert t["lost_reason"][first] == "collapse" and t["visible"][first] == 0.0 and len(t["cx"]) == 34
