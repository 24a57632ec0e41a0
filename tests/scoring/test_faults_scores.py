"""Faults that break scores: frames that fail to decode, absent or short ground truth and result files, a
plate clip's empty frames; run's summary and eval score the same frames alike."""

from __future__ import annotations

import json

import pytest

from cli_helpers import run
from fault_helpers import (
    image_folder,
    moving_box_frames,
    otb_folder,
    read_rows,
)


def test_eval_keeps_frames_aligned_with_the_truth_past_a_bad_frame(tmp_path, capsys):
    """The bad frame counts as lost (no estimate) and the frames after it are scored against their own
    ground truth, not shifted by one."""
    import json

    rows = moving_box_frames(tmp_path / "clip" / "img")
    (tmp_path / "clip" / "img" / "0004.png").write_bytes(b"not a png")
    (tmp_path / "clip" / "groundtruth_rect.txt").write_text("\n".join(rows) + "\n")
    code, _, err = run(["eval", str(tmp_path / "clip"), "--model", "box", "--algos", "lis", "--particles", "50",
                        "--runs", "1", "--in-process", "--out", str(tmp_path / "ev"), "-q"], capsys)
    assert code == 0, err
    (task,) = [json.loads(p.read_text()) for p in (tmp_path / "ev" / "tasks").glob("*.json")]
    assert task["error"][3] is None and task["lost"][3] == 1
    assert all(e is not None and e < 3 for k, e in enumerate(task["error"]) if k != 3)

def test_absent_frames_count_alike_in_results_json_and_csv(tmp_path, capsys):
    """OTB frames without the object (NaN, 0,0,0,0) are not visible everywhere: results.csv's row of
    a task has results.json's numbers for that one run."""
    import json

    rows = moving_box_frames(tmp_path / "clip" / "img")
    rows[3], rows[4] = "NaN,NaN,NaN,NaN", "0,0,0,0"
    (tmp_path / "clip" / "groundtruth_rect.txt").write_text("\n".join(rows) + "\n")
    code, _, err = run(["eval", str(tmp_path / "clip"), "--model", "box", "--algos", "bootstrap", "--particles", "30",
                        "--runs", "1", "--in-process", "--out", str(tmp_path / "ev"), "-q"], capsys)
    assert code == 0, err
    (s,) = json.loads((tmp_path / "ev" / "results.json").read_text())["results"]
    (row,) = read_rows(tmp_path / "ev" / "results.csv")
    for k in ("mean_error", "mean_error_all", "p_lost", "success_auc", "precision_20px"):
        assert float(row[k]) == pytest.approx(s[k], abs=1e-4), k
    assert s["p_lost"] == 0.0 and s["success_auc"] > 0.7

def test_7_short_result_files_are_said_and_scored_as_not_reported(tmp_path, capsys):
    image_folder(tmp_path / "c", 10)
    (tmp_path / "mt").mkdir()
    (tmp_path / "mt" / "c.txt").write_text("".join(f"{40 + 2 * i},50,25,19\n" for i in range(6)))
    from vistrack.evaluation.experiment import ResultsLengthWarning

    with pytest.warns(ResultsLengthWarning, match="has 6 lines for the 10 ground-truth frames.*scored as not reported"):
        code, _, err = run(["eval", str(tmp_path / "c"), "--algos", "", "--results-dir", str(tmp_path / "mt"),
                            "--out", str(tmp_path / "e"), "-q"], capsys)
    assert code == 0, err
    (summary,) = json.loads((tmp_path / "e" / "results.json").read_text())["results"]
    assert summary["algo"] == "mt" and len(summary["p_lost_per_frame"]) == 10
    assert summary["precision_20px"] == pytest.approx(0.6) and summary["p_lost"] == pytest.approx(0.4)

def test_run_summary_scores_an_undecodable_frame_as_eval_does(tmp_path):
    """run_summary_decode: one frame of 12 fails to decode; run's summary and eval --results-dir over
    the same results give the same success AUC, precision, lost frames and mean error."""
    import json
    import re

    seq = otb_folder(tmp_path / "seq", 12, bad=[4])
    (tmp_path / "mt").mkdir()
    code, out, err = run(["run", seq, "--init-gt", "-n", "50", "--results", tmp_path / "mt" / "seq.txt"])
    assert code == 0, err
    line = next(ln for ln in out.splitlines() if ln.startswith("vs ground truth"))
    code, _, err = run(["eval", seq, "--algos", "", "--results-dir", tmp_path / "mt", "--out", tmp_path / "ev", "-q"])
    assert code == 0, err
    (r,) = json.loads((tmp_path / "ev" / "results.json").read_text())["results"]
    got = {k: float(re.search(pat, line).group(1)) for k, pat in (
        ("success_auc", r"success AUC ([0-9.]+)"), ("precision_20px", r"precision@20px ([0-9.]+)"),
        ("mean_error_all", r"mean centre error ([0-9.]+) px over all"),
        ("lost", r"lost by the ground truth \([^)]*\) in (\d+)"))}
    assert got["precision_20px"] == pytest.approx(r["precision_20px"], abs=1e-3) == 11 / 12
    assert got["lost"] / 12 == pytest.approx(r["p_lost"]) == 1 / 12
    assert got["success_auc"] == pytest.approx(r["success_auc"], abs=1e-3)
    assert got["mean_error_all"] == pytest.approx(r["mean_error_all"], abs=0.01)
    assert "but the 1 without an estimate" in line

def test_eval_scores_a_plate_clip_from_its_first_box_frame(tmp_path):
    """eval on a plate clip whose first 7 frames have no plate: the plate rule compares each frame's
    report with that frame's truth (the reports were 7 frames off: every frame lost, no mean error)."""
    import json

    from vistrack.data_synth.plate_clip import make_plate_clip

    make_plate_clip(tmp_path / "p", frames=40, size=(320, 240), seed=1, cars=1)
    code, _, err = run(["eval", tmp_path / "p", "--model", "plate", "--algos", "lis", "--particles", "50", "--runs",
                        "1", "--in-process", "--out", tmp_path / "ev", "-q"])
    assert code == 0, err
    (r,) = json.loads((tmp_path / "ev" / "results.json").read_text())["results"]
    assert r["p_lost"] < 0.6 and r["mean_error"] < 2.0, r["p_lost"]


# ------------------------------------------------------------------ the fourth sweep (issue 55)


def test_iou_is_at_most_one_and_a_perfect_track_scores_20_of_21():
    """A results file equal to the ground truth scored success AUC 0.9555, above the 20/21 maximum: two equal
    boxes' IoU came out as 1 + 1e-15, above the last threshold (1)."""
    import numpy as np

    from vistrack.scoring.metrics import iou, success_auc

    rng = np.random.default_rng(0)
    boxes = np.column_stack([rng.uniform(0, 500, (200, 2)), rng.uniform(3, 90, (200, 2))])
    got = iou(boxes, boxes)
    assert got.max() <= 1.0 and got.min() > 1 - 1e-12  # rounding: never above 1
    assert success_auc(got) == 20 / 21
    assert iou([np.nan] * 4, [1, 2, 3, 4]) == 0.0  # no estimate: no overlap, as before
