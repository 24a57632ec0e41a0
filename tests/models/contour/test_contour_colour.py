"""The contour model's colour term (real footage): learned inside the initial curve against
a band around it; on by default for colour video through ``model_from_box``."""

from __future__ import annotations

import cv2
import numpy as np

from vistrack.appearance.features import FeatureMaps, colour_bins
from vistrack.registry.builders import model_from_box

H, W = 200, 260
CX, CY, RX, RY = 130.0, 100.0, 30.0, 22.0


def frame(cx=CX, cy=CY, target=True, seed=0):
    """A textured green-grey background with a red ellipse at (cx, cy) (none when not ``target``)."""
    rng = np.random.default_rng(seed)
    noise = cv2.GaussianBlur(rng.normal(0, 1, (H, W)).astype(np.float32), (0, 0), 3)
    base = 110 + 300 * noise
    img = np.dstack([base * 0.8, base, base * 0.85]).clip(0, 255).astype(np.uint8)
    if target:
        cv2.ellipse(img, (int(cx), int(cy)), (int(RX), int(RY)), 0, 0, 360, (40, 50, 210), -1)
    return img


def box(cx=CX, cy=CY):
    return (cx - RX, cy - RY, 2 * RX, 2 * RY)


def poses(model, shifts):
    s = np.tile(model.prior_mean, (len(shifts), 1))
    s[:, :2] += shifts
    s[:, 4:6] += shifts
    return s


def test_label_counts_match_counting_pixels():
    img = frame()
    model = model_from_box("contour", img, box())
    labels = colour_bins(img)
    pts = np.array([[[3.2, 4.9], [3.7, 4.1], [-1.0, 5.0], [100.5, 60.5]], [[259.9, 199.9], [260.0, 10.0],
                                                                          [0.0, 0.0], [0.5, 0.5]]])
    counts = model._label_counts(labels, pts)
    expect = np.zeros_like(counts)
    for i, row in enumerate(pts):
        for x, y in row:
            if 0 <= x < W and 0 <= y < H:
                expect[i, labels[int(y), int(x)]] += 1
    np.testing.assert_array_equal(counts, expect)
    assert counts[0].sum() == 3 and counts[1].sum() == 3  # the points outside the frame are not counted


def test_colour_on_for_colour_video_off_for_grey_and_on_request():
    img = frame()
    assert model_from_box("contour", img, box()).colour is not None
    assert model_from_box("contour", cv2.cvtColor(img, cv2.COLOR_BGR2GRAY), box()).colour is None
    assert model_from_box("contour", img, box(), colour=False).colour is None


def test_colour_term_peaks_at_the_object_and_is_flat_without_it():
    img = frame(CX + 6, CY - 4)  # the object moved by (6, -4) since the first frame
    model = model_from_box("contour", frame(), box())
    g = np.arange(-16, 17, 2.0)
    shifts = np.stack(np.meshgrid(g, g), -1).reshape(-1, 2)
    ll = model.colour_loglik(FeatureMaps(img), poses(model, shifts)[:, :4])
    best = shifts[np.argmax(ll)]
    assert np.abs(best - (6, -4)).max() <= 2
    # the same poses on the same background without the object: no colour to find
    flat = model.colour_loglik(FeatureMaps(frame(target=False)), poses(model, shifts)[:, :4])
    assert np.ptp(flat) < 0.2 * np.ptp(ll)
    # the grid form (LLS/LIS) is the pointwise form at the shifted poses (up to a sample point
    # that rounding puts on the other side of a pixel border)
    grid = model.colour_loglik(FeatureMaps(img), model.prior_mean[None, :4], shifts)[0]
    assert np.mean(np.isclose(grid, ll, atol=1e-9)) > 0.9
    np.testing.assert_allclose(grid, ll, atol=0.5)


def test_full_likelihood_adds_the_colour_term():
    img = frame(CX + 6, CY - 4)
    with_c = model_from_box("contour", frame(), box())
    edges = model_from_box("contour", frame(), box(), colour=False)
    obs = FeatureMaps(img)
    states = poses(with_c, np.array([[0.0, 0.0], [6.0, -4.0], [-10.0, 8.0]]))
    np.testing.assert_allclose(with_c.loglik(obs, states),
                               edges.loglik(obs, states) + with_c.colour_loglik(obs, states[:, :4]), atol=1e-9)


def test_run_no_colour_gives_the_edges_only_track_and_is_refused_for_the_box(tmp_path, capsys):
    """``vistrack run --model contour --no-colour`` is the edges-only model (the Python API with
    ``colour=False``); by default the colour term is on; ``--no-colour`` makes no sense on a box."""
    import vistrack
    from cli_helpers import run
    from vistrack.io.clips import read_groundtruth_csv
    from vistrack.io.video import open_video

    video = tmp_path / "clip.avi"
    wr = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"MJPG"), 25, (W, H))
    for t in range(8):
        wr.write(frame(CX + 3 * t, CY + t))
    wr.release()
    init = ",".join(f"{v:g}" for v in box())
    tracks = {}
    for flag in ([], ["--no-colour"]):
        code, _, err = run(["run", str(video), "--model", "contour", "--init", init, "--track",
                            str(tmp_path / "t.csv"), "-q", *flag], capsys)
        assert code == 0, err
        tracks[bool(flag)] = read_groundtruth_csv(tmp_path / "t.csv")["cx"]
    frames = [f for _, f in open_video(video)]
    t = vistrack.Tracker(model="contour", colour=False)
    t.init(frames[0], box())
    api = [t.result.estimate[0]] + [t.update(f) and t.result.estimate[0] for f in frames[1:]]
    np.testing.assert_allclose(tracks[True], api, atol=1e-3)
    assert not np.allclose(tracks[True], tracks[False])
    code, _, err = run(["run", str(video), "--init", init, "--no-colour"], capsys)
    assert code != 0 and "--no-colour is for the contour and plate models" in err
