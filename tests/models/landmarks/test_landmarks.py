"""Landmark shape model and filters of seed 000: geometry, Laplace derivatives, proper weighting, recovery."""

import numpy as np
import pytest

from vistrack.data_synth.landmark_clip import observe, simulate
from vistrack.models.landmarks.model import Landmarks, regular_polygon, shape_step, tangent_basis
from vistrack.registry import make_filter
from vistrack.reproduce.landmarks import LandmarksConfig, landmarks_run, run_landmarks


def paper_gram_schmidt(u_prev, z_prev):
    """The recursion of §3.1 literally, one particle, columns in order (normalised)."""
    k, m = u_prev.shape
    u = np.zeros_like(u_prev)
    for j in range(m):
        proj = np.eye(k) - np.outer(z_prev, z_prev.conj())
        for i in range(j):
            proj -= np.outer(u[:, i], u[:, i].conj())
        v = proj @ u_prev[:, j]
        u[:, j] = v / np.linalg.norm(v)
    return u


@pytest.fixture(scope="module")
def moved():
    """Particles after 15 random steps of the K = 8 model: varied shapes and bases."""
    model = Landmarks(8, sigma_c=0.003)
    rng = np.random.default_rng(0)
    x = model.sample_prior(30, rng)
    for _ in range(15):
        x = model.predict(x, rng)
    return model, x


def test_basis_is_orthonormal_and_tangent(moved):
    model, x = moved
    _, _, _, z, u = model.unpack(x)
    u_new = tangent_basis(u, z)
    gram = np.einsum("nki,nkj->nij", u_new.conj(), u_new)
    assert np.allclose(gram, np.eye(model.k - 2), atol=1e-12)
    assert np.allclose(np.einsum("nk,nkm->nm", z.conj(), u_new), 0, atol=1e-12)  # ⟂ z
    assert np.allclose(u_new.sum(axis=1), 0, atol=1e-12)  # ⟂ 1_K
    for i in range(3):  # the batched QR is the paper's Gram–Schmidt
        assert np.allclose(u_new[i], paper_gram_schmidt(u[i], z[i]), atol=1e-10)


def test_shape_step_stays_on_the_centred_unit_sphere(moved):
    model, x = moved
    _, _, c, z, u = model.unpack(x)
    assert np.allclose(np.linalg.norm(z, axis=1), 1, atol=1e-12)
    assert np.allclose(z.sum(axis=1), 0, atol=1e-12)
    c_big = np.random.default_rng(1).normal(0, 0.2, c.shape)
    z2 = shape_step(z, tangent_basis(u, z), c_big)
    assert np.allclose(np.linalg.norm(z2, axis=1), 1, atol=1e-12)
    assert not np.allclose(z2, z)
    assert np.allclose(np.linalg.norm(regular_polygon(5)), 1)


@pytest.mark.parametrize("free", ["c", "all"])
def test_laplace_gradient_hessian_and_mode_match_finite_differences(moved, free):
    model, prev = moved
    prev = prev[:6]
    rng = np.random.default_rng(2)
    y = observe(model, model.configuration(model.predict(prev[:1], rng))[0], rng)
    s, th = model.sample_motion(prev, rng)
    c = model.c_prior_mean(prev) + rng.normal(0, 0.02, (6, model.dc))
    motion = (s, th) if free == "c" else None
    x = c if free == "c" else np.column_stack([s, th, c])

    def obj(v):
        return model.objective(y, prev, v, free=free, motion=motion, derivs=False)

    _, grad, hess, gn = model.objective(y, prev, x, free=free, motion=motion)
    eps = 1e-6
    for d in range(x.shape[1]):
        e = np.zeros(x.shape[1])
        e[d] = eps
        fd = (obj(x + e) - obj(x - e)) / (2 * eps)
        assert np.allclose(grad[:, d], fd, rtol=1e-5, atol=1e-6 * np.abs(grad).max())
        g_p = model.objective(y, prev, x + e, free=free, motion=motion)[1]
        g_m = model.objective(y, prev, x - e, free=free, motion=motion)[1]
        assert np.allclose(hess[:, :, d], (g_p - g_m) / (2 * eps), rtol=1e-4, atol=1e-6 * np.abs(hess).max())
    assert np.all(np.linalg.eigvalsh(gn) > 0)
    mode, h_mode, _ = model.laplace(y, prev, free=free, motion=motion)
    _, g_mode, _, _ = model.objective(y, prev, mode, free=free, motion=motion)
    scale = np.sqrt(np.diagonal(np.linalg.inv(h_mode), axis1=1, axis2=2))
    assert np.all(np.abs(g_mode) * scale < 1e-5)  # stationary, in units of the proposal's spread
    assert np.all(np.linalg.eigvalsh(h_mode) > 0)
    for _ in range(5):  # and a minimum
        step = rng.normal(0, 0.5, mode.shape) * scale
        assert np.all(obj(mode + step) >= obj(mode))


@pytest.mark.slow
def test_laplace_proposals_are_properly_weighted():
    """One step from a fixed X_{t-1}: the mean weight estimates p(Y_t | X_{t-1}) for every algorithm."""
    model = Landmarks(5)
    rng = np.random.default_rng(3)
    states, obs = simulate(model, 3, rng)
    y = obs[2]
    estimates = {}
    for algo, n in [("pf-gordon", 400_000), ("pf-eis", 40_000), ("pf-doucet", 40_000)]:
        filt = make_filter(algo, model)
        prev = np.repeat(states[2:3], n, axis=0)
        _, log_incr, _, _ = filt.propose(prev, y, np.random.default_rng(4), filt.kernel)
        w = np.exp(log_incr - log_incr.max())
        estimates[algo] = (np.log(w.mean()) + log_incr.max(), w.std() / w.mean() / np.sqrt(n))
    ref, ref_se = estimates["pf-gordon"]
    for algo in ("pf-eis", "pf-doucet"):
        est, se = estimates[algo]
        assert abs(est - ref) < 4 * np.hypot(se, ref_se) + 0.01, (algo, est, ref)
    # coefficient of variation of the weights: the Laplace proposals waste fewer particles than the prior
    cv = {a: se * np.sqrt(n) for (a, (_, se)), n in zip(estimates.items(), (400_000, 40_000, 40_000))}
    assert cv["pf-doucet"] < 0.5 * cv["pf-gordon"] and cv["pf-eis"] < cv["pf-gordon"], cv


@pytest.mark.parametrize("algo", ["pf-gordon", "pf-doucet", "pf-eis", "pf-eis-mt"])
def test_filters_recover_a_known_configuration_without_clutter(algo):
    model = Landmarks(5, p=0.0, sigma2_o=1e-4, sigma2_theta=0.01, sigma_c=1e-4)
    states, obs = simulate(model, 12, np.random.default_rng(5))
    n = 400 if algo == "pf-gordon" else 30
    est = landmarks_run(model, make_filter(algo, model), obs, n, np.random.default_rng(6))
    truth = model.configuration(states[1:])
    err = np.sqrt(np.mean(np.abs(est - truth) ** 2, axis=1))  # rms per landmark
    assert err[-4:].max() < 0.02, err  # noise sd 0.01, landmarks 0.45 from the centre
    blind = np.sqrt(np.mean(np.abs(model.configuration(states[:1]) - truth) ** 2, axis=1))
    assert blind[-4:].min() > 3 * err[-4:].max()  # it tracked a configuration that did move


@pytest.mark.slow
def test_same_seed_same_output_and_eis_beats_gordon():
    cfg = dict(k=5, runs=6, steps=15, seed=11, algos=["pf-eis", "pf-gordon"])
    a = run_landmarks(LandmarksConfig(**cfg))["results"]
    b = run_landmarks(LandmarksConfig(**cfg))["results"]
    assert [r["mse_per_step"] for r in a] == [r["mse_per_step"] for r in b]
    mse = {r["algo"]: r["mean_mse"] for r in a}
    assert mse["pf-eis"] < mse["pf-gordon"]


def test_model_rejects_bad_parameters():
    with pytest.raises(ValueError, match="K >= 3"):
        Landmarks(2)
    with pytest.raises(ValueError, match="clutter probability"):
        Landmarks(5, p=1.0)
    with pytest.raises(ValueError, match="mt_dims"):
        make_filter("pf-eis-mt", Landmarks(5), mt_dims=6)
    with pytest.raises(ValueError, match="--k must be 5 or 8"):
        LandmarksConfig(k=6)


def test_reproduce_landmarks_cli_json_plot_and_resume(tmp_path, capsys):
    import json

    import matplotlib.image as mpimg

    from vistrack.cli import main

    def cli(argv):
        with pytest.raises(SystemExit) as e:
            main(argv)
        out = capsys.readouterr()
        return e.value.code, out.out, out.err

    base = ["reproduce", "landmarks", "--k", "8", "--runs", "3", "--steps", "6", "--seed", "2", "-q", "--in-process",
            "--workers", "2", "--out", str(tmp_path / "res")]
    code, out, err = cli(base + ["--json", str(tmp_path / "a.json"), "--plots", str(tmp_path / "p")])
    assert code == 0, err
    assert "pf-eis-mt" in out and "mean MSE" in out
    data = json.loads((tmp_path / "a.json").read_text())
    assert set(data) == {"config", "results"} and data["config"]["k"] == 8 and data["config"]["mt_dims"] == 10
    assert [r["algo"] for r in data["results"]] == ["pf-eis-mt", "pf-eis", "pf-gordon"]
    for r in data["results"]:
        assert {"algo", "particles", "k", "mse_per_step", "mean_mse", "ms_per_run"} <= set(r)
        assert r["particles"] == 20 and len(r["mse_per_step"]) == 6 and r["mean_mse"] > 0
    png = tmp_path / "p" / "mse_vs_time.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and mpimg.imread(png).shape[0] > 100
    # an interrupted reproduction resumed gives the same numbers
    tasks = sorted((tmp_path / "res" / "tasks").glob("*.json"))
    assert len(tasks) == 3
    tasks[1].unlink()
    code, _, err = cli(base + ["--resume", "--json", str(tmp_path / "b.json")])
    assert code == 0, err

    def strip(d):
        return [{k: v for k, v in r.items() if k != "ms_per_run"} for r in d["results"]]

    assert strip(json.loads((tmp_path / "b.json").read_text())) == strip(data)
    code, _, err = cli(["reproduce", "landmarks", "--algos", "lis", "-q"])
    assert code != 0 and "unknown algorithm 'lis' for landmarks" in err
