"""Synthetic road clips (issue 6 groundwork): ground truth is where the plate is."""

import numpy as np
import pytest

from vistrack.clips import load_clip
from vistrack.cli import main
from vistrack.models.plate_layout import LAYOUTS, plate_vertices


@pytest.fixture(scope="module")
def road(tmp_path_factory):
    out = tmp_path_factory.mktemp("road")
    with pytest.raises(SystemExit) as e:
        main(["synth", "plate", "--out", str(out), "--frames", "60", "--size", "320x240", "--cars", "2",
              "--seed", "3", "-q"])
    assert e.value.code == 0
    return out


def test_plate_truth_matches_the_rendered_plate(road):
    clip = load_clip(road)
    t = clip.truth
    assert clip.meta["model"] == "plate" and len(t["frame"]) == 60
    vis = np.flatnonzero(t["visible"] > 0)
    assert 10 < len(vis) < 60  # plates in view, and stretches without one
    assert np.all(np.isnan(t["cx"][t["visible"] == 0]))
    frames = dict(clip.source)
    lay = LAYOUTS["jp"]
    for k in vis[:: max(1, len(vis) // 5)]:
        pose = np.array([t["cx"][k], t["cy"][k], np.deg2rad(t["angle_deg"][k]), t["scale"][k]])
        v = plate_vertices(pose, lay.aspect)[0]
        np.testing.assert_allclose(v[:, 0], [t[f"x{i}"][k] for i in range(4)], atol=2e-3)
        # the white plate: bright inside (between the character rows), darker around
        gray = frames[k].mean(axis=2)
        inner = gray[int(pose[1] - 0.3 * pose[3] / lay.aspect), int(pose[0] - 0.3 * pose[3])]
        assert inner > 150


def test_synth_plate_bad_size(tmp_path, capsys):
    with pytest.raises(SystemExit) as e:
        main(["synth", "plate", "--out", str(tmp_path / "p"), "--size", "100x80"])
    assert e.value.code != 0 and "too small" in capsys.readouterr().err


def test_plate_likelihood_has_a_narrow_dominant_peak_at_the_plate(road):
    """Fig. 1.6: over a (u, w) grid at the true angle and scale, the maximum of r is at the
    true plate, and poses 15 % of the plate width away are far less likely."""
    from vistrack.features import FeatureMaps
    from vistrack.models.plate import PlateLikelihood

    clip = load_clip(road)
    t = clip.truth
    frames = dict(clip.source)
    lik = PlateLikelihood("jp")
    vis = np.flatnonzero(t["visible"] > 0)
    for k in vis[[len(vis) // 4, len(vis) // 2, 3 * len(vis) // 4]]:
        obs = FeatureMaps(frames[k])
        s, th = t["scale"][k], np.deg2rad(t["angle_deg"][k])
        du, dw = np.meshgrid(np.arange(-40, 41, 1.0), np.arange(-30, 31, 1.0))
        poses = np.stack([t["cx"][k] + du.ravel(), t["cy"][k] + dw.ravel(), np.full(du.size, th),
                          np.full(du.size, s)], axis=1)
        ll = lik.loglik(obs, poses)
        dist = np.hypot(du.ravel(), dw.ravel())
        assert dist[np.argmax(ll)] <= 0.08 * s + 1.5
        assert ll.max() - ll[dist > 0.15 * s].max() > 1.0


def test_plate_lis_proposal_is_a_proper_density_on_the_window():
    """§4.5.2 proposal q = q^h(W') q^v(U'|W') on the box window: E_q[1 / q(Z)] is the box's
    area (2 s) × (2 s / aspect) — q integrates to one and log q is exact. (A textured frame
    and a mild κ keep the importance estimate's variance small.)"""
    import cv2

    from vistrack.features import FeatureMaps
    from vistrack.models.plate import Plate

    g = np.random.default_rng(1)
    img = cv2.GaussianBlur((g.random((240, 320)) * 255).astype(np.uint8), (0, 0), 2)
    obs = FeatureMaps(cv2.cvtColor(img, cv2.COLOR_GRAY2BGR))
    model = Plate((320, 240), kappa=0.5)
    s = 50.0
    x = np.array([[160.0, 120.0, 0.05, s, 159.0, 119.0, 0.05, s]])
    xs = np.repeat(x, 3000, axis=0)
    z, log_alpha, log_q = type(model.lis_proposal())(model, cells=12).sample(xs, obs, np.random.default_rng(0))
    assert np.all(log_alpha == 0)
    area = (2 * s) * (2 * s / model.layout.aspect)
    assert np.mean(np.exp(-log_q)) == pytest.approx(area, rel=0.05)
    assert np.all(np.abs(z[:, 0] - 160) <= s + 1e-9) and np.all(np.abs(z[:, 1] - 120) <= s / 2 + 1e-9)
    np.testing.assert_array_equal(z[:, 2:], xs[:, 2:])  # only the translation moves


def test_plate_dynamics_entering_branch(rng):
    from vistrack.models.plate import Plate

    model = Plate((640, 480))
    prev = model.sample_prior(4000, rng)
    prev[:, 4:] -= 1.0  # moving plates
    new = model.predict(prev, rng)
    assert model.entering(new).mean() == pytest.approx(0.1, abs=0.02)
    lp = model.transition_logpdf(new, prev)
    assert np.all(np.isfinite(lp))
    moved = model.with_local(new, new[:, :2] + 5.0)
    np.testing.assert_array_equal(model.entering(moved), model.entering(new))


def test_run_plate_clip_default_model_writes_vertices(road, tmp_path, capsys):
    import csv

    track = tmp_path / "t.csv"
    with pytest.raises(SystemExit) as e:
        main(["run", str(road / "video.mp4"), "--algo", "lis", "-n", "20", "--max-frames", "6", "--track", str(track),
              "-q"])
    assert e.value.code == 0, capsys.readouterr().err
    with open(track, newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 6
    assert list(rows[0])[:8] == ["frame", "visible", "cx", "cy", "w", "h", "angle_deg", "scale"]
    assert {"x0", "y3", "ess", "ms"} <= set(rows[0]) and set(r["visible"] for r in rows) <= {"0", "1"}
