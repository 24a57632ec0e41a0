"""A rendered plate composited onto a real clip's car (vistrack.data_synth.plate_composite): where it goes,
that its ground truth is exact, and the clip it writes."""


import cv2
import numpy as np
import pytest

from path_helpers import REAL
from vistrack.data_synth.plate_composite import composite_frame, composite_plate_clip, plate_boxes
from vistrack.io.video import open_video

CAR4 = REAL / "car4_otb_first100"


def test_plate_boxes_sit_on_the_smoothed_car_box():
    car = np.tile([100.0, 50.0, 200.0, 100.0], (9, 1))
    car[4, 0] += 9.0  # one frame's jitter, smoothed over 3 frames: +3 px on frames 3-5
    b = plate_boxes(car, aspect=4.0, width=0.4, centre=(0.5, 0.6), smooth=1)
    # a plate 80 x 20 centred at (100 + 100, 50 + 60)
    np.testing.assert_allclose(b[0], [160.0, 100.0, 80.0, 20.0])
    np.testing.assert_allclose(b[3:6, 0], [163.0, 163.0, 163.0])
    np.testing.assert_allclose(b[[2, 6], 0], [160.0, 160.0])


@pytest.mark.parametrize("box", [(40.0, 30.0, 64.0, 16.0), (40.5, 30.25, 63.5, 15.5)])
def test_the_plate_covers_exactly_its_box(box):
    frame = np.full((100, 160, 3), 40, np.uint8)
    plate = np.full((50, 200, 3), 235.0, np.float32)  # a white plate: its coverage is visible per pixel
    out = composite_frame(frame, plate, box, 1.0, np.random.default_rng(0), blur=0, noise=0)
    cover = (out[..., 0].astype(float) - 40) / (235 - 40)  # the share of each pixel the plate covers
    x, y, w, h = box
    assert cover.sum() == pytest.approx(w * h, rel=0.01)  # its area
    cols, rows = np.arange(160) + 0.5, np.arange(100) + 0.5  # pixel centres
    assert cover[:, cols.searchsorted(x + w + 0.5):].max() < 0.01  # nothing a pixel beyond its right side
    assert cover[rows.searchsorted(y + h + 0.5):].max() < 0.01  # nor below
    assert cover[int(y) + 2, int(x) + 2] > 0.99 and cover[int(y + h) - 2, int(x + w) - 2] > 0.99
    my, mx = np.average(np.mgrid[:100, :160] + 0.5, axis=(1, 2), weights=cover)  # its centroid
    assert (mx, my) == (pytest.approx(x + w / 2, abs=0.05), pytest.approx(y + h / 2, abs=0.05))


@pytest.mark.slow
@pytest.mark.skipif(not CAR4.is_dir(), reason="../shared/data not present")
def test_car4_clip_with_a_plate(tmp_path):
    out = tmp_path / "c"
    assert composite_plate_clip(out, CAR4, layout="jp", seed=1) == 100
    gt = np.loadtxt(out / "groundtruth_rect.txt", delimiter=",")
    assert gt.shape == (100, 4) and np.allclose(gt[:, 2] / gt[:, 3], 2.0, rtol=1e-3)  # the jp aspect
    frames = [f for _, f in open_video(next(out.glob("*.mp4")))]
    assert len(frames) == 100 and frames[0].shape == (240, 360, 3)
    x, y, w, h = gt[0]
    g = cv2.cvtColor(frames[0], cv2.COLOR_BGR2GRAY)
    inside = g[int(y + 0.2 * h):int(y + 0.4 * h), int(x + 0.1 * w):int(x + 0.2 * w)]  # the plate's blank corner
    assert inside.mean() > 180  # a white plate on car4's dark car
