"""The plate model on a plate its rendered-plate likelihood was not fitted to: with ``--init``
(``model_from_box``) it learns the plate's appearance from the first frame and follows it."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

import vistrack
from vistrack.appearance.features import FeatureMaps
from vistrack.registry.builders import model_from_box

H, W = 240, 320
PW, PH = 64, 14  # a single-row plate: aspect about 4.6


def road(seed=0):
    rng = np.random.default_rng(seed)
    noise = cv2.GaussianBlur(rng.normal(0, 1, (H, W)).astype(np.float32), (0, 0), 3)
    base = (90 + 250 * noise).clip(0, 255)
    return np.dstack([base, base, base * 1.05]).clip(0, 255).astype(np.uint8)


def draw_plate(img, cx, cy):
    """A yellow plate with dark characters centred at (cx, cy)."""
    out = img.copy()
    x0, y0 = int(round(cx - PW / 2)), int(round(cy - PH / 2))
    cv2.rectangle(out, (x0, y0), (x0 + PW - 1, y0 + PH - 1), (0, 200, 240), -1)
    for k in range(7):
        cv2.rectangle(out, (x0 + 4 + 8 * k, y0 + 3), (x0 + 8 + 8 * k, y0 + PH - 4), (20, 20, 20), -1)
    return out


def centre(t):
    return 120 + 4.0 * t, 150 + 1.5 * t


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_plate_follows_a_yellow_plate_after_learning_it(seed):
    """Without entering-car births (a plate from a box has none) the line scans must reach the
    plate: with the rendered-plate likelihood's scans alone, whose mode on this plate is a character
    pitch (8 px) to the side, seed 1 drifted 8 px; the appearance map in the scans keeps it."""
    bg = road()
    frames = [draw_plate(bg, *centre(t)) for t in range(20)]
    cx, cy = centre(0)
    trk = vistrack.Tracker(model="plate", algo="lis", particles=100, seed=seed, layout="single-row")
    trk.init(frames[0], (cx - PW / 2, cy - PH / 2, PW, PH))
    assert trk.model.app is not None
    assert trk.model.enter_weight == 0 and trk.model.birth_reserve == 0
    errs = []
    for t in range(1, 20):
        ok, (x, y, w, h) = trk.update(frames[t])
        errs.append(np.hypot(x + w / 2 - centre(t)[0], y + h / 2 - centre(t)[1]))
    assert max(errs) < 4.0, errs
    assert ok  # reported visible: the estimate matches the learned plate


def test_appearance_adds_to_the_plate_likelihood_and_can_be_turned_off():
    img = draw_plate(road(), 160, 120)
    box = (160 - PW / 2, 120 - PH / 2, PW, PH)
    with_app = model_from_box("plate", img, box, layout="single-row")
    plain = model_from_box("plate", img, box, layout="single-row", appearance=False)
    assert plain.app is None
    maps = with_app.observe(FeatureMaps(img), None)
    states = np.tile(with_app.prior_mean, (3, 1))
    states[1, 0] += 12
    states[2, 1] -= 9
    # each box's appearance term is read on a frame that covers it (the tracked region's, or one of its own)
    log_rc, log_rt, _ = with_app._app_terms(maps, states)
    extra = log_rc + log_rt
    inside = maps.appearance_frames(with_app.app_boxes(states[:1]), np.zeros(1), 0.0)[0][0] is maps.appearance
    assert inside  # the start pose's box lies in the tracked region
    np.testing.assert_allclose(extra[0], with_app.app.loglik(maps.appearance, with_app.app_boxes(states[:1]))[0])
    np.testing.assert_allclose(with_app.loglik(maps, states), plain.loglik(maps, states) + extra, atol=1e-9)
    assert np.argmax(extra) == 0  # the appearance term peaks at the learned plate


@pytest.mark.parametrize("compiled", [False, True])
def test_the_first_view_anchors_the_adaptation(compiled):
    """A template that has drifted onto the road adapts on to it without an anchor; with the first view as
    anchor (the plate model's ``anchor_min_ncc`` 0.5) the road does not match the first plate: no adaptation."""
    from vistrack import kernels
    from vistrack.appearance.cues import Appearance

    img = draw_plate(road(), 160, 120)
    box = (160 - PW / 2, 120 - PH / 2, PW, PH)
    elsewhere = np.array([60.0, 60.0, PW, PH])  # road texture, (cx, cy, w, h)
    with kernels.numpy_paths(not compiled):
        for anchor, adapted in ((None, True), (0.5, False)):
            app = Appearance(img, box, anchor_min_ncc=anchor)
            obs = app.frame(img, app.roi(elsewhere[None], 20))
            app.template = app.patches(obs, elsewhere[None])[0]  # drifted: the current template is the road's
            assert app.anchor_ncc(obs, elsewhere) < 0.5
            assert app.adapt(obs, elsewhere) is adapted
    assert model_from_box("plate", img, box).app.anchor_min_ncc == 0.5


def _rendered_plate_scene(cx, cy, width=120):
    """A rendered single-row plate (``width`` px) on the road at ``(cx, cy)``, BGR uint8 320 x 240 -> 480 x 360."""
    from vistrack.data_synth.plate_clip import render_plate
    from vistrack.models.plate.layout import LAYOUTS

    img = cv2.resize(road(3), (480, 360)).astype(np.float32)
    plate = cv2.resize(render_plate(LAYOUTS["single-row"], np.random.default_rng(4), 240), None, fx=width / 240,
                       fy=width / 240, interpolation=cv2.INTER_AREA)
    h, w = plate.shape[:2]
    x0, y0 = int(cx - w / 2), int(cy - h / 2)
    img[y0:y0 + h, x0:x0 + w] = plate
    return img.astype(np.uint8), (x0, y0, w, h)


@pytest.mark.parametrize("detector", [False, True])
def test_a_plate_lost_to_a_jump_is_found_again(detector):
    """The plate jumps 150 px (a cut, a shaken camera) out of the dynamics' reach: a plate model from a box
    has no births, so without its detector it stays lost; with it, the next step's births sit at the
    re-detected plate (Plate.redetect) and the track is back on it and reported."""
    frames, boxes = zip(*([_rendered_plate_scene(140, 250)] * 4 + [_rendered_plate_scene(300, 120)] * 8))
    trk = vistrack.Tracker(model="plate", algo="lis", particles=100, seed=1, layout="single-row")
    trk.init(frames[0], boxes[0])
    assert trk.model.detector is not None
    if not detector:
        trk.model.detector = None
    for f in frames[1:]:
        ok, (x, y, w, h) = trk.update(f)
    bx, by, bw, bh = boxes[-1]
    near = np.hypot(x + w / 2 - (bx + bw / 2), y + h / 2 - (by + bh / 2)) < 4
    assert bool(ok and near) is detector


def test_the_correlation_filter_term_peaks_at_the_moved_plate():
    """The box model's correlation filter, learned with the plate's appearance (``Plate.cf``): on the next
    frame, with the plate moved by (6, -3) px, its response over the search region about the particles'
    prediction peaks at the moved plate (within one of its cells, 2.3 px here), and ``log r`` has the term
    ``λ_dcf y`` read at the state's centre and width (``Plate.dcf_states``)."""
    from vistrack.core.particles import ParticleSet

    f0, b0 = _rendered_plate_scene(200, 180)
    f1, (x, y, w, h) = _rendered_plate_scene(206, 177)
    moved = np.array([x + w / 2, y + h / 2])
    model = model_from_box("plate", f0, b0, layout="single-row")
    assert model.cf is not None and model.lambda_dcf == 20.0
    start = np.tile(model.prior_mean, (4, 1))  # tracked at the first box, no velocity
    obs = model.observe(FeatureMaps(f1), ParticleSet(start))
    resp = obs.dcf
    cell = resp.cell_origin()[1]
    assert np.hypot(*(resp.peak_xy - moved)) <= cell, (resp.peak_xy, moved, cell)
    d = np.arange(-8, 9, 1.0)
    grid = np.tile(model.prior_mean, (len(d) ** 2, 1))
    grid[:, 0] = moved[0] + np.repeat(d, len(d))
    grid[:, 1] = moved[1] + np.tile(d, len(d))
    y = resp.read(model.dcf_states(grid))
    assert np.hypot(*(grid[np.argmax(y), :2] - moved)) <= cell
    assert y.max() > 0.5 and y.min() < 0.5 * y.max()  # a peak, not a plateau
    ll = model.loglik(obs, grid)
    obs.dcf = None  # the same frame without the filter's term
    np.testing.assert_allclose(ll - model.loglik(obs, grid), 20.0 * y, atol=1e-9)


def test_the_line_scans_draw_with_the_correlation_filter_term():
    """The LIS line scans' map (``PlateLISProposal.appearance_map``) holds the filter's term ``λ_dcf y`` of
    ``log r`` beside the appearance's: the map with the response minus the map without it is ``λ_dcf`` times
    the response read at the map pixels' frame positions."""
    from vistrack.core.particles import ParticleSet
    from vistrack.models.plate.proposal import PlateLISProposal, map_values

    f0, b0 = _rendered_plate_scene(200, 180)
    f1, _ = _rendered_plate_scene(206, 177)
    model = model_from_box("plate", f0, b0, layout="single-row")
    x = np.tile(model.prior_mean, (4, 1))
    obs = model.observe(FeatureMaps(f1), ParticleSet(x))
    prop = PlateLISProposal(model)
    half = np.tile([12.0, 8.0], (4, 1))
    with_dcf = prop.appearance_map(obs, x, x[:, :2], half)
    resp, obs.dcf = obs.dcf, None
    without = prop.appearance_map(obs, x, x[:, :2], half)
    m, a = with_dcf
    np.testing.assert_allclose(a, without[1])
    j, i = np.meshgrid(np.arange(m.shape[1], dtype=float), np.arange(m.shape[0], dtype=float))
    px, py = (j - a[1]) / a[0], (i - a[3]) / a[2]  # the map pixels' frame positions
    at = np.stack([px.ravel(), py.ravel(), np.zeros(px.size)], axis=1)
    y = resp.read(at).reshape(m.shape)
    np.testing.assert_allclose(m - without[0], model.lambda_dcf * y, atol=1e-4)
    assert y.max() > 0.5  # the plate is in the map's span: the term is not zero
    # read as the scans read it: at a frame point between pixels, bilinear in both
    np.testing.assert_allclose(map_values(with_dcf, 206.3, 177.6) - map_values(without, 206.3, 177.6),
                               map_values((np.float32(model.lambda_dcf) * y.astype(np.float32), a), 206.3, 177.6),
                               atol=1e-3)
