"""The colour-blob proposal of §3.2.5: its density is exact (integrates to one, its draws follow
it), it finds the target's colour, and the contour and box models learn it from the first frame."""

import numpy as np
import pytest
from scipy import stats

from vistrack.proposals import BlobProposal, GaussianColour

X0, Y0, F = 7.0, -3.0, 0.5  # the image lies at frame (7, -3), at half the frame's resolution


def scene(seed=0):
    """A 72 x 56 BGR image of random colours with an orange disc; the disc's colour model."""
    import cv2

    rng = np.random.default_rng(seed)
    img = rng.integers(0, 256, (56, 72, 3)).astype(np.uint8)
    mask = np.zeros((56, 72), np.uint8)
    cv2.circle(mask, (50, 20), 8, 1, -1)
    img[mask > 0] = (30, 120, 230)
    img[mask > 0] += rng.integers(0, 20, (int(mask.sum()), 3)).astype(np.uint8)
    return img, GaussianColour.fit(img, mask)


def proposal(img, colour, **kw):
    return BlobProposal(colour, lambda obs: (img, X0, Y0, F), cell=8.0, **kw)


def test_density_integrates_to_one():
    """Cell 8 frame px, fine displacement ±4.4 px: the density is constant on 0.4-px squares, so
    the midpoint sum on a 0.2-px grid over the frame grown by the displacement is exact."""
    img, colour = scene()
    prop = proposal(img, colour)
    p, origin, cell = prop.cell_map(object())
    assert p.shape == (14, 18) and np.allclose(origin, (X0, Y0)) and np.allclose(cell, 8.0)
    h = 0.5 * 1.1 * 8.0
    d = 0.2
    xs = np.arange(X0 - h - 1, X0 + 144 + h + 1, d) + d / 2
    ys = np.arange(Y0 - h - 1, Y0 + 112 + h + 1, d) + d / 2
    gx, gy = np.meshgrid(xs, ys)
    obs = object()
    dens = np.exp(prop.logpdf(np.stack([gx.ravel(), gy.ravel()], 1), obs))
    assert abs(dens.sum() * d * d - 1.0) < 1e-9
    assert dens.reshape(gx.shape)[np.abs(gy - (Y0 + 40)) < 3].max() > 20 * dens.min(where=dens > 0, initial=1)


def test_draws_follow_the_density():
    img, colour = scene(1)
    prop = proposal(img, colour, floor=0.2)
    obs = object()
    x = prop.sample(40000, obs, np.random.default_rng(2))
    # 7 x 6 bins of 24 x 24 frame px over the frame grown by the displacement; exact bin masses
    ex, ey = X0 - 4.4 + 24 * np.arange(8), Y0 - 4.4 + 24 * np.arange(7)
    counts, _, _ = np.histogram2d(x[:, 0], x[:, 1], bins=[ex, ey])
    d = 0.2
    gx, gy = np.meshgrid(np.arange(ex[0], ex[-1], d) + d / 2, np.arange(ey[0], ey[-1], d) + d / 2)
    dens = np.exp(prop.logpdf(np.stack([gx.ravel(), gy.ravel()], 1), obs)) * d * d
    mass, _, _ = np.histogram2d(gx.ravel(), gy.ravel(), bins=[ex, ey], weights=dens)
    assert abs(mass.sum() - 1.0) < 1e-9
    some = mass.ravel() > 0
    assert counts.ravel()[~some].sum() == 0
    assert stats.chisquare(counts.ravel()[some], 40000 * mass.ravel()[some]).pvalue > 1e-4
    # the blob's cells (the disc at image (50, 20): frame (107, 37)) get most of the draws
    near = np.hypot(x[:, 0] - (X0 + 50 / F), x[:, 1] - (Y0 + 20 / F)) < 24
    assert near.mean() > 0.5


def test_same_seed_same_draws_and_bad_parameters():
    img, colour = scene()
    prop = proposal(img, colour)
    a, b = (prop.sample(50, object(), np.random.default_rng(9)) for _ in range(2))
    assert np.array_equal(a, b)
    with pytest.raises(ValueError, match="BlobProposal needs cell > 0"):
        BlobProposal(colour, None, cell=0.0)


def test_models_learn_the_blob_from_the_first_frame():
    """Box and contour (through the builder) learn the target's colour; a contour built by hand
    says what it lacks in one line."""
    from vistrack.models.box.model import Box
    from vistrack.models.contour.model import Contour
    from vistrack.registry import make_filter

    img, disc = scene()
    box = Box(img, (42, 12, 16, 16))  # the disc's bounding box: its corners are background
    lik = box.blob_colour.likelihood(img)
    inside = disc.likelihood(img) > 0.1
    assert lik[inside].mean() > 10 * lik[~inside].mean()
    assert make_filter("rb-ss-hs-sir", box).proposal.cell == pytest.approx(4.0)
    contour = Contour.from_box((42, 12, 16, 16), (72, 56))
    with pytest.raises(ValueError, match=r"needs the target's colour: Contour.learn_blob\(first_frame\) first"):
        make_filter("rb-ss-hs-sir", contour)
    contour.learn_blob(img)
    assert make_filter("sir", contour).proposal.image.cell == pytest.approx(3.0)


def test_colour_fit_reads_the_mask_box_only_and_equals_the_whole_frame():
    from vistrack.proposals.blob import colour_features

    rng = np.random.default_rng(4)
    frame = rng.integers(0, 255, (90, 120, 3)).astype(np.uint8)
    mask = np.zeros((90, 120), np.uint8)
    mask[20:41, 33:70] = 1
    mask[25, 80] = 1
    g = GaussianColour.fit(frame, mask)
    f = colour_features(frame)[mask > 0].astype(float)
    np.testing.assert_array_equal(g.mean, f.mean(axis=0))
    np.testing.assert_array_equal(g.cov, np.cov(f, rowvar=False) + 1e-4 * np.eye(2))
