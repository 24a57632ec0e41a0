"""The plate detection stage (issue 35): finding plates without a box, the search before tracking,
the one-line hint when nothing is found, ``--layout auto``."""


import numpy as np
import pytest

from cli_helpers import run
from path_helpers import REAL
from vistrack.data_synth.plate_clip import detection_frames
from vistrack.models.plate.detect import Detection, PlateDetector, _split_touching, acquire, plate_from_row
from vistrack.scoring.metrics import iou

DASHCAM = REAL / "plate_in_polo_dashcam" / "plate_in_polo_dashcam.mp4"


def test_plate_from_row_inverts_the_layout_geometry():
    # single-row: the row is 0.1-0.9 x 0.2-0.8 of the plate,
    # so a row 80x12 at (110, 53) is the plate 100x20 at (100, 50)
    np.testing.assert_allclose(plate_from_row((110, 54, 80, 12), "single-row"), (100, 50, 100, 20), atol=1e-9)
    # jp: the four digits are 0.24-0.92 x 0.51-0.89
    np.testing.assert_allclose(plate_from_row((24, 51, 68, 38), "jp"), (0, 0, 100, 100), atol=1e-9)


def test_touching_characters_are_cut_into_pieces():
    st = np.array([[0, 0, 10, 20, 100], [20, 0, 37, 20, 370]], float)  # a glyph and three touching (fill 0.5)
    out = _split_touching(st)
    assert len(out) == 4 and out[:, 5].tolist() == [0, 1, 1, 1]
    np.testing.assert_allclose(out[1:, 0], [20, 20 + 37 / 3, 20 + 74 / 3])
    solid = np.array([[0, 0, 40, 20, 790]], float)  # a solid blob (a window, a light) stays whole
    assert _split_touching(solid)[:, 5].tolist() == [0]


class _Fixed:
    """A detector that returns given detections per frame."""

    def __init__(self, per_frame):
        self.per_frame = per_frame

    def detect(self, frame):
        return self.per_frame[int(frame)]


def _det(x):
    return Detection(np.array([x, 10.0, 50.0, 12.0]), 5.0, "single-row", 7)


def test_acquire_needs_the_plate_in_consecutive_frames():
    dets = {0: [_det(100)], 1: [_det(10)], 2: [_det(12)], 3: [_det(12)]}
    found, searched = acquire(((i, i) for i in range(4)), _Fixed(dets), within=30, confirm=2)
    assert found[0] == 2 and found[2].box[0] == 12 and [i for i, _ in searched] == [0, 1]
    nothing = {i: ([_det(100)] if i % 2 else []) for i in range(40)}
    found, searched = acquire(((i, i) for i in range(40)), _Fixed(nothing), within=30)
    assert found is None and len(searched) == 30


@pytest.mark.slow
def test_no_false_plates_in_plate_free_synthetic_scenes():
    # the road scenes' text signs, grilles and windows: at most 0.05 false plates per frame (issue 35)
    frames, _ = detection_frames(30, seed=6, with_plate=False)
    det = PlateDetector()
    assert sum(len(det.detect(f)) for f in frames) / len(frames) <= 0.05


@pytest.mark.slow
@pytest.mark.parametrize("layout", ["single-row", "jp"])
def test_finds_rendered_plates_of_both_layouts(layout):
    # issue 35: recall >= 0.95 (IoU >= 0.5) on both layouts, the layout told right; seed 5 is not among the
    # classifier's training seeds (benchmarks/train_plate_classifier.py: 100-120)
    frames, boxes = detection_frames(30, layout=layout, seed=5)
    det = PlateDetector()
    found = [[d for d in det.detect(f) if iou(d.box, b) >= 0.5] for f, b in zip(frames, boxes)]
    assert sum(bool(d) for d in found) / len(frames) >= 0.95
    assert sum(bool(d) and d[0].layout == layout for d in found) / len(frames) >= 0.95


@pytest.mark.slow
def test_the_character_row_path_alone_misses_the_bold_jp_digits():
    # what the classifier adds: without it the Japanese layout's touching digits are not found
    frames, boxes = detection_frames(10, layout="jp", seed=5)
    det = PlateDetector(classifier=None)
    assert not any(any(iou(d.box, b) >= 0.5 for d in det.detect(f)) for f, b in zip(frames, boxes))


@pytest.mark.slow
@pytest.mark.skipif(not DASHCAM.is_file(), reason="../shared/data not present")
def test_dashcam_plate_found_without_a_box(tmp_path, capsys):
    res = tmp_path / "r.txt"
    code, out, err = run(["run", str(DASHCAM), "--max-frames", "20", "--seed", "1", "--results", str(res)], capsys)
    assert code == 0, err
    assert "plate found in frame 1" in err and "single-row layout" in err
    gt = np.loadtxt(DASHCAM.parent / "groundtruth_rect.txt", delimiter=",")[:20]
    boxes = np.loadtxt(res, delimiter=",")
    assert boxes[0].tolist() == [0, 0, 0, 0]  # the frame searched before the plate was confirmed
    assert np.all(iou(boxes[1:], gt[1:]) >= 0.5)
    again = tmp_path / "s.txt"
    run(["run", str(DASHCAM), "--max-frames", "20", "--seed", "1", "--results", str(again)], capsys)
    assert res.read_text() == again.read_text()  # same seed, same track


@pytest.mark.skipif(not (REAL / "girl_otb").is_dir(), reason="../shared/data not present")
def test_no_plate_gives_a_one_line_hint_and_fails(capsys):
    code, out, err = run(["run", str(REAL / "girl_otb"), "-q"], capsys)
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert code != 0 and len(lines) == 1
    assert "no license plate found in the first 30 frames" in lines[0] and "--init x,y,w,h" in lines[0]


def test_layout_auto_is_for_every_model(capsys):
    # the default "auto" is no plate option: another model runs with it; a forced layout is refused
    code, _, err = run(["run", "nonexistent.mp4", "--model", "box", "--layout", "jp"], capsys)
    assert code == 2


@pytest.mark.skipif(not (REAL / "girl_otb").is_dir(), reason="real clips not present")
def test_without_init_run_says_which_model_it_chose_and_why(capsys):
    """issue 37: a video without --init (and no meta.json model) is searched for a plate, said first."""
    code, out, err = run(["run", str(REAL / "girl_otb"), "--max-frames", "40"], capsys)
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert code != 0 and lines[0].startswith("tracking with the plate model (no --init and no model in meta.json: "
                                             "it looks for a license plate") and "--init x,y,w,h" in lines[0]
    assert "no license plate found" in lines[-1]
