"""A comparison tracker is one registry entry (issue 52): ``eval`` runs it, counts its runs and reports it
from its :class:`~vistrack.registry.baseline_specs.BaselineSpec` alone."""

import json

import numpy as np
import pytest

from cli_helpers import run
from clip_helpers import square_clip
from vistrack.registry import BASELINES, BaselineSpec, check_baseline, get_baseline_spec, is_baseline, runs_once


def _still(box, frames):
    """A tracker that never moves: the start box on every frame, 1 ms a frame."""
    index = np.array([i for i, _ in frames], int)
    return np.tile(np.asarray(box, float), (len(index), 1)), np.ones(len(index)), index


@pytest.fixture
def still(monkeypatch):
    """``still``, registered for the test only."""
    spec = BaselineSpec("still", _still, "the start box on every frame")
    monkeypatch.setitem(BASELINES, "still", spec)
    return spec


def test_opencv_trackers_are_entries():
    assert list(BASELINES)[:3] == ["opencv-mil", "opencv-kcf", "opencv-csrt"]
    assert runs_once("opencv-kcf") and not runs_once("opencv-mil") and not runs_once("lis")
    assert get_baseline_spec("opencv-mil").runs_note == "randomised inside OpenCV, not seeded"
    assert get_baseline_spec("opencv-csrt").help == "opencv-csrt (needs opencv-contrib-python-headless)"
    check_baseline("opencv-mil")  # every OpenCV build has MIL
    with pytest.raises(ValueError, match="unknown comparison tracker 'opencv-nano'; choose from opencv-mil, "):
        get_baseline_spec("opencv-nano")


@pytest.mark.slow
def test_one_entry_adds_a_tracker_to_eval(still, tmp_path):
    assert is_baseline("still") and runs_once("still")
    square_clip(tmp_path / "clips" / "sq", 6)
    out = tmp_path / "ev"
    code, _, err = run(["eval", tmp_path / "clips", "--algos", "still", "--runs", "3", "--in-process",
                        "--workers", "1", "--out", out, "-q"])
    assert code == 0, err
    res = json.loads((out / "results.json").read_text())["results"]
    assert [(r["algo"], r["particles"], r["runs"]) for r in res] == [("still", 1, 1)]  # deterministic: once
    task = json.loads(next((out / "tasks").glob("*still*.json")).read_text())
    t = np.arange(6)  # the 20-px square moves 1 px a frame away from the box that stays: IoU (20 - t) / (20 + t)
    assert task["iou"] == pytest.approx((20 - t) / (20 + t))
    md = (out / "report.md").read_text()
    assert "Runs per clip: still: 1 run (deterministic)" in md
    assert any(line.startswith("| still | – | 1 |") for line in md.splitlines())
