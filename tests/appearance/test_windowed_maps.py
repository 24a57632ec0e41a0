"""Appearance maps made window by window (issue 53) equal the numpy path's, made over the whole region at once:
a grey video's grey-level bins, their integrals and the texture, and a region shrunk by a whole factor."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from vistrack import kernels
from vistrack.appearance.features import is_grey
from vistrack.appearance.frame_maps import AppearanceFrame, MapBuffers

pytestmark = pytest.mark.skipif(not kernels.AVAILABLE, reason="numba is not installed")


@pytest.mark.parametrize("f", [0.33, 0.5, 0.96, 1.0])
def test_windowed_grey_maps_equal_the_whole_regions(f):
    rng = np.random.default_rng(4)
    grey = cv2.GaussianBlur(rng.integers(0, 256, (150, 200), dtype=np.uint8), (0, 0), 1.2)
    frame = cv2.cvtColor(grey, cv2.COLOR_GRAY2BGR)  # a grey video stored as colour
    assert is_grey(frame)
    roi = (17, 9, 190, 140)
    windowed = AppearanceFrame(frame, roi, f, True, buffers=MapBuffers())
    texture, ii = windowed.maps((5, 30, 7, 40), (10, 25, 12, 33))
    part = ii[5:31, 7:41].astype(np.int64)
    with kernels.numpy_paths():
        whole = AppearanceFrame(frame, roi, f, True)
    w = whole.ii[5:31, 7:41].astype(np.int64)
    # a window's integrals count from its corner: box sums inside it are the whole region's
    np.testing.assert_array_equal(part - part[:1] - part[:, :1] + part[:1, :1], w - w[:1] - w[:, :1] + w[:1, :1])
    np.testing.assert_array_equal(texture[10:25, 12:33], whole.texture[10:25, 12:33])
    np.testing.assert_array_equal(windowed.labels, whole.labels)  # the whole region made on demand
    np.testing.assert_array_equal(windowed.ii, whole.ii)
    np.testing.assert_array_equal(windowed.texture, whole.texture)
    assert windowed.labels.max() < 16


@pytest.mark.parametrize("k", [2, 3, 5])
def test_windows_of_a_region_shrunk_by_a_whole_factor_equal_the_whole(k):
    rng = np.random.default_rng(1)
    frame = cv2.GaussianBlur(rng.integers(0, 256, (300, 400, 3), dtype=np.uint8), (0, 0), 1.0)
    roi = (13, 7, 391, 288)
    windowed = AppearanceFrame(frame, roi, 1.0 / k, False, buffers=MapBuffers())
    assert windowed.roi == (13, 7, 13 + 378 // k * k, 7 + 281 // k * k)  # whole blocks from the region's corner
    texture, ii = windowed.maps((3, 20, 4, 30), (5, 15, 6, 25))
    part = ii[3:21, 4:31].astype(np.int64)
    with kernels.numpy_paths():
        whole = AppearanceFrame(frame, roi, 1.0 / k, False)
    w = whole.ii[3:21, 4:31].astype(np.int64)
    np.testing.assert_array_equal(part - part[:1] - part[:, :1] + part[:1, :1], w - w[:1] - w[:, :1] + w[:1, :1])
    np.testing.assert_array_equal(texture[5:15, 6:25], whole.texture[5:15, 6:25])
    want = cv2.resize(frame[7:7 + 281 // k * k, 13:13 + 378 // k * k], None, fx=1 / k, fy=1 / k,
                      interpolation=cv2.INTER_AREA)  # OpenCV's block averages
    np.testing.assert_array_equal(whole.image, want)
    np.testing.assert_array_equal(windowed.labels, whole.labels)
