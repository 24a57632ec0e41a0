"""Ground truth as users have it: OTB, VOT, GOT-10k and LaSOT layouts, polygons, absent frames,
malformed lines; and text files that FFmpeg would happily "decode"."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from cli_helpers import run
from path_helpers import REAL
from vistrack.io.clips import load_clip
from vistrack.io.video import VideoError, open_video, read_rects

H, W = 64, 96


def images(folder, n=4):
    folder.mkdir(parents=True, exist_ok=True)
    for i in range(n):
        img = np.full((H, W, 3), 90, np.uint8)
        cv2.rectangle(img, (20 + i, 20), (40 + i, 36), (30, 60, 220), -1)
        cv2.imwrite(str(folder / f"{i + 1:08d}.jpg"), img)


@pytest.mark.parametrize("layout, gt_name, line, first_box", [
    ("otb", "groundtruth_rect.txt", "21,21,21,17", (20, 20, 21, 17)),  # OTB: 1-based
    ("lasot", "groundtruth.txt", "21,21,21,17", (20, 20, 21, 17)),  # LaSOT: 1-based (img/ + full_occlusion.txt)
    ("vot-rect", "groundtruth.txt", "20,20,21,17", (20, 20, 21, 17)),  # VOT 2013-2019: images in the folder
    ("vot-poly", "groundtruth.txt", "20,22,41,20,40,37,21,36", (20, 20, 21, 17)),  # polygon: bounding box
    ("vot2020", "groundtruth.txt", "20,20,21,17", (20, 20, 21, 17)),  # color/
    ("got10k", "groundtruth.txt", "20\t20\t21\t17", (20, 20, 21, 17)),
])
def test_dataset_layouts_give_the_first_box(tmp_path, layout, gt_name, line, first_box):
    seq = tmp_path / "seq"
    sub = {"otb": "img", "lasot": "img", "vot2020": "color"}.get(layout)
    images(seq / sub if sub else seq)
    if layout == "lasot":
        (seq / "full_occlusion.txt").write_text("0,0,0,0\n")
    (seq / gt_name).write_text("\n".join([line] * 4) + "\n")
    clip = load_clip(seq)
    assert clip.source.frame_count == 4
    np.testing.assert_allclose(clip.first_box(), first_box)


def test_absent_frames_are_not_visible(tmp_path):
    p = tmp_path / "groundtruth.txt"
    p.write_text("nan,nan,nan,nan\n0,0,0,0\n5,5,10,10\nNaN NaN NaN NaN NaN NaN NaN NaN\n")
    r = read_rects(p)
    assert r.tolist() == [[0, 0, 0, 0], [0, 0, 0, 0], [5, 5, 10, 10], [0, 0, 0, 0]]
    images(tmp_path)
    t = load_clip(tmp_path).truth
    assert t["visible"].tolist() == [0, 0, 1, 0]


@pytest.mark.parametrize("text, message", [("1,2,3,4\n1,2,3\n", "line 2: expected 4 values x,y,w,h or 8"),
                                           ("1,2,3,4\n\n1,2,x,4\n", "line 3: expected numbers")])
def test_malformed_ground_truth_is_one_error(tmp_path, capsys, text, message):
    images(tmp_path / "img")
    (tmp_path / "groundtruth_rect.txt").write_text(text)
    with pytest.raises(VideoError, match=message):
        load_clip(tmp_path)
    code, _, err = run(["run", str(tmp_path), "--init-gt"], capsys)
    assert code != 0 and message in err and "groundtruth_rect.txt" in err and err.count("\n") == 1


def test_a_text_file_is_not_a_video(tmp_path, capsys):
    p = tmp_path / "groundtruth_rect.txt"
    p.write_text("1,2,3,4\n" * 30)
    with pytest.raises(VideoError, match="not a video"):
        open_video(p)
    code, _, err = run(["run", str(p), "--init", "1,1,5,5"], capsys)
    assert code != 0 and "is a .txt file, not a video" in err


def test_results_file_is_the_otb_format_and_matches_the_track(tmp_path, capsys):
    """``--results``: one ``x,y,w,h`` line per frame, the track's box in OTB's 1-based pixels (issue 37:
    as the OTB toolkit and pytracking write it), 0,0,0,0 where the object is not reported; a run with no
    output file says so."""
    images(tmp_path / "seq", n=6)
    code, out, err = run(["run", str(tmp_path / "seq"), "--init", "20,20,21,17", "--track", str(tmp_path / "t.csv"),
                          "--results", str(tmp_path / "r.txt")], capsys)
    assert code == 0, err
    from vistrack.io.clips import read_groundtruth_csv

    t = read_groundtruth_csv(tmp_path / "t.csv")
    r = np.loadtxt(tmp_path / "r.txt", delimiter=",")
    assert r.shape == (6, 4)
    np.testing.assert_allclose(r[:, 0] - 1 + r[:, 2] / 2, t["cx"], atol=0.01)
    np.testing.assert_allclose(r[:, 2], t["w"], atol=0.01)
    assert "results (x,y,w,h):" in out
    code, out, err = run(["run", str(tmp_path / "seq"), "--init", "20,20,21,17"], capsys)
    assert code == 0 and "nothing written" in out




@pytest.mark.slow
@pytest.mark.skipif(not (REAL / "girl_otb").is_dir(), reason="real clips not present")
def test_run_summary_centre_error_is_the_mean_over_all_ground_truth_frames(tmp_path, capsys):
    """Computed here independently: the OTB boxes (1-based) against the track CSV's centres."""
    import re

    code, out, err = run(["run", str(REAL / "girl_otb"), "--init-gt", "--max-frames", "60", "--track",
                          str(tmp_path / "t.csv")], capsys)
    assert code == 0, err
    from vistrack.io.clips import read_groundtruth_csv

    t = read_groundtruth_csv(tmp_path / "t.csv")
    gt = np.loadtxt(REAL / "girl_otb" / "groundtruth_rect.txt", delimiter=",")[:60]
    cx, cy = gt[:, 0] - 1 + gt[:, 2] / 2, gt[:, 1] - 1 + gt[:, 3] / 2
    expect = np.hypot(t["cx"] - cx, t["cy"] - cy).mean()
    printed = float(re.search(r"mean centre error ([0-9.]+) px over all", out).group(1))
    assert abs(printed - expect) < 0.006


@pytest.mark.slow
def test_result_files_round_trip_through_eval(tmp_path, capsys):
    """``run --results`` then ``eval --results-dir``: the other tracker's scores equal the run's own
    (success AUC, all-frames centre error), with no frame rate; a missing result file is one line."""
    import json
    import re

    seq = tmp_path / "seq"
    images(seq / "img", n=6)
    (seq / "groundtruth_rect.txt").write_text("\n".join(f"{21 + i},21,21,17" for i in range(6)) + "\n")
    (tmp_path / "mytracker").mkdir()
    code, out, err = run(["run", str(seq), "--init-gt", "--results", str(tmp_path / "mytracker" / "seq.txt")], capsys)
    assert code == 0, err
    auc = float(re.search(r"success AUC ([0-9.]+)", out).group(1))
    mean_err = float(re.search(r"mean centre error ([0-9.]+) px over all", out).group(1))
    code, out, err = run(["eval", str(seq), "--algos", "", "--results-dir", str(tmp_path / "mytracker"),
                          "--out", str(tmp_path / "ev"), "-q"], capsys)
    assert code == 0, err
    (r,) = json.loads((tmp_path / "ev" / "results.json").read_text())["results"]
    assert r["algo"] == "mytracker" and r["frames_per_s"] is None
    assert r["success_auc"] == pytest.approx(auc, abs=2e-3) and r["mean_error_all"] == pytest.approx(mean_err, abs=0.01)
    (tmp_path / "empty").mkdir()
    code, _, err = run(["eval", str(seq), "--algos", "", "--results-dir", str(tmp_path / "empty"),
                        "--out", str(tmp_path / "ev2"), "-q"], capsys)
    assert code != 0 and "no result file seq.txt" in err


@pytest.mark.parametrize("rows, message", [(3, "3 rows for 4 frames; frames past its end are not scored"),
                                           (6, "6 rows for 4 frames; its extra rows are ignored")])
def test_ground_truth_of_another_length_is_a_warning_with_the_counts(tmp_path, rows, message):
    from vistrack.io.clips import GroundTruthWarning

    images(tmp_path / "img")
    (tmp_path / "groundtruth_rect.txt").write_text("21,21,21,17\n" * rows)
    with pytest.warns(GroundTruthWarning, match=message):
        clip = load_clip(tmp_path)
    assert len(clip.truth["cx"]) == rows
