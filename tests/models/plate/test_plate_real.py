"""The plate likelihood on a real plate (issue 35): on the dashcam clip's frames, scanned over a grid of
centres about the ground truth, it peaks at the plate."""


import numpy as np
import pytest

from path_helpers import REAL
from vistrack.appearance.features import FeatureMaps
from vistrack.io.video import open_video, read_rects
from vistrack.models.plate.detect import PlateDetector
from vistrack.registry.builders import model_from_box

pytestmark = pytest.mark.slow  # every test here (the rule: tests/conftest.py)

CLIP = REAL / "plate_in_polo_dashcam"


@pytest.fixture(scope="module")
def dashcam():
    if not (CLIP / "groundtruth_rect.txt").is_file() or not any(CLIP.glob("*.mp4")):
        pytest.skip("../shared/data/real/plate_in_polo_dashcam not present")
    frames = [f for _, f in open_video(next(CLIP.glob("*.mp4")))]
    return frames, np.asarray(read_rects(CLIP / "groundtruth_rect.txt"), float)


def _peak_errors(model, frames, gt, width):
    """Distance (px) from the ground-truth centre to the best of a 21 x 21 grid of centres 1 px apart
    about it (plate width ``width``, angle 0), with the appearance learned in the first frame (not adapted)."""
    d = np.arange(-10, 11, 1.0)
    du, dv = (a.ravel() for a in np.meshgrid(d, d))
    errs = []
    for f, (x, y, w, h) in zip(frames, gt):
        st = np.zeros((len(du), 9))
        st[:, 0], st[:, 1], st[:, 3] = x + w / 2 + du, y + h / 2 + dv, width * w / gt[0, 2]
        st[:, 4:8] = st[:, :4]
        model.prior_mean = st[len(du) // 2].copy()  # the appearance's region: about the ground truth
        k = int(np.argmax(model.loglik(model.observe(FeatureMaps(f), None), st)))
        errs.append(np.hypot(du[k], dv[k]))
    return np.array(errs)


def test_likelihood_peaks_at_the_plate_from_the_first_box(dashcam):
    frames, gt = dashcam
    model = model_from_box("plate", frames[0], gt[0])
    errs = _peak_errors(model, frames, gt, gt[0, 2])
    assert np.mean(errs <= 3) >= 0.9, np.round(errs, 1)  # 138 of 138 frames (docs/experiments.md)


def test_likelihood_peaks_at_the_plate_from_the_detection(dashcam):
    frames, gt = dashcam
    det = PlateDetector().detect(frames[0])[0]  # no box: the plate as the detector finds it in the first frame
    model = model_from_box("plate", frames[0], det.box, layout=det.layout)
    errs = _peak_errors(model, frames, gt, det.box[2])
    assert np.mean(errs <= 3) >= 0.9, np.round(errs, 1)


def test_from_the_first_box_the_angle_holds_and_the_plate_model_is_level_with_the_box_model(dashcam):
    """Issue 35: from the first ground-truth box (LIS-100, seed 1) the plate model's success AUC is at least
    the box model's (since the box model's scale filter, issue 43, the two are level: 0.931 each). The
    learned template reads the parallelogram's axis-aligned box; adapted to the estimate, it learned the
    taller box of a tilted estimate and the angle drifted to about -2 degrees (the reported box 12 % higher
    than the ground truth, AUC 0.88 against the box model's 0.91): the plate model keeps its first view
    (``Plate.adapt_rate`` 0) and the correlation filter adapts."""
    import vistrack
    from vistrack.scoring.metrics import iou, success_auc

    frames, gt = dashcam
    out = {}
    for name in ("plate", "box"):
        trk = vistrack.Tracker(model=name, algo="lis", particles=100, seed=1)
        trk.init(frames[0], gt[0])
        boxes = [trk.box if trk.visible else (0, 0, 0, 0)]
        for f in frames[1:len(gt)]:
            ok, b = trk.update(f)
            boxes.append(b if ok else (0, 0, 0, 0))
        out[name] = np.array(boxes, float)
    plate = out["plate"]
    assert np.median(plate[:, 3] / gt[:len(plate), 3]) <= 1.06  # 1.12 with the template adapting
    auc = {k: success_auc(iou(np.nan_to_num(v), gt[:len(v)])) for k, v in out.items()}
    # 0.926 against 0.910 before the box model's scale filter; 0.9306 against 0.9313 with it
    assert auc["plate"] >= auc["box"] - 0.005, auc


def test_same_seed_same_track_with_the_correlation_filter(dashcam):
    """From the first box the plate model carries the correlation filter (its search, its adaptation and its
    term in the line scans): the same seed still gives the same track, to the bit."""
    import vistrack

    frames, gt = dashcam
    tracks = []
    for _ in range(2):
        trk = vistrack.Tracker(model="plate", algo="lis", particles=100, seed=3)
        trk.init(frames[0], gt[0])
        assert trk.model.cf is not None
        tracks.append([trk.update(f)[1] for f in frames[1:20]])
    np.testing.assert_array_equal(np.array(tracks[0], float), np.array(tracks[1], float))
