"""What the box model reports when it loses the object, and how it finds it again.

Lost
    ``visible=0`` where the collapse test fires (``log r`` at the estimate far below its running level,
    the scale below a floor or the centre out of the frame: :mod:`~vistrack.models.collapse`) or, with
    the correlation filter, where the estimate's calibrated confidence (:mod:`~vistrack.models.box.confidence`)
    falls below its threshold (``low-confidence``). The model does not adapt on a frame reported lost.
Found
    after ``redetect_after`` frames reported lost in a row, each frame is searched whole with the
    correlation filter (:meth:`LostAndFound.search_whole`); the most confident of its best places is taken
    where its confidence (a whole-frame search's candidate's calibration) clears the threshold, the
    particles are re-seeded about it (:meth:`LostAndFound.reseed`) and the frame is marked ``redetected``.
"""

from __future__ import annotations

import numpy as np

from ...core.particles import ParticleSet
from .confidence import BoxConfidence, Calibration

__all__ = ["LostAndFound"]


class LostAndFound:
    """The box model's lost test, confidence and re-detection (module docstring);
    :class:`~vistrack.models.box.model.Box` calls :meth:`init_lost` from its constructor."""

    def init_lost(self, dcf, confidence, lost_confidence, redetect, reentry, redetect_after, search_crop,
                  search_peaks):
        """Set up the confidence and the re-detection (the Box's parameters of these names).

        Parameters
        ----------
        dcf : bool
            Whether the model has the correlation filter (the confidence and the search need it).
        confidence : bool, tuple or path
            With the filter, the estimate's confidence on each frame (:mod:`~vistrack.models.box.confidence`):
            ``True`` the calibrations shipped with the package, a pair of
            :class:`~vistrack.models.box.confidence.Calibration` (an estimate's, a candidate's) or the path
            of an ``.npz`` holding them; ``False``: none (nor without the filter).
        lost_confidence : float in [0, 1] or None
            The object is reported lost (``low-confidence``) on a frame whose confidence is below this
            (``None``: the calibration's threshold; 0: never).
        redetect_after : int, >= 1
            Frames reported lost in a row before each frame is searched whole (:meth:`_redetect`).
        search_crop : float, > 0 or None
            That search correlates the filter's taps over the object's box grown this many times
            (:meth:`~vistrack.appearance.correlation.CorrelationFilter.search`; ``None``: all its taps, the
            surroundings learnt with it too).
        search_peaks : int, >= 1
            The best places of that search whose confidence is computed; the most confident is the
            candidate.
        redetect : float, >= 0 or None
            Without a confidence (``confidence=False``), a whole-frame search's best place is taken when
            ``log r`` there is within ``redetect`` times the collapse test's ``drop`` of its running level
            (``None``: no search at all).
        reentry : float in [0, 1]
            The share of a pose uniform over the frame in the dynamics on the frame after a re-detection
            (:meth:`~vistrack.models.box.model.Box.predict`).
        """
        self.conf = None
        if dcf and confidence is not False:
            cal = None if confidence is True else tuple(confidence) if isinstance(confidence, (tuple, list)) \
                else (Calibration.load(confidence), Calibration.load(confidence, "candidate"))
            self.conf = BoxConfidence(self, cal)
        self.lost_confidence = lost_confidence
        self.redetect = None if redetect is None else float(redetect)
        self.reentry = float(reentry)
        self.redetect_after = int(redetect_after)
        self.search_crop, self.search_peaks = search_crop, int(search_peaks)
        self._lost = False  # the last frame was reported lost
        self._lost_run = 0  # frames reported lost in a row
        self._last_scale = 0.0  # the log-scale of the last frame reported
        self._found = False  # this frame is a re-detection
        self._reentry = False  # this frame's dynamics has the re-entry share
        self._pred = None  # this frame's mean prediction (cx, cy, l), the motion cue's reference
        self._conf_obs = None  # the observation the last confidence was computed on

    def _redetect(self, frame):
        """While the track is lost (:attr:`redetect_after` frames in a row): of the best places of a whole-frame
        search (:meth:`search_whole`), the most confident (:meth:`BoxConfidence.candidate`; without a
        confidence, the best), taken (the observation about it, the particles re-seeded there by
        :meth:`reseed`, the dynamics' re-entry share on, and no velocity carried into the next frame's
        prediction: ``d = 0`` there) when its confidence (:meth:`BoxConfidence.candidate`) clears
        :attr:`threshold` (without a confidence: when ``log r`` of the pose there is within ``redetect``
        times the collapse test's ``drop`` of its running level); ``None`` otherwise."""
        found = self.search_whole(frame)
        if self.conf is not None and self.conf.candidate_calibration is not None:
            c, k = max((self.conf.candidate(self, o, p), -k) for k, (o, p) in enumerate(found))
            obs, cand = found[-k][0], found[-k][1][None]
            if not c >= self.threshold:
                return None
        else:
            obs, cand = found[0][0], found[0][1][None]
            level, drop = self._collapse.level, self._collapse.drop
            if level is None or drop is None or not self.collapse_loglik(obs, cand)[0] >= level - self.redetect * drop:
                return None
        self._reentry = self.reentry > 0
        self._found = True
        obs.found = cand[0]
        return obs

    def search_whole(self, frame):
        """A whole-frame search with the filter (:meth:`CorrelationFilter.search`: its taps over the object's
        box, ``search_crop``) at the last reported frame's scale, and at the first frame's where they differ
        by more than 10 %: for each of its :attr:`search_peaks` best places at each scale, the observation
        about it (the filter's response there, ``β`` at least 0.9, marked a re-detection) and the pose
        ``(cx, cy, l) (3,)`` at that response's peak. Changes nothing the tracking reads
        (``benchmarks/fit_confidence.py`` calls it on any frame)."""
        out = []
        # the estimate's scale drifts while the object is lost, and may shrink as it leaves the frame
        scales = (self._last_scale,) if abs(self._last_scale) < 0.1 else (self._last_scale, 0.0)
        for scale in scales:
            for x, y, _ in self.cf.search(frame, scale, crop=self.search_crop, peaks=self.search_peaks):
                roi = self.app.roi(self.boxes(np.array([[x, y, scale]])), 0.0)
                obs = self._dcf_frame(frame, roi, np.array([x, y, scale]), max(self.dcf_share, 0.9), True)
                r = obs.dcf
                out.append((obs, np.array([*r.peak_xy, r.log_scales[r.best]])))
        return out

    def reseed(self, obs, particles, rng):
        """On a frame whose whole-frame search found the object (:meth:`_redetect`): the previous particles
        replaced by ``N`` equally weighted draws about the place found (the prior's spread ``p_0`` about it,
        no velocity); ``None`` on any other frame (the particles stay)."""
        if not obs.redetected:
            return None
        z = obs.found + self.prior_std * rng.standard_normal((particles.n, 3))
        return ParticleSet(np.concatenate([z, z], axis=1), np.zeros(particles.n))

    def redetected(self, obs):
        """Whether this frame's observation is a whole-frame search's find (:meth:`_redetect`)."""
        return bool(obs.redetected)

    def check_lost(self, obs, state):
        """The collapse test (:class:`~vistrack.models.collapse.CollapseCheck`) and the confidence's
        (``low-confidence`` below :attr:`threshold`, when :meth:`confidence` was computed on ``obs``),
        remembered for the next frame's re-detection."""
        c, low = self.conf.value if self.conf is not None and obs is self._conf_obs else None, ""
        if c is not None and c < self.threshold:
            low = f"confidence {c:.3f}, below the threshold {self.threshold:.3f}"
        out = super().check_lost(obs, state, low)
        self._lost = bool(out[0])
        self._lost_run = self._lost_run + 1 if self._lost else 0
        if not self._lost:
            self._last_scale = float(np.ravel(state)[2])
        return out

    # -- the confidence (issue 44; :mod:`~vistrack.models.box.confidence`) ------------------------
    @property
    def threshold(self):
        """The confidence below which the object is reported lost (``lost_confidence``, else the
        calibration's); 0 without a confidence."""
        if self.conf is None or self.conf.calibration is None:
            return 0.0
        return self.conf.calibration.threshold if self.lost_confidence is None else float(self.lost_confidence)

    def confidence(self, obs, state, particles):
        """The calibrated confidence in ``[0, 1]`` that the estimate ``state (6,)`` lies on the object, on
        the frame observed as ``obs`` with the weighted ``particles`` (1 on the first frame); ``None``
        without one (no correlation filter, or ``confidence=False``)."""
        if self.conf is None:
            return None
        self._conf_obs = obs
        return self.conf.update(self, obs, state, None if obs.dcf is None else particles)

    def predicted_pose(self):
        """This frame's mean prediction ``(cx, cy, l)`` (the weighted mean of ``K``'s means), ``None`` on the
        first frame."""
        return self._pred

