"""The detector's learned plate test (vistrack.models.plate.classifier): its candidates, features and
decision, by known answers."""

import cv2
import numpy as np

from vistrack.models.plate.classifier import WINDOW, PlateClassifier, rectangle_candidates, window_features


def _frame_with_rectangle():
    img = np.full((120, 200), 90, np.uint8)
    cv2.rectangle(img, (50, 40), (149, 69), 230, -1)  # a light 100 x 30 rectangle with a dark border
    cv2.rectangle(img, (50, 40), (149, 69), 20, 2)
    return img


def test_a_bordered_rectangle_is_a_candidate_and_a_square_is_not():
    img = _frame_with_rectangle()
    cv2.rectangle(img, (10, 10), (39, 39), 230, -1)  # a square: not plate-shaped
    c = rectangle_candidates(img)
    assert len(c) >= 1
    assert np.min(np.abs(c - [50, 40, 100, 30]).max(axis=1)) <= 2  # the rectangle's box, to 2 px
    assert not np.any((c[:, 0] < 45) & (c[:, 1] < 45))


def test_features_are_the_hog_of_the_grown_box_and_its_aspect():
    img = _frame_with_rectangle()
    f = window_features(img, np.array([[50.0, 40.0, 100.0, 30.0]]))
    assert f.shape == (1, 757)
    assert f[0, 756] == np.float32(np.log(100 / 30))
    # the same window cut by hand: the box grown by 8 % / 15 % a side (x 42..158, y 35..75)
    patch = cv2.resize(img[35:75, 42:158], WINDOW, interpolation=cv2.INTER_AREA)
    from skimage.feature import hog

    want = hog(patch, orientations=9, pixels_per_cell=(8, 8), cells_per_block=(2, 2), block_norm="L2-Hys")
    np.testing.assert_allclose(f[0, :756], want, rtol=1e-6)


def test_decision_is_the_standardised_linear_score(tmp_path):
    p = tmp_path / "c.npz"
    np.savez(p, coef=np.array([1.0, -2.0]), bias=0.5, mean=np.array([1.0, 1.0]), scale=np.array([2.0, 4.0]),
             threshold=1.0)
    clf = PlateClassifier(p)
    np.testing.assert_allclose(clf.decision(np.array([[3.0, 5.0], [1.0, 1.0]])), [1.0 - 2.0 + 0.5, 0.5])


def test_the_shipped_classifier_loads():
    clf = PlateClassifier()
    assert clf.coef.shape == (757,) and clf.mean.shape == (757,) and clf.threshold >= 1.0
