"""The box model's per-frame confidence: how likely the estimate lies on the object (issue 44).

Cues (:data:`FEATURES`), each what the filter knows already on a frame, read at the frame's estimate
``x̂ = (cx, cy, l)`` and its box ``b`` (``w_0 e^l × h_0 e^l`` about ``(cx, cy)``):

``apce``
    ``log APCE`` of the correlation filter's response ``F`` at its best scale (Wang, Liu and Huang 2017,
    average peak-to-correlation energy): ``|F_max - F_min|² / mean((F - F_min)²)``: high for one sharp
    peak, low for a flat or many-peaked response.
``psr``
    The peak-to-sidelobe ratio (Bolme et al. 2010, MOSSE): ``(F_max - μ_s) / σ_s`` over the map
    outside the 11 × 11 cells about the peak.
``peak``
    ``F_max``, the response's peak (about 1 on the object the filter learnt).
``response``
    The response at the estimate (:meth:`~vistrack.appearance.correlation.DCFResponse.read`).
``ncc_first``
    The correlation of the estimate's grey and gradient patch with the *first frame's* template
    (:meth:`~vistrack.appearance.cues.Appearance.anchor_ncc`).
``colour_first``
    The Bhattacharyya coefficient ``Σ_u sqrt(h_u q⁰_u)`` of the estimate's colour histogram with the
    first frame's ``q⁰`` (background-weighted, :class:`~vistrack.appearance.target_colour.TargetColour`).
``ncc``, ``colour``
    The same two against the model as adapted so far (the template and ``q`` of
    :class:`~vistrack.appearance.cues.Appearance`, which adapt on frames where the object is
    reported).
``contrast``
    The first frame's back-projection inside the box less in the ring about it
    (``mean_in β - mean_ring β``): the object's colours against its surroundings.
``drop``
    ``log r`` at the estimate less its running level (the collapse test's, :mod:`~vistrack.models.collapse`),
    clipped to ``[-100, 20]``.
``ess``
    The particle set's effective sample size over ``N`` (thesis 001 §2.4).
``spread``
    ``log`` of the particle cloud's weighted centre spread, ``sqrt(tr Σ_c)``, over the box's side
    ``sqrt(w h)``.
``motion``
    The estimate's distance from the dynamics' mean prediction in innovation stds of the centre
    (``σ_c e^l``), clipped to 10: a jump the motion model finds implausible.

The confidence is a logistic map of the standardised cues, ``c = σ(β · (z - μ) / s + β_0)``, fitted on the
development clips against "the estimate's box overlaps the true box" (IoU > 0) by
``benchmarks/fit_confidence.py``, which writes :data:`CALIBRATION` (``confidence.npz`` beside this module):
the cue names, ``μ``, ``s``, ``β``, ``β_0``, and the threshold below which the object is reported lost. The
response and appearance cues (:data:`MONOTONE`) enter with ``β >= 0`` (the fit drops any that would not),
so a sharper response or a closer appearance never lowers the confidence.

A whole-frame search's candidate (the box model's re-detection) is a place chosen for its response, so its
cues mean something else than an estimate's (a look-alike has a high peak by construction): it has a
calibration of its own, fitted the same way on the candidates of such searches made on the development
clips' low-confidence frames, from the cues a candidate has (the response's and the appearance's,
:data:`SEEN`; :meth:`BoxConfidence.candidate`). A candidate is taken where that confidence clears the
same threshold.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ... import kernels
from .. import calibration

__all__ = ["FEATURES", "SEEN", "MONOTONE", "CALIBRATION", "Calibration", "BoxConfidence", "apce", "psr"]

#: the cues, in the order of a feature vector
FEATURES = ("apce", "psr", "peak", "response", "ncc_first", "colour_first", "ncc", "colour", "contrast", "drop", "ess",
            "spread", "motion")
#: the cues whose weight must not be negative: the response's sharpness and the appearance's closeness (and
#: ``log r`` against its level)
MONOTONE = ("apce", "psr", "peak", "response", "ncc_first", "colour_first", "ncc", "colour", "contrast", "drop")
#: the cues of the frame's response and appearance at a pose: all that a whole-frame search's candidate has
SEEN = FEATURES[:10]
#: the calibration shipped with the package (``benchmarks/fit_confidence.py`` writes it)
CALIBRATION = Path(__file__).with_name("confidence.npz")
#: the cells about the peak that the peak-to-sidelobe ratio leaves out (each side)
PSR_HALF = 5


def apce(response):
    """Average peak-to-correlation energy of a response map ``(H, W)``: ``|F_max - F_min|² / mean((F - F_min)²)``
    (``inf`` for a map that is flat but for its peak; 0 for a constant map)."""
    f = np.asarray(response, float)
    lo, hi = f.min(), f.max()
    energy = np.mean((f - lo) ** 2)
    if energy <= 0:
        return 0.0
    return float((hi - lo) ** 2 / energy)


def psr(response, half=PSR_HALF):
    """Peak-to-sidelobe ratio of a response map ``(H, W)``: ``(F_max - μ_s) / σ_s`` over the cells outside the
    ``(2 half + 1)²`` window about the peak (0 where the sidelobe is empty or flat)."""
    f = np.asarray(response, float)
    i, j = np.unravel_index(int(np.argmax(f)), f.shape)
    mask = np.ones(f.shape, bool)
    mask[max(0, i - half):i + half + 1, max(0, j - half):j + half + 1] = False
    side = f[mask]
    if side.size < 2:
        return 0.0
    sd = side.std()
    return float((f[i, j] - side.mean()) / sd) if sd > 0 else 0.0


@dataclass
class Calibration(calibration.Calibration):
    """The box model's calibrated confidence: :class:`vistrack.models.calibration.Calibration` over cue vectors in
    :data:`FEATURES` order (a candidate's: :data:`SEEN`, their prefix), shipped in :data:`CALIBRATION`."""

    def __post_init__(self):
        if not self.features:
            self.features = FEATURES

    @classmethod
    def load(cls, path=CALIBRATION, part="frame", features=FEATURES):
        """The calibration ``part`` (``"frame"``: an estimate's; ``"candidate"``: a whole-frame search's
        candidate's) in ``path``, an ``.npz`` written by :meth:`save_all`."""
        return super().load(path, part, features)


class BoxConfidence:
    """The cues of the box model's estimate on each frame (module docstring) and their confidence.

    Only the cues the calibrations read are computed (the others are NaN in :attr:`features`): the shipped
    calibration reads eight of the thirteen an estimate has and six of a candidate's ten.

    Parameters
    ----------
    model : Box
        The box model (its appearance, correlation filter, dynamics and collapse test are read).
    calibration : tuple of Calibration or None
        The maps to a confidence of an estimate and of a whole-frame search's candidate (``None``: those in
        :data:`CALIBRATION`, or none where that file is missing: the cues alone, as
        ``benchmarks/fit_confidence.py`` needs them before a first fit).
    every_cue : bool
        Compute every cue of :data:`FEATURES` (and of :data:`SEEN` for a candidate), not only those the
        calibrations read: what ``benchmarks/fit_confidence.py`` fits on (every cue is also computed without
        a calibration).

    Attributes
    ----------
    features : ndarray of shape (len(FEATURES),) or None
        The last frame's cues (NaN where not computed).
    value : float or None
        The last frame's confidence (1 on the first frame: the user's box; ``None`` without a calibration).
    frame_cues, candidate_cues_read : tuple of str
        The cues computed for an estimate and for a candidate.
    """

    def __init__(self, model, calibration=None, every_cue=False):
        if calibration is None and CALIBRATION.is_file():
            calibration = Calibration.load(), Calibration.load(part="candidate")
        self.calibration, self.candidate_calibration = (None, None) if calibration is None else calibration
        every = every_cue or self.calibration is None
        self.frame_cues = FEATURES if every else tuple(self.calibration.names)
        self.candidate_cues_read = SEEN if every or self.candidate_calibration is None \
            else tuple(self.candidate_calibration.names)
        self.q0 = model.app.colour.q.copy()  # the first frame's colour model (q adapts)
        self.features = None
        self.value = 1.0

    def cues(self, model, obs, state, particles, names=FEATURES):
        """The cue vector ``(len(FEATURES),)`` of the estimate ``state (6,)`` on the frame observed as ``obs``
        (with its response ``obs.dcf``), ``particles`` the frame's weighted set (``None``: the
        ``(len(SEEN),)`` cues of the response and the appearance alone); only the cues ``names``, the
        others NaN."""
        s = np.asarray(state, float).reshape(1, -1)
        box = model.boxes(s)[0]
        want = set(names)
        out = np.full(len(SEEN) if particles is None else len(FEATURES), np.nan)
        self._response_cues(model, obs, s, want, out)
        self._appearance_cues(model, obs, box, want, out)
        if particles is not None:
            self._particle_cues(model, s[0], box, particles, want, out)
        return out

    @staticmethod
    def _response_cues(model, obs, s, want, out):
        """``apce``, ``psr``, ``peak``, ``response`` and ``drop`` of the pose ``s (1, 6)`` into ``out``."""
        resp = obs.dcf
        if want & {"apce", "psr"}:
            best = resp.maps[resp.best]
            out[0], out[1] = np.log(max(apce(best), 1e-6)), psr(best)
        if "peak" in want:
            out[2] = float(resp.peak)
        if "response" in want:
            out[3] = float(resp.read(s)[0])
        if "drop" in want:
            level = model.collapse_level
            loglik = float(model.collapse_loglik(obs, s)[0])  # the collapse test's log r, against its level
            out[9] = -100.0 if not np.isfinite(loglik) else 0.0 if level is None \
                else float(np.clip(loglik - level, -100.0, 20.0))

    def _appearance_cues(self, model, obs, box, want, out):
        """``ncc_first``, ``colour_first``, ``ncc``, ``colour`` and ``contrast`` of ``box (4,)`` into ``out``."""
        app = model.app
        if want & {"ncc_first", "ncc"} and want & {"colour_first", "colour", "contrast"}:
            b = np.ascontiguousarray(box, float)[None]
            obs.maps(obs.window(b, app.ring), obs.window(b))  # the maps both read, made in one pass
        if "ncc_first" in want:
            out[4] = app.anchor_ncc(obs, box)
        if "ncc" in want:
            out[6] = float(app.ncc(obs, box[None])[0])
        if not want & {"colour_first", "colour", "contrast"}:
            return
        colour = app.colour
        if kernels.use():
            from .kernels import colour_cues

            b = np.ascontiguousarray(box, float)
            _, ii = obs.maps(obs.window(b[None], app.ring))
            out[[5, 7, 8]] = colour_cues(ii, float(obs.x0), float(obs.y0), float(obs.f), b, float(app.ring),
                                         colour.bg_weight, self.q0, colour.q, colour.bp, np.empty(3))
            return
        grow = app.ring * 0.5 * (box[2] + box[3])
        inner, ring = obs.histograms(box[:1], box[1:2], box[2:3], box[3:4], grow=np.array([grow]))
        bp = colour.bp
        out[5] = float(np.sqrt(colour.normalise(inner[0]) * self.q0).sum())
        out[7] = float(1.0 - colour.d2(inner[0]))
        out[8] = float(inner[0] @ bp / max(inner[0].sum(), 1) - ring[0] @ bp / max(ring[0].sum(), 1))

    @staticmethod
    def _particle_cues(model, s, box, particles, want, out):
        """``ess``, ``spread`` and ``motion`` of the weighted ``particles`` about the estimate ``s (6,)``."""
        if "ess" in want:
            out[10] = particles.ess / particles.n
        if "spread" in want:
            w = particles.weights
            c = particles.states[:, :2] - w @ particles.states[:, :2]
            spread = float(np.sqrt(w @ np.einsum("ij,ij->i", c, c)))
            out[11] = np.log(max(spread / float(np.sqrt(box[2] * box[3])), 1e-4))
        if "motion" in want:
            pred = model.predicted_pose()
            step = 0.0 if pred is None else float(np.hypot(*(s[:2] - pred[:2])) / (model.sigma[0] * np.exp(pred[2])))
            out[12] = min(step, 10.0)

    def candidate_cues(self, model, obs, state, names=SEEN):
        """The cues ``(len(SEEN),)`` of a whole-frame search's candidate ``state (3,)`` on the frame observed
        about it as ``obs``: its response's and its appearance's (only ``names``, the others NaN)."""
        s = np.ravel(state)[:3]
        return self.cues(model, obs, np.concatenate([s, s]), None, names)

    def candidate(self, model, obs, state):
        """The confidence of a whole-frame search's candidate ``state (3,)`` on the frame observed about it as
        ``obs`` (:meth:`candidate_cues` through the candidates' calibration); ``None`` without one."""
        if self.candidate_calibration is None:
            return None
        return float(self.candidate_calibration(self.candidate_cues(model, obs, state, self.candidate_cues_read)))

    def update(self, model, obs, state, particles):
        """The confidence of the frame's estimate (kept in :attr:`value`, its cues in :attr:`features`); 1 on
        the first frame (no response: the user's box)."""
        if particles is None or obs.dcf is None:
            self.features, self.value = None, None if self.calibration is None else 1.0
            return self.value
        self.features = self.cues(model, obs, state, particles, self.frame_cues)
        self.value = None if self.calibration is None else float(self.calibration(self.features))
        return self.value
