"""What the siam model reports when it loses the object, and how it finds it again.

Confidence
    a logistic map of the frame's cues (:data:`FEATURES`, read off the response, the particle cloud and the
    dynamics), calibrated on the development clips against "the estimate's box overlaps the true box"
    (``benchmarks/fit_confidence.py --model siam``, ``confidence.npz`` beside this module). The object is
    reported lost (``visible=0``, ``low-confidence``) below the calibration's threshold, and ``out-of-frame``
    when the estimate's centre leaves the frame.
Re-detection
    after ``redetect_after`` frames reported lost in a row, a lost frame is searched wider, then again after
    ``search_every`` frames, the gap doubling up to ``search_cap`` while the object stays lost (a search costs
    about six frames' network, so that a long loss costs little more than tracking): one ``511 × 511`` crop
    about the last reported place at twice the search crop's side, through the head made for its ``32 × 32``
    features (:class:`~vistrack.models.siam.network.SiamNetwork`, ``wide``: its logits differ from a normal
    crop's, so they only name candidates); the ``search_peaks`` best places are confirmed each with a normal
    search crop about them (one batch through the network), and the most confident confirmation is taken when
    its confidence clears the candidates' threshold: the frame's observation is
    that crop, the particles are re-seeded about the place found and the frame is marked ``redetected``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ... import kernels
from ...core.particles import ParticleSet
from ..calibration import Calibration
from .network import INSTANCE, WIDE, crop
from .observation import SiamFrame, cell_boxes

__all__ = ["FEATURES", "MONOTONE", "CALIBRATION", "SiamLost", "psr"]

#: the cues of an estimate, in the order of a feature vector
FEATURES = ("peak", "logit", "agree", "psr", "rival", "colour", "drop", "ess", "spread", "motion", "size")
#: cues whose weight must not be negative (a stronger, sharper response, closer colours never lower the confidence)
MONOTONE = ("peak", "logit", "agree", "psr", "rival", "colour", "drop")
#: the cues a candidate of a search has (no particle cloud, no dynamics)
SEEN = FEATURES[:6]
#: the calibration shipped with the package
CALIBRATION = Path(__file__).with_name("confidence.npz")


def psr(logit, half=2):
    """The logit map's peak-to-sidelobe ratio: ``(ℓ_max - μ_s) / σ_s`` over the cells outside the
    ``(2 half + 1)²`` about the peak (0 where that is flat)."""
    i, j = np.unravel_index(int(np.argmax(logit)), logit.shape)
    mask = np.ones(logit.shape, bool)
    mask[max(0, i - half):i + half + 1, max(0, j - half):j + half + 1] = False
    side = logit[mask]
    sd = side.std()
    return float((logit[i, j] - side.mean()) / sd) if sd > 0 else 0.0


def rival(logit, half=3):
    """The peak's lead over the best cell outside the ``(2 half + 1)²`` about it (a look-alike's gap)."""
    i, j = np.unravel_index(int(np.argmax(logit)), logit.shape)
    mask = np.ones(logit.shape, bool)
    mask[max(0, i - half):i + half + 1, max(0, j - half):j + half + 1] = False
    return float(logit[i, j] - logit[mask].max()) if mask.any() else 0.0


class SiamLost:
    """The siam model's confidence, lost test and re-detection (module docstring); the model calls
    :meth:`init_lost` from its constructor."""

    def init_lost(self, confidence, lost_confidence, redetect_after, search_every, search_peaks, search_cap):
        """Set up the confidence (``True``: the package's calibrations, a pair of
        :class:`~vistrack.models.calibration.Calibration` (an estimate's, a candidate's) or the path of an ``.npz``
        holding them; ``False``: none), the threshold (``lost_confidence``; ``None``: the calibration's) and the
        re-detection (after ``redetect_after`` lost frames, then after ``search_every`` more, the gap doubling up to
        ``search_cap`` frames while the object stays lost; ``search_peaks`` candidates; ``redetect_after=None``:
        never)."""
        cal = (None, None)
        if confidence is True and CALIBRATION.is_file():
            confidence = CALIBRATION
        if isinstance(confidence, (tuple, list)):
            cal = tuple(confidence)
        elif confidence is not True and confidence:
            cal = Calibration.load(confidence, "frame", FEATURES), Calibration.load(confidence, "candidate", SEEN)
        self.calibration, self.candidate_calibration = cal
        self._cues = confidence is not False  # the cues are computed (a calibration's fit reads them without one)
        self.lost_confidence = lost_confidence
        self.redetect = None if redetect_after is None else int(redetect_after)
        self.search_every, self.search_peaks = max(1, int(search_every)), int(search_peaks)
        self.search_cap = max(self.search_every, int(search_cap))
        self._next_search, self._search_gap = self.redetect, self.search_every
        self.features = None  # the last frame's cues
        self.conf_value = None
        self._lost_run = 0
        self._level = []  # log r at the reported estimates (the drop cue's running level)
        self._reported = None  # the last reported pose (cx, cy, lw, lh)
        self._ll, self._ll_obs = None, None  # log r at the last estimate whose cues were read, and its frame
        self._pred = None

    @property
    def hold(self):
        """How much higher than :attr:`threshold` the confidence of an object reported lost must rise for it to be
        reported again (the calibration's ``hold``; 0 with ``lost_confidence`` given or without a calibration)."""
        return 0.0 if self.calibration is None or self.lost_confidence is not None else self.calibration.hold

    @property
    def threshold(self):
        """The confidence below which the object is reported lost (0 without a calibration)."""
        if self.calibration is None:
            return 0.0
        return self.calibration.threshold if self.lost_confidence is None else float(self.lost_confidence)

    # -- the cues ----------------------------------------------------------------------------------------------
    def response_cues(self, obs, pose):
        """The cues of :data:`SEEN` ``(6,)`` of a pose ``(4,)`` on the frame observed as ``obs``: the map's peak
        logit, the logit at the pose, its box's agreement with the head's, the map's PSR, the peak's lead and the
        colours' match with the first box's."""
        logit, agree = self.pose_terms(obs, pose)
        colour = self.colour_match(obs, pose)
        if kernels.use():
            from .kernels import map_cues

            peak, sharp, lead = map_cues(obs.logit, 2, 3, np.empty(3))
            return np.array([peak, logit, agree, sharp, lead, colour])
        return np.array([float(obs.logit.max()), logit, agree, psr(obs.logit), rival(obs.logit), colour])

    def cues(self, obs, state, particles):
        """The cue vector ``(len(FEATURES),)`` of the estimate ``state (8,)`` with the frame's ``particles``."""
        s = np.asarray(state, float)
        seen = self.response_cues(obs, s[:4])
        ll = self._ll = self.lambda_logit * seen[1] + seen[2]  # log r at the estimate
        self._ll_obs = obs
        level = _median(self._level) if self._level else ll
        side = self.side0 * np.exp((s[2] + s[3]) / 2)
        if kernels.use():
            from .kernels import cloud_stats

            spread = float(cloud_stats(np.ascontiguousarray(particles.states, float), np.array(particles.weights), 0.0,
                                       np.empty(5))[4])
        else:
            w = particles.weights
            c = particles.states[:, :2] - w @ particles.states[:, :2]
            spread = float(np.sqrt(w @ np.einsum("ij,ij->i", c, c)))
        pred = self._pred if self._pred is not None else s[:4]
        step = float(np.hypot(*(s[:2] - pred[:2])) / (self.sigma_xy * side))
        return np.concatenate([seen, [float(np.clip(ll - level, -50.0, 20.0)), particles.ess / particles.n,
                                      np.log(max(spread / side, 1e-4)), min(step, 10.0),
                                      abs((s[2] + s[3]) / 2)]])

    def confidence(self, obs, state, particles):
        """The calibrated confidence in ``[0, 1]`` that the estimate lies on the object (1 on the first frame and on
        a re-detection); ``None`` without a calibration (the cues are still kept in :attr:`features` unless
        ``confidence=False``)."""
        if not self._cues:
            return None
        if obs.redetected or self._reported is None:
            self.features, self.conf_value = None, None if self.calibration is None else 1.0
        else:
            self.features = self.cues(obs, state, particles)
            self.conf_value = None if self.calibration is None else float(self.calibration(self.features))
        return self.conf_value

    # -- lost ------------------------------------------------------------------------------------------------
    def check_lost(self, obs, state):
        """``(reason, detail)``: ``out-of-frame`` when the estimate's centre left the frame, ``low-confidence``
        below :attr:`threshold`, else ``("", "")``; remembered for the re-detection."""
        s = np.ravel(state)
        w, h = self.frame_size
        if not (0 <= s[0] < w and 0 <= s[1] < h):
            out = "out-of-frame", f"centre ({s[0]:.1f}, {s[1]:.1f}) outside the {w}x{h} frame"
        elif self.conf_value is not None and self.conf_value < self.threshold + (self.hold if self._lost_run else 0):
            level = self.threshold + (self.hold if self._lost_run else 0)
            out = "low-confidence", (f"confidence {self.conf_value:.3f}, below the threshold {level:.3f}"
                                     + (" (a lost object's)" if self._lost_run else ""))
        else:
            out = "", ""
        self._lost_run = self._lost_run + 1 if out[0] else 0
        if not out[0]:
            self._next_search, self._search_gap = self.redetect, self.search_every
            self._reported = s[:4].copy()
            ll = self._ll if self._ll_obs is obs else float(self.loglik(obs, s[None])[0])
            self._level = (self._level + [ll])[-30:]
        return out

    # -- found -----------------------------------------------------------------------------------------------
    def searching(self):
        """Whether this frame is one the re-detection searches (module docstring)."""
        return self.redetect is not None and self._reported is not None and self._lost_run >= self._next_search

    def search(self, frame):
        """The wide search's candidates, confirmed: a list of ``(confidence, SiamFrame, pose (4,))``, best first
        (confidence ``None`` without a calibration: then ordered by the confirmation's peak logit)."""
        last = self._reported
        side = 2.0 * self.search_side(last)
        scale = WIDE / round(side)
        logit, ltrb = self.net.search(crop(frame, last[:2], side, WIDE, self.fill), wide=True)
        m = logit.shape[1]
        boxes = cell_boxes(ltrb[0], last[:2], scale, self.size0, _points(m))
        flat = logit[0].astype(float).ravel().copy()
        picks = []
        for _ in range(self.search_peaks):
            k = int(np.argmax(flat))
            if not np.isfinite(flat[k]):
                break
            picks.append(k)
            i, j = divmod(k, m)
            region = flat.reshape(m, m)
            region[max(0, i - 3):i + 4, max(0, j - 3):j + 4] = -np.inf
        if not picks:
            return []
        centres = [np.r_[boxes[k, :2], last[2:]] for k in picks]
        sides = [self.search_side(c) for c in centres]
        crops = np.stack([crop(frame, c[:2], sd, INSTANCE, self.fill) for c, sd in zip(centres, sides)])
        logits, ltrbs = self.net.search(crops)
        out = []
        for c, sd, lg, lt, patch in zip(centres, sides, logits, ltrbs, crops):
            sc = INSTANCE / round(sd)
            obs = SiamFrame(frame, c[:2].copy(), sc, lg.astype(float), cell_boxes(lt, c[:2], sc, self.size0),
                            self.size0, patch, redetected=True)
            k = int(np.argmax(obs.logit))
            pose = np.r_[obs.boxes[k, :2], last[2:]]
            cal = self.candidate_calibration
            conf = None if cal is None else float(cal(self.response_cues(obs, pose)))
            out.append((conf, obs, pose))
        out.sort(key=lambda t: -(t[0] if t[0] is not None else float(t[1].logit.max())))
        return out

    def redetect_frame(self, frame):
        """The observation of a searched frame whose best confirmation clears the threshold (``found`` set, marked
        ``redetected``), else ``None``."""
        found = self.search(frame)
        self._next_search = self._lost_run + self._search_gap  # the next search, the gap doubling to search_cap
        self._search_gap = min(2 * self._search_gap, self.search_cap)
        if not found:
            return None
        conf, obs, pose = found[0]
        if conf is None or conf < self.candidate_calibration.threshold:
            return None
        obs.found = pose
        return obs

    def reseed(self, obs, particles, rng):
        """On a frame whose search found the object: ``N`` equally weighted draws about it (``p_0``'s spread, no
        velocity); ``None`` on any other frame."""
        if not obs.redetected or obs.found is None:
            return None
        z = obs.found + self.prior_std * rng.standard_normal((particles.n, 4))
        return ParticleSet(np.concatenate([z, z], axis=1), np.zeros(particles.n))

    def redetected(self, obs):
        """Whether the frame observed as ``obs`` is a search's find."""
        return bool(obs.redetected and obs.found is not None)


def _median(values):
    """The median of a short list (as ``np.median``)."""
    s = sorted(values)
    k = len(s) // 2
    return s[k] if len(s) % 2 else (s[k - 1] + s[k]) / 2.0


def _points(m):
    from .network import cell_points

    return cell_points(m)
