"""Appendix D: product of Gaussians against numerical integration and the literal formula."""

import numpy as np
import pytest
from scipy import stats

from vistrack.core.gaussian import gaussian_product, gm_logpdf, mvn_logpdf


def test_mvn_logpdf_matches_scipy(rng):
    a = rng.standard_normal((2, 2))
    cov = a @ a.T + 0.5 * np.eye(2)
    x = rng.standard_normal((7, 2))
    mu = np.array([0.3, -1.0])
    assert mvn_logpdf(x, mu, cov) == pytest.approx(stats.multivariate_normal(mu, cov).logpdf(x))


def test_product_matches_numerical_integration():
    mu1, s1 = np.array([0.5, -0.2]), np.array([[0.4, 0.1], [0.1, 0.3]])
    mu2, s2 = np.array([-0.3, 0.4]), np.array([[0.2, -0.05], [-0.05, 0.5]])
    mu, cov, log_c = gaussian_product(mu1, s1, mu2, s2)
    g = np.linspace(-5, 5, 801)
    xx, yy = np.meshgrid(g, g, indexing="ij")
    pts = np.stack([xx, yy], -1)
    prod = np.exp(mvn_logpdf(pts, mu1, s1) + mvn_logpdf(pts, mu2, s2))
    da = (g[1] - g[0]) ** 2
    mass = prod.sum() * da
    assert np.exp(log_c) == pytest.approx(mass, rel=1e-6)
    m = np.einsum("ijk,ij->k", pts, prod) * da / mass
    d = pts - m
    c = np.einsum("ijk,ijl,ij->kl", d, d, prod) * da / mass
    assert mu == pytest.approx(m, abs=1e-6)
    assert cov == pytest.approx(c, abs=1e-6)


def test_product_matches_appendix_d_formula(rng):
    """Σ = (Σ1⁻¹+Σ2⁻¹)⁻¹, μ = ΣΣ1⁻¹μ1 + ΣΣ2⁻¹μ2, c = ((2π)^d|Σ1||Σ2|/|Σ|)^(-1/2) e^(-K/2)."""
    d = 3
    a, b = rng.standard_normal((d, d)), rng.standard_normal((d, d))
    s1, s2 = a @ a.T + np.eye(d), b @ b.T + 0.3 * np.eye(d)
    mu1, mu2 = rng.standard_normal(d), rng.standard_normal(d)
    i1, i2 = np.linalg.inv(s1), np.linalg.inv(s2)
    s = np.linalg.inv(i1 + i2)
    m = s @ i1 @ mu1 + s @ i2 @ mu2
    k = (mu1 - mu2) @ i1 @ s @ i2 @ (mu1 - mu2)
    c = ((2 * np.pi) ** d * np.linalg.det(s1) * np.linalg.det(s2) / np.linalg.det(s)) ** -0.5 * np.exp(-k / 2)
    mu, cov, log_c = gaussian_product(mu1, s1, mu2, s2)
    assert mu == pytest.approx(m)
    assert cov == pytest.approx(s)
    assert np.exp(log_c) == pytest.approx(c)


def test_gm_logpdf_is_log_of_weighted_sum():
    log_p = np.log([0.2, 0.8])
    mu = np.array([[0.0], [2.0]])
    cov = np.array([[[1.0]], [[0.25]]])
    x = np.array([[0.7], [-1.0]])
    expect = np.log(0.2 * stats.norm(0, 1).pdf(x[:, 0]) + 0.8 * stats.norm(2, 0.5).pdf(x[:, 0]))
    assert gm_logpdf(x, log_p, mu, cov) == pytest.approx(expect)


@pytest.mark.parametrize("m", [1, 2, 3])
def test_small_matrix_fast_paths_match_numpy(m, rng):
    from vistrack.core.gaussian import _cholesky, _inv_spd

    a = rng.standard_normal((5, m, m))
    s = a @ np.swapaxes(a, -1, -2) + 0.1 * np.eye(m)
    assert _cholesky(s) == pytest.approx(np.linalg.cholesky(s))
    assert _inv_spd(s) == pytest.approx(np.linalg.inv(s))


def test_diag_logpdf_matches_scipy_per_coordinate_and_per_row_std():
    from scipy import stats

    from vistrack.core.gaussian import diag_logpdf

    rng = np.random.default_rng(0)
    x, mean = rng.normal(size=(5, 3)), rng.normal(size=3)
    std = np.array([0.5, 2.0, 1.3])
    expect = stats.norm(mean, std).logpdf(x).sum(axis=1)
    np.testing.assert_allclose(diag_logpdf(x, mean, std), expect, rtol=1e-12)
    rows = rng.uniform(0.2, 3.0, size=(5, 3))
    np.testing.assert_allclose(diag_logpdf(x, mean, rows), stats.norm(mean, rows).logpdf(x).sum(axis=1), rtol=1e-12)
