"""The neural-network local search of LS-N-IPS (thesis 001 §4.3.1, Fig. 4.5; vistrack.models.contour.nn)."""

import cv2
import numpy as np
import pytest

from vistrack.appearance.features import FeatureMaps
from vistrack.models.contour import nn
from vistrack.models.contour.model import Contour, ellipse_template, pose_from
from vistrack.registry import make_filter

SIZE = (240, 180)
NOISELESS = nn.NNSearchConfig(samples=3000, hidden=(32,), epochs=60, noise=0.0, miss=0.0, clutter=0.0)


def model(**kw):
    return Contour(ellipse_template(60, 36, n=12), (120, 90, 0, 0), SIZE, **kw)


@pytest.fixture(scope="module")
def noiseless_net():
    return nn.train(model(), NOISELESS)


def brute_offsets(m, z, zt):
    """Offsets (px) along the support-point normals of pose z where the contour of pose zt crosses
    them, in image coordinates (a dense polygon, one line at a time); NaN where none within l0·s."""
    poly = m.outline(zt[None], per_segment=64)[0]
    o, d = m.support_points(z[None])[0], m.normals(z[None])[0]
    reach = m.search_length * np.hypot(1 + z[2], z[3])
    out = np.full(m.n, np.nan)
    for i in range(m.n):
        a, b = poly - o[i], np.roll(poly, -1, axis=0) - o[i]
        sa, sb = a[:, 1] * d[i, 0] - a[:, 0] * d[i, 1], b[:, 1] * d[i, 0] - b[:, 0] * d[i, 1]
        for k in np.nonzero((sa * sb <= 0) & (sa != sb))[0]:
            u = (a[k] + sa[k] / (sa[k] - sb[k]) * (b[k] - a[k])) @ d[i]
            if abs(u) <= reach:
                out[i] = u
    return out


@pytest.mark.slow
def test_noiseless_measurements_give_the_pose(noiseless_net):
    """Trained on noiseless simulated measurements, the network recovers Δ = Z' - Z_0 on fresh
    poses within λ: mean error under 5 % of λ on every coordinate (rotation: 12 %)."""
    m = model()
    x, delta = nn.simulate(m, nn.NNSearchConfig(samples=1000, noise=0.0, miss=0.0, clutter=0.0, seed=7),
                           np.random.default_rng(7))
    err = np.mean(np.abs(noiseless_net.predict(x) - delta), axis=0) / m.search_lambda
    assert np.all(err[:3] < 0.05) and err[3] < 0.12, err


def test_normal_pose_trick_matches_the_actual_pose(rng):
    """Measured at a translated, rotated and scaled pose Z in image coordinates and normalised by
    its scale, the inputs equal those at the normal pose Z_0 for the same relative pose Δ (to 0.1 px,
    the simulation's polygon of 4 chords per spline segment against 64 here): the
    training set (so the network) is the one training at Z would give."""
    m = model()
    z = pose_from(150.0, 100.0, 1.3, 20.0)
    delta = rng.uniform(-1, 1, (20, 4)) * m.search_lambda
    at_z0 = nn.intersections(m, delta, rng)
    at_z = np.array([brute_offsets(m, z, zt) for zt in nn.compose(np.tile(z, (20, 1)), delta)]) / 1.3
    np.testing.assert_array_equal(np.isnan(at_z), np.isnan(at_z0))
    np.testing.assert_allclose(at_z[~np.isnan(at_z)], at_z0[~np.isnan(at_z0)], atol=0.1)  # 4 chords per segment
    np.testing.assert_allclose(nn.relative(np.tile(z, (20, 1)), nn.compose(np.tile(z, (20, 1)), delta)), delta,
                               atol=1e-12)


def ellipse_frame(zt):
    m = model()
    img = np.full((SIZE[1], SIZE[0]), 50, np.uint8)
    pts = np.round(m.outline(zt[None], 16)[0] * 16).astype(np.int32)
    cv2.fillPoly(img, [pts], 200, cv2.LINE_AA, shift=4)
    return FeatureMaps(cv2.cvtColor(img, cv2.COLOR_GRAY2BGR))


def test_search_on_an_image_at_a_moved_pose(noiseless_net, rng):
    """Fig. 4.5 on a frame: predictions around a translated/rotated/scaled truth move to it
    (median centre error under 1 px), within λ, and never lower r (eq. 4.1)."""
    m = model(search="nn")
    m.nn_search = noiseless_net
    truth = pose_from(110.0, 95.0, 1.2, 25.0)
    obs = ellipse_frame(truth)
    z = nn.compose(np.tile(truth, (30, 1)), rng.uniform(-0.6, 0.6, (30, 4)) * m.search_lambda / 1.2)
    x = np.concatenate([z, z], axis=1)
    out, ll = m.local_search(obs, x)
    after, before = (np.hypot(s[:, 0] - truth[0], s[:, 1] - truth[1]) for s in (out, x))
    assert np.median(after) < 1.0 and np.mean(after) < np.mean(before) / 3, (after, before)
    assert np.all(np.abs(out[:, :4] - x[:, :4]) <= m.search_lambda + 1e-9)
    assert np.all(ll >= m.loglik(obs, x) - 1e-9)
    np.testing.assert_allclose(ll, m.loglik(obs, out))


@pytest.fixture(scope="module")
def small_clip(synth_clip):
    return synth_clip("contour", frames=10, size=(160, 120), seed=4, clutter="low", distractor=False)


def test_same_seed_same_network_and_track(small_clip):
    from vistrack.io.clips import load_clip
    from vistrack.loop import Stepper
    from vistrack.registry.builders import build_model

    cfg = nn.NNSearchConfig(samples=400, epochs=5)
    clip = load_clip(small_clip)
    frames = list(clip.source)[:10]
    base = build_model("contour", clip, init_gt="")
    a, b = nn.train(base, cfg), nn.train(base, cfg)
    for u, v in zip(a.coefs + a.intercepts, b.coefs + b.intercepts):
        np.testing.assert_array_equal(u, v)
    assert not np.array_equal(nn.train(base, nn.NNSearchConfig(samples=400, epochs=5, seed=1)).coefs[0], a.coefs[0])

    def run():
        m = build_model("contour", clip, init_gt="")
        m.nn_search = a
        return np.array([r.estimate for r in Stepper(make_filter("ls-n-ips-nn", m), 15,
                                                     np.random.default_rng(3)).steps(frames)])

    np.testing.assert_array_equal(run(), run())


def test_missing_or_corrupt_cache_is_rebuilt(tmp_path, monkeypatch):
    monkeypatch.setenv("VISTRACK_CACHE", str(tmp_path))
    m, cfg = model(), nn.NNSearchConfig(samples=300, epochs=3)
    path = nn.cache_path(m, cfg)
    assert path.parent == tmp_path / "nn-search"
    net, info = nn.load_or_train(m, cfg)
    assert info["trained"] and path.is_file()
    again, info = nn.load_or_train(m, cfg)
    assert not info["trained"]
    np.testing.assert_array_equal(again.coefs[0], net.coefs[0])
    heard = []
    for junk in (b"not a zip", path.read_bytes()[:100]):
        path.write_bytes(junk)
        rebuilt, info = nn.load_or_train(m, cfg, notify=heard.append)
        assert info["trained"]
        np.testing.assert_array_equal(rebuilt.coefs[0], net.coefs[0])
        assert nn.NNSearch.load(path, nn.cache_key(m, cfg)).coefs[0].shape == net.coefs[0].shape
    assert "not a usable network" in heard[0] and heard[1].startswith("training")
    with pytest.raises(ValueError, match="another template"):
        nn.NNSearch.load(path, "other")


def test_options_are_checked():
    with pytest.raises(ValueError, match="choose lms or nn"):
        model(search="cnn")
    from vistrack.models.box.model import Box

    assert "ls-n-ips-nn" in __import__("vistrack.registry", fromlist=["ALGORITHMS"]).ALGORITHMS
    with pytest.raises(ValueError, match=r"ls-n-ips-nn \(a learned local search\) needs a model with searcher"):
        make_filter("ls-n-ips-nn", Box.__new__(Box))


def test_cli_train_search(tmp_path, monkeypatch, capsys):
    from cli_helpers import run

    monkeypatch.setenv("VISTRACK_CACHE", str(tmp_path / "cache"))
    tmpl = tmp_path / "t.txt"
    tmpl.write_text("\n".join(f"{x:.3f} {y:.3f}" for x, y in ellipse_template(40, 30, 8)))
    code, out, err = run(["train-search", "--template", str(tmpl), "--samples", "200"], capsys)
    assert code == 0 and out.startswith("trained in ") and str(tmp_path / "cache" / "nn-search") in out, err
    code, out, _ = run(["train-search", "--template", str(tmpl), "--samples", "200"], capsys)
    assert code == 0 and out.startswith("already trained: ")
    code, _, err = run(["train-search", "--template", str(tmp_path / "none.txt")], capsys)
    assert code == 1 and err.strip() == f"Error: template file {tmp_path / 'none.txt'} does not exist"
