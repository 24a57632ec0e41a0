"""Learning the coefficients of the plate likelihood's terms (thesis 001, §1.3.2).

The thesis's likelihood is a weighted sum of pixel-set means (Table 1.1) and
notes that it "could be further refined by e.g. learning coefficients for each
of the terms". This module does that on synthetic road clips: the pixel-set means of
:meth:`~vistrack.models.plate.model.PlateLikelihood.features` at true plate poses
(jittered within tracking accuracy) are positives; negatives are random poses,
near misses (shifted by 0.15–1 plate size or rescaled by up to ±35 %) and hard
negatives — the best-scoring poses of a dense scan of each frame away from the
plate, mined with the current weights and added in rounds. A class-balanced,
L2-regularised logistic regression gives ``log r = w · φ + b``: the log-odds
that a plate lies at the pose, so ``log r > 0`` is the visibility decision.
The features are ``log(1 + mean)``, which keeps very strong edges (headlights,
sign borders) from outweighing the characters.

With ``--scales S0,S1`` the coefficients are scale-banded: one set at plate width
``S0`` px and one at ``S1``, interpolated in log s (:func:`design`). The DoGs and
Sobel filters have a fixed size in pixels, so a pixel set's mean on a 35-px plate
is not the same feature as on an 80-px one: a single set fitted on both sizes
let text signs at 640×480 score like plates, one fitted at 640×480 alone scored
35-px plates below 0.

    python -m vistrack.models.plate.fitting --layout jp --clips CLIPS_DIR --scales 40,80
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy import optimize

from ...appearance.features import FeatureMaps
from ...io.clips import load_clip
from .layout import LAYOUTS
from .model import PlateLikelihood, scale_band

__all__ = ["feature_likelihood", "truth_poses", "training_samples", "scan_poses", "design", "split_weights",
           "fit_logistic", "fit_weights"]


def truth_poses(truth, i):
    """The true pose ``(u, w, θ, s)`` of frame ``i``, or ``None`` when no plate is in view."""
    if not truth["visible"][i] > 0:
        return None
    return np.array([truth["cx"][i], truth["cy"][i], np.deg2rad(truth["angle_deg"][i]), truth["scale"][i]])


def scan_poses(size, step=8, scales=(0.05, 0.065, 0.08, 0.1, 0.125, 0.15, 0.19, 0.24, 0.3)):
    """A dense grid of upright poses over the frame (``step`` px, widths ``scales × W``)."""
    w, h = size
    u, v = np.meshgrid(np.arange(step / 2, w, step), np.arange(step / 2, h, step))
    out = []
    for s in scales:
        out.append(np.column_stack([u.ravel(), v.ravel(), np.zeros(u.size), np.full(u.size, s * w)]))
    return np.concatenate(out)


def _far(poses, pose):
    """Poses not within half a plate of ``pose`` or with a scale more than 30 % off."""
    if pose is None:
        return np.ones(len(poses), bool)
    s = pose[3]
    near = (np.abs(poses[:, 0] - pose[0]) < 0.5 * s) & (np.abs(poses[:, 1] - pose[1]) < 0.25 * s)
    return ~near | (np.abs(np.log(poses[:, 3] / s)) > np.log(1.3))


def feature_likelihood(layout):
    """A :class:`PlateLikelihood` whose :meth:`~PlateLikelihood.features` has every pixel set of the
    layout, Table 1.1's and the extra ones (the coefficients are what is being fitted)."""
    lay = LAYOUTS[layout] if isinstance(layout, str) else layout
    names = PlateLikelihood.BASE_FEATURES + tuple(e[0] for e in lay.extra)
    return PlateLikelihood(lay, weights=(dict.fromkeys(names, 1.0), 0.0))


def design(f, s, scales=None):
    """The regression's inputs from features ``f (M, F)`` at plate widths ``s (M,)``: ``f`` itself,
    or with scale-banded weights (``scales = (s_0, s_1)``) ``[(1 - a) f, a f, a]`` with
    ``a`` from :func:`~vistrack.models.plate.model.scale_band` — a linear model whose coefficients are
    interpolated in log s between their values at ``s_0`` and ``s_1``."""
    if scales is None:
        return f
    a = scale_band(s, scales)[:, None]
    return np.column_stack([(1 - a) * f, a * f, a])


def split_weights(w, b, n_features, scales=None):
    """``(coef (F,) or (2, F), bias float or (2,))`` from the regression's ``(w, b)`` (see :func:`design`)."""
    if scales is None:
        return w, b
    return np.stack([w[:n_features], w[n_features:2 * n_features]]), np.array([b, b + w[-1]])


def training_samples(clips, layout, rng, *, every=6, weights=None, hard_per_frame=20, scales=None):
    """Regression inputs ``X`` (:func:`design` of every feature of :func:`feature_likelihood`,
    ``log(1 + mean)`` as the likelihood uses them), labels ``y (M,)``
    and sample kinds from the clip folders ``clips``.

    With ``weights`` (``(w, b)`` on ``X``), each frame also gives its ``hard_per_frame``
    best-scoring poses of :func:`scan_poses` away from the plate as negatives.
    """
    lik = feature_likelihood(layout)
    xs, ys, kinds = [], [], []

    def feats(maps, poses):
        return design(np.log1p(lik.features(maps, poses)), poses[:, 3], scales)

    def add(x, label, kind):
        xs.append(x)
        ys.append(np.full(len(x), label))
        kinds.append(np.full(len(x), kind))

    for path in clips:
        clip = load_clip(path)
        size = clip.source.size
        grid = scan_poses(size)
        for i, frame in clip.source:
            if i % every:
                continue
            maps = FeatureMaps(frame)
            pose = truth_poses(clip.truth, i)
            n = 40
            rnd = np.column_stack([rng.uniform(0, size[0], n), rng.uniform(0, size[1], n), rng.normal(0, 0.1, n),
                                   rng.uniform(0.05, 0.3, n) * size[0]])
            add(feats(maps, rnd[_far(rnd, pose)]), 0, "random")
            if pose is not None:
                s = pose[3]
                pos = np.tile(pose, (10, 1))
                pos[:, 0] += rng.normal(0, 0.01 * s, 10)
                pos[:, 1] += rng.normal(0, 0.005 * s, 10)
                pos[:, 3] *= 1 + rng.normal(0, 0.01, 10)
                add(feats(maps, pos), 1, "plate")
                m = 20
                near = np.tile(pose, (m, 1))
                ang, r = rng.uniform(0, 2 * np.pi, m), rng.uniform(0.15, 1.0, m)
                near[:, 0] += r * s * np.cos(ang)
                near[:, 1] += r * s / 2 * np.sin(ang)
                near[:, 3] *= np.exp(rng.uniform(-0.35, 0.35, m))
                add(feats(maps, near), 0, "near")
            if weights is not None:
                g = grid[_far(grid, pose)]
                f = feats(maps, g)
                top = np.argsort(-(f @ weights[0]))[:hard_per_frame]
                add(f[top], 0, "hard")
    return np.concatenate(xs), np.concatenate(ys), np.concatenate(kinds)


def fit_logistic(x, y, lam=1e-3):
    """Class-balanced L2 logistic regression on standardised features; returns ``(w, b)``
    in the original units (log-odds ``x · w + b``)."""
    mu, sd = x.mean(axis=0), np.maximum(x.std(axis=0), 1e-9)
    a = np.column_stack([(x - mu) / sd, np.ones(len(x))])
    sw = np.where(y == 1, (y == 0).sum() / max((y == 1).sum(), 1), 1.0)

    def f(beta):
        z = a @ beta
        loss = np.where(y == 1, np.logaddexp(0, -z), np.logaddexp(0, z))
        grad = a.T @ (sw * (1 / (1 + np.exp(-z)) - y)) / len(y)
        reg = np.r_[beta[:-1], 0.0]
        return (sw * loss).mean() + lam * reg @ reg, grad + 2 * lam * reg

    beta = optimize.minimize(f, np.zeros(a.shape[1]), jac=True, method="L-BFGS-B").x
    w = beta[:-1] / sd
    return w, float(beta[-1] - mu @ w)


def fit_weights(clips, layout, *, rounds=2, seed=0, every=6, scales=None):
    """Fit, then refit ``rounds`` times with hard negatives mined by the current weights.
    Returns ``(w, b)`` on :func:`design`'s inputs and the samples."""
    rng = np.random.default_rng(seed)
    x, y, kinds = training_samples(clips, layout, rng, every=every, scales=scales)
    w = fit_logistic(x, y)
    for _ in range(rounds):
        xh, yh, kh = training_samples(clips, layout, rng, every=every, weights=w, scales=scales)
        hard = kh == "hard"
        x, y, kinds = np.concatenate([x, xh[hard]]), np.concatenate([y, yh[hard]]), np.concatenate([kinds, kh[hard]])
        w = fit_logistic(x, y)
    return w, (x, y, kinds)


def fit_plate_coefficients(clips_dir, layout="jp", *, rounds=2, scales=None):
    """Fit the plate likelihood's term coefficients on the plate clips under ``clips_dir``
    (folders with ``groundtruth.csv``): :func:`fit_weights`, split per feature.

    Returns
    -------
    dict
        ``names`` (the features), ``weights`` (one value per feature, or a ``(w_0, w_1)``
        pair with ``scales``), ``bias``, ``scales`` and ``samples``: per sample kind
        (``pos``, ``near``, ``far``, ``hard``) the count and the 1/50/99 % log-odds
        percentiles and the share scored above 0.
    """
    clips = sorted(p for p in Path(clips_dir).glob("[!.]*") if (p / "groundtruth.csv").is_file())
    if not clips:
        raise ValueError(f"{clips_dir}: no plate clip folders (with groundtruth.csv)")
    for c in clips:  # the plate vertices x0..y3 are what is fitted: other clips would fit nonsense
        if "x3" not in (c / "groundtruth.csv").read_text().partition("\n")[0].split(","):
            raise ValueError(f"{c} is not a plate clip (its groundtruth.csv has no plate vertices x0..y3): "
                             "make plate clips with vistrack synth plate")
    (w, b), (x, y, kinds) = fit_weights(clips, layout, rounds=rounds, scales=scales)
    score = x @ w + b
    samples = {str(k): {"n": int(np.sum(kinds == k)),
                        "log_odds_1_50_99": np.percentile(score[kinds == k], [1, 50, 99]).round(2).tolist(),
                        "above_0": float(np.mean(score[kinds == k] > 0))} for k in np.unique(kinds)}
    names = feature_likelihood(layout).FEATURES
    coef, bias = split_weights(w, b, len(names), scales)
    weights = dict(zip(names, coef)) if scales is None else dict(zip(names, zip(*coef)))
    return {"names": list(names), "weights": weights, "bias": bias, "scales": scales, "samples": samples}
