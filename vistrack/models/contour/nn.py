"""The neural-network local search ``LS_λ`` of LS-N-IPS for contours (thesis 001, §4.3.1, Fig. 4.5).

Training (simulation, with the normal-pose trick)
    Poses ``Δ`` are drawn uniformly within ``λ`` of the normal pose ``Z_0 = 0`` (the template
    at the origin, scale 1). The contour of ``Δ`` is intersected with the normals of ``Z_0`` at
    its support points within the search length ``l0`` (one intersection at random where there
    are several); the measurement noise and clutter of the likelihood model act on them: the
    offset gets Gaussian noise (``noise``, default ``σ_edge``), with probability ``miss`` the edge
    is not detected, and with probability ``clutter`` a clutter feature uniform on the line is
    picked instead. Input: the offsets ``ν_i / l0`` along the normals and a flag per normal for
    a missing one; output: ``Δ / λ`` (each coordinate of equal importance, §4.3.2). A
    scikit-learn ``MLPRegressor`` (ReLU, Adam) learns the map in seconds.
Use (Fig. 4.5)
    For a predicted pose ``Z`` (scale ``s``), on each support-point normal the strongest edge
    feature within ``l0 · s`` (the likelihood's edge features); dividing its offset by ``s`` is
    the normalisation ``H`` with ``H Z = Z_0`` (a similarity keeps normals and scales offsets).
    The network's ``Δ̂`` is mapped back, ``Ẑ = Z ∘ Δ̂`` (:func:`compose`). Inference is a few
    matrix products over all particles in numpy. The contour model then rejects moves beyond
    ``λ`` and keeps a move only if it does not lower ``r`` (eq. 4.1), as for LMS.
Cache
    A trained network is kept as an ``.npz`` under ``$VISTRACK_CACHE`` (else
    ``$XDG_CACHE_HOME/vistrack``, else ``~/.cache/vistrack``) in ``nn-search/``, named by a hash
    of the template, the search parameters and the training options; a missing, corrupt or
    mismatched file is rebuilt.
"""

from __future__ import annotations

import hashlib
import os
import time
import warnings
import zipfile
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from ...io.outputs import replacing
from .spline import edge_peaks

__all__ = ["NNSearchConfig", "NNSearch", "compose", "relative", "intersections", "simulate", "train",
           "cache_path", "load_or_train", "network_for", "nn_candidates"]

#: bump when the features, targets or the file layout change (old cache files are then retrained)
VERSION = 1


@dataclass(frozen=True)
class NNSearchConfig:
    """Training options of the network (defaults: the shipped search)."""

    samples: int = 10000  #: simulated training poses
    hidden: tuple = (64,)  #: hidden layer sizes
    epochs: int = 30  #: passes of Adam over the data
    noise: float | None = None  #: edge position noise std (px at scale 1); None: the model's σ_edge
    miss: float = 0.1  #: probability that a normal has no edge (the likelihood's q)
    clutter: float = 0.25  #: probability that a clutter feature is picked instead of the edge
    seed: int = 0


def compose(z, d):
    """The pose of the similarity ``T_z ∘ T_d`` (``d`` relative to ``z``): ``(N, 4)``.

    With ``T_z(p) = c_z + w_z p`` in complex numbers, ``w_z = (1 + a) + i b``:
    ``c = c_z + w_z c_d``, ``w = w_z w_d``.
    """
    z, d = np.atleast_2d(z), np.atleast_2d(d)
    wz = (1 + z[:, 2]) + 1j * z[:, 3]
    c = z[:, 0] + 1j * z[:, 1] + wz * (d[:, 0] + 1j * d[:, 1])
    w = wz * ((1 + d[:, 2]) + 1j * d[:, 3])
    return np.stack([c.real, c.imag, w.real - 1, w.imag], axis=1)


def relative(z, zt):
    """``d`` with ``compose(z, d) = zt``: the pose ``zt`` seen from ``z`` (``H zt`` with ``H z = Z_0``)."""
    z, zt = np.atleast_2d(z), np.atleast_2d(zt)
    wz = (1 + z[:, 2]) + 1j * z[:, 3]
    c = (zt[:, 0] - z[:, 0] + 1j * (zt[:, 1] - z[:, 1])) / wz
    w = ((1 + zt[:, 2]) + 1j * zt[:, 3]) / wz
    return np.stack([c.real, c.imag, w.real - 1, w.imag], axis=1)


def _windows(model, reach):
    """Per support point ``i``, the dense template segments ``(n, Kw)`` that can reach its normal
    within ``reach`` (template px), with a validity mask; and the dense template ``(K, 2)``."""
    p0 = model.spline.dense(4) @ model.q0  # 4 segments per spline segment: sagitta << 0.1 px
    seg = np.linalg.norm(np.roll(p0, -1, axis=0) - p0, axis=1).max()
    dist = np.linalg.norm(p0[None] - model.q0[:, None], axis=2)  # (n, K)
    near = np.minimum(dist, np.roll(dist, -1, axis=1)) <= reach + seg
    width = int(near.sum(axis=1).max())
    idx = np.argsort(~near, axis=1, kind="stable")[:, :width]
    return p0, idx, np.take_along_axis(near, idx, 1)


def intersections(model, d, rng, chunk=2000):
    """Offsets ``(S, n)`` along the template's normals at its support points (the normal pose
    ``Z_0``) where the contour of pose ``d (S, 4)`` crosses them within ``±l0``; one crossing at
    random where there are several, NaN where there is none."""
    d = np.atleast_2d(d)
    l0, q0, n0 = model.search_length, model.q0, model.normals0
    radius = np.linalg.norm(model.q0, axis=1).max() * 1.05
    move = np.hypot(d[:, 0], d[:, 1]).max() + np.hypot(d[:, 2], d[:, 3]).max() * radius
    p0, idx, valid = _windows(model, l0 + move)
    out = np.full((len(d), model.n), np.nan)
    for a in range(0, len(d), chunk):
        poly = model.place_points(d[a:a + chunk], p0)  # (S, K, 2)
        rel = poly[:, idx] - q0[:, None]  # (S, n, Kw, 2)
        rel2 = poly[:, (idx + 1) % len(p0)] - q0[:, None]
        side = rel[..., 1] * n0[:, None, 0] - rel[..., 0] * n0[:, None, 1]
        side2 = rel2[..., 1] * n0[:, None, 0] - rel2[..., 0] * n0[:, None, 1]
        cross = (side * side2 <= 0) & (side != side2) & valid
        t = side / np.where(cross, side - side2, 1.0)
        u = (rel[..., 0] + t * (rel2[..., 0] - rel[..., 0])) * n0[:, None, 0] + \
            (rel[..., 1] + t * (rel2[..., 1] - rel[..., 1])) * n0[:, None, 1]
        ok = cross & (np.abs(u) <= l0)
        j = np.argmax(np.where(ok, rng.random(ok.shape), -1.0), axis=2)
        pick = np.take_along_axis(u, j[..., None], 2)[..., 0]
        out[a:a + chunk] = np.where(ok.any(axis=2), pick, np.nan)
    return out


def _measure(model, cfg, nu, rng):
    """The likelihood's noise and clutter on normalised offsets ``nu (S, n)`` (NaN: none)."""
    l0 = model.search_length
    noise = model.sigma_edge if cfg.noise is None else cfg.noise
    nu = nu + noise * rng.standard_normal(nu.shape)
    nu[np.abs(nu) > l0] = np.nan
    nu[rng.random(nu.shape) < cfg.miss] = np.nan
    clutter = rng.random(nu.shape) < cfg.clutter
    nu[clutter] = rng.uniform(-l0, l0, int(clutter.sum()))
    return nu


def features(model, nu):
    """Network inputs ``(S, 2n)`` from normalised offsets ``nu (S, n)``: ``ν / l0`` (0 where
    missing) and the missing flags."""
    miss = np.isnan(nu)
    return np.concatenate([np.where(miss, 0.0, nu / model.search_length), miss.astype(float)], axis=1)


def simulate(model, cfg, rng):
    """Training pairs ``(x (S, 2n), Δ (S, 4))``: ``Δ`` uniform within ``λ`` of the normal pose,
    measured along its normals (:func:`intersections`, :func:`_measure`, :func:`features`)."""
    delta = rng.uniform(-1.0, 1.0, (cfg.samples, 4)) * model.search_lambda
    nu = _measure(model, cfg, intersections(model, delta, rng), rng)
    return features(model, nu), delta


class NNSearch:
    """A trained network ``x -> Δ``: weights, biases and the output scale ``λ``."""

    def __init__(self, coefs, intercepts, lam):
        self.coefs = [np.asarray(c, float) for c in coefs]
        self.intercepts = [np.asarray(b, float) for b in intercepts]
        self.lam = np.asarray(lam, float)

    def predict(self, x):
        """``Δ̂ (N, 4)`` for inputs ``x (N, 2n)``: ReLU layers, linear output, times ``λ``."""
        h = x
        for w, b in zip(self.coefs[:-1], self.intercepts[:-1]):
            h = np.maximum(h @ w + b, 0.0)
        return (h @ self.coefs[-1] + self.intercepts[-1]) * self.lam

    def save(self, path, key):
        """Write the weights and ``key`` to ``path`` (an ``.npz``; written whole, then renamed)."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        arrays = {f"w{i}": w for i, w in enumerate(self.coefs)}
        arrays.update({f"b{i}": b for i, b in enumerate(self.intercepts)})
        with replacing(path, "network cache") as tmp, open(tmp, "wb") as f:
            np.savez(f, key=np.array(key), lam=self.lam, **arrays)

    @classmethod
    def load(cls, path, key):
        """The network in ``path``; ``ValueError`` if it is unreadable or was trained for another key."""
        try:
            with np.load(path, allow_pickle=False) as f:
                if str(f["key"]) != key:
                    raise ValueError(f"{path}: trained for another template or options")
                layers = sum(1 for k in f.files if k.startswith("w"))
                net = cls([f[f"w{i}"] for i in range(layers)], [f[f"b{i}"] for i in range(layers)], f["lam"])
        except (OSError, KeyError, EOFError, ValueError, zipfile.BadZipFile) as e:
            raise ValueError(f"{path}: not a usable network ({e})") from None
        if not layers or any(w.shape[1] != b.shape[0] for w, b in zip(net.coefs, net.intercepts)):
            raise ValueError(f"{path}: inconsistent layer shapes")
        return net


def train(model, cfg=None):
    """Simulate ``cfg.samples`` pairs and fit the network (scikit-learn ``MLPRegressor``)."""
    from sklearn.exceptions import ConvergenceWarning
    from sklearn.neural_network import MLPRegressor

    cfg = cfg or NNSearchConfig()
    rng = np.random.default_rng(cfg.seed)
    x, delta = simulate(model, cfg, rng)
    mlp = MLPRegressor(hidden_layer_sizes=tuple(cfg.hidden), activation="relu", solver="adam", alpha=1e-4,
                       batch_size=min(200, len(x)), learning_rate_init=2e-3, max_iter=cfg.epochs, tol=0.0,
                       n_iter_no_change=cfg.epochs + 1, shuffle=True, random_state=cfg.seed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        mlp.fit(x, delta / model.search_lambda)
    return NNSearch(mlp.coefs_, mlp.intercepts_, model.search_lambda)


def cache_key(model, cfg):
    """A hash of what the network depends on: the template, ``l0``, ``λ``, ``σ_edge`` and ``cfg``."""
    h = hashlib.sha256(f"v{VERSION}".encode())
    for a in (model.q0, model.search_length, model.search_lambda, model.sigma_edge):
        h.update(np.round(np.asarray(a, float), 6).tobytes())
    h.update(repr(sorted(asdict(cfg).items())).encode())
    return h.hexdigest()[:24]


def cache_dir():
    """``$VISTRACK_CACHE``, else ``$XDG_CACHE_HOME/vistrack``, else ``~/.cache/vistrack``."""
    root = os.environ.get("VISTRACK_CACHE") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache"), "vistrack")
    return Path(root) / "nn-search"


def cache_path(model, cfg=None):
    """Where the network of ``model``'s template and search options is cached."""
    return cache_dir() / f"{cache_key(model, cfg or NNSearchConfig())}.npz"


def load_or_train(model, cfg=None, path=None, notify=None):
    """The cached network of ``model`` (``path``: default :func:`cache_path`), trained and cached
    when the file is missing, corrupt or for other options. ``notify(message)`` hears of training.
    Returns ``(net, info)`` with ``info``: ``path``, ``trained``, ``kept`` (the network is in ``path``)
    and (trained) ``seconds``, ``cpu_seconds``. A network that cannot be written to a ``path`` given is an
    :class:`~vistrack.io.outputs.OutputError` (the cache's own folder: a note, and the network is used)."""
    cfg = cfg or NNSearchConfig()
    key = cache_key(model, cfg)
    given = path is not None
    path = Path(path) if given else cache_dir() / f"{key}.npz"
    info = {"path": str(path), "trained": False, "kept": True}
    if path.exists():
        try:
            return NNSearch.load(path, key), info
        except ValueError as e:
            if notify:
                notify(f"{e}; retraining")
    if notify:
        notify(f"training the NN local search ({cfg.samples} simulated poses; once per template)")
    t0, c0 = time.perf_counter(), time.process_time()
    net = train(model, cfg)
    info.update(trained=True, seconds=time.perf_counter() - t0, cpu_seconds=time.process_time() - c0)
    try:
        net.save(path, key)
    except OSError as e:  # a read-only cache: use the network without keeping it
        if given:
            raise
        info["kept"] = False
        if notify:
            notify(f"cannot cache the network at {path}: {e.strerror}")
    return net, info


def network_for(model, notify=None):
    """The model's network (``model.nn_search``), loaded or trained on first use."""
    if model.nn_search is None:
        model.nn_search = load_or_train(model, notify=notify)[0]
    return model.nn_search


def nn_candidates(model, obs, z):
    """Fig. 4.5: the network's poses ``Ẑ (N, 4)`` for predicted poses ``z (N, 4)``.

    On each support-point normal of ``z`` the strongest edge feature within ``l0 · s`` (``s``:
    the scale of ``z``), its offset divided by ``s`` (the normalisation ``H``), the network's
    ``Δ̂``, then ``Ẑ = z ∘ Δ̂``.
    """
    net = network_for(model)
    l0 = model.search_length
    u = np.arange(-np.floor(l0), np.floor(l0) + 1)  # 1-px samples at scale 1
    scale = np.hypot(1 + z[:, 2], z[:, 3])
    gn = model.edge_profiles(obs, z, scale[:, None, None] * u, support=True)  # (N, n, L)
    peaks = edge_peaks(gn, model.feature_threshold(obs))
    best = np.argmax(np.where(peaks, gn, -1.0), axis=-1)
    nu = np.where(peaks.any(axis=-1), u[best], np.nan)
    return compose(z, net.predict(features(model, nu)))
