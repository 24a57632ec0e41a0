"""What the box model reports when it loses the object, and how it finds it again.

Lost
    ``visible=0`` where the collapse test fires (``log r`` at the estimate far below its running level,
    the scale below a floor or the centre out of the frame: :mod:`~vistrack.models.collapse`) or, with
    the correlation filter, where the estimate's calibrated confidence (:mod:`~vistrack.models.box.confidence`)
    falls below its threshold (``low-confidence``). The model does not adapt on a frame reported lost.
Found
    after ``redetect_after`` frames reported lost in a row, every ``redetect_every``-th frame is searched whole
    with the correlation filter, coarse to fine (:meth:`LostAndFound.candidates`); the most confident of its
    best places is taken where its confidence (a whole-frame search's candidate's calibration) clears the
    threshold, the particles are re-seeded about it (:meth:`LostAndFound.reseed`) and the frame is marked
    ``redetected``.
"""

from __future__ import annotations

import numpy as np

from ...core.particles import ParticleSet
from .confidence import BoxConfidence, Calibration

__all__ = ["LostAndFound"]


class LostAndFound:
    """The box model's lost test, confidence and re-detection (module docstring);
    :class:`~vistrack.models.box.model.Box` calls :meth:`init_lost` from its constructor."""

    def init_lost(self, dcf, confidence, lost_confidence, redetect, reentry, every_cue):
        """Set up the confidence and what is done on a re-detection (the Box's parameters of these names).

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
        redetect : float, >= 0 or None
            Without a confidence (``confidence=False``), a whole-frame search's best place is taken when
            ``log r`` there is within ``redetect`` times the collapse test's ``drop`` of its running level
            (``None``: no search at all).
        reentry : float in [0, 1]
            The share of a pose uniform over the frame in the dynamics on the frame after a re-detection
            (:meth:`~vistrack.models.box.model.Box.predict`).
        every_cue : bool
            Compute every cue of the confidence on each frame, not only those its calibration reads
            (:class:`~vistrack.models.box.confidence.BoxConfidence`; ``benchmarks/fit_confidence.py`` fits on them).
        """
        self.conf = None
        if dcf and confidence is not False:
            cal = None if confidence is True else tuple(confidence) if isinstance(confidence, (tuple, list)) \
                else (Calibration.load(confidence), Calibration.load(confidence, "candidate"))
            self.conf = BoxConfidence(self, cal, every_cue)
        self.lost_confidence = lost_confidence
        self.redetect = None if redetect is None else float(redetect)
        self.reentry = float(reentry)
        self._lost = False  # the last frame was reported lost
        self._lost_run = 0  # frames reported lost in a row
        self._searches = 0  # whole-frame searches since the track was last reported
        self._last_scale = 0.0  # the log-scale of the last frame reported
        self._found = False  # this frame is a re-detection
        self._reentry = False  # this frame's dynamics has the re-entry share
        self._pred = None  # this frame's mean prediction (cx, cy, l), the motion cue's reference
        self._conf_obs = None  # the observation the last confidence was computed on

    def init_search(self, redetect_after, redetect_every, search_crop, search_peaks, search_stride, lean_when_lost):
        """Set up the whole-frame search (the Box's parameters of these names).

        Parameters
        ----------
        redetect_after : int, >= 1
            Frames reported lost in a row before a frame is searched whole (:meth:`_redetect`).
        redetect_every : int, >= 1
            From then on, every this many frames reported lost in a row, one is searched (:meth:`search_due`).
        search_crop : float, > 0 or None
            That search correlates the filter's taps over the object's box grown this many times
            (:meth:`~vistrack.appearance.correlation.CorrelationFilter.search`; ``None``: all its taps, the
            surroundings learnt with it too).
        search_peaks : int, >= 1
            The best places of that search whose confidence is computed; the most confident is the
            candidate.
        search_stride : int, >= 1
            That search's first, coarse correlation is over the frame at the filter's resolution divided by
            this (:meth:`candidates`).
        lean_when_lost : bool
            While the track is lost (:meth:`lean`), observe at the prediction's scale alone and without the scale
            filter, and verify a search's places so (the one taken is observed in full): a size means nothing
            while the object is not followed, and the correlation filter's second scale and the scale filter are
            a fifth of a frame's time (``docs/experiments.md``).
        """
        self.redetect_after, self.redetect_every = int(redetect_after), int(redetect_every)
        if self.redetect_every < 1:
            raise ValueError(f"redetect_every must be an integer >= 1, got {redetect_every!r}")
        self.search_crop, self.search_peaks, self.search_stride = search_crop, int(search_peaks), int(search_stride)
        self.lean_when_lost = bool(lean_when_lost)

    def lean(self):
        """Whether this frame is observed lean (``lean_when_lost``): the track lost :attr:`redetect_after` frames in
        a row or more, the frames a whole-frame search may run on."""
        return self.lean_when_lost and self._lost_run >= self.redetect_after

    def search_due(self):
        """Whether this frame is searched whole: the track lost :attr:`redetect_after` frames in a row or more,
        and every :attr:`redetect_every`-th such frame from then on (a search with re-detection on)."""
        run = self._lost_run - self.redetect_after
        return self.redetect is not None and run >= 0 and run % self.redetect_every == 0

    def _redetect(self, frame):
        """On a frame :meth:`search_due`: of the best places of a whole-frame search (:meth:`candidates`, at one of
        :meth:`search_scales` a search, in turn, the last reported frame's first), the most confident
        (:meth:`BoxConfidence.candidate`; without a confidence, the best), taken (the observation about it, the
        particles re-seeded there by :meth:`reseed`, the dynamics' re-entry share on, and no velocity carried into
        the next frame's prediction: ``d = 0`` there) when its confidence (:meth:`BoxConfidence.candidate`) clears
        :attr:`threshold` (without a confidence: when ``log r`` of the pose there is within ``redetect`` times the
        collapse test's ``drop`` of its running level); ``None`` otherwise. The observation of the place taken has
        the filter's scales and the scale filter's response, as a tracked frame's."""
        scales = self.search_scales()  # one a search, in turn
        found = self.candidates(frame, (scales[self._searches % len(scales)],))
        self._searches += 1
        if not found:
            return None
        if self.conf is not None and self.conf.candidate_calibration is not None:
            c, k = max((self.conf.candidate(self, o, p), -k) for k, (o, p, _) in enumerate(found))
            obs, pose, centre = found[-k]
            if not c >= self.threshold:
                return None
        else:
            obs, pose, centre = found[0]
            level, drop = self._collapse.level, self._collapse.drop
            if level is None or drop is None or \
                    not self.collapse_loglik(obs, pose[None])[0] >= level - self.redetect * drop:
                return None
        if self.lean_when_lost:  # the place taken observed in full
            obs = self._dcf_frame(frame, self.app.roi(self.boxes(centre[None]), 0.0), centre, obs.dcf_share, True)
        else:
            self.scale_response(frame, obs, centre)
        self._reentry = self.reentry > 0
        self._found = True
        obs.found = pose
        return obs

    def search_scales(self):
        """The log-scales a whole-frame search looks at: the last reported frame's, and the first frame's where
        they differ by more than 10 % (the estimate's scale drifts while the object is lost, and may shrink as it
        leaves the frame)."""
        return (self._last_scale,) if abs(self._last_scale) < 0.1 else (self._last_scale, 0.0)

    def candidates(self, frame, scales=None):
        """A whole-frame search, coarse to fine: the filter's taps over the object's box (``search_crop``)
        correlated with the whole frame at the filter's resolution divided by :attr:`search_stride`
        (:meth:`CorrelationFilter.search`) at each of ``scales`` (``None``: :meth:`search_scales`); then, about
        each of its :attr:`search_peaks` best places at each scale,
        the filter's response at full resolution (with ``lean_when_lost``, at that scale alone). Returns
        ``[(obs, pose, centre)]``: the observation about each place (its response, ``β`` at least 0.9, marked a
        re-detection; not the scale filter's response: :meth:`scale_response`), the pose ``(cx, cy, l) (3,)`` at
        that response's peak and the place searched about ``(x, y, l)``."""
        out = []
        for scale in self.search_scales() if scales is None else scales:
            for x, y, _ in self.cf.search(frame, scale, stride=self.search_stride, crop=self.search_crop,
                                          peaks=self.search_peaks):
                centre = np.array([x, y, scale])
                roi = self.app.roi(self.boxes(centre[None]), 0.0)
                obs = self._dcf_frame(frame, roi, centre, max(self.dcf_share, 0.9), True, scale=False,
                                      lean=self.lean_when_lost)
                r = obs.dcf
                out.append((obs, np.array([*r.peak_xy, r.log_scales[r.best]]), centre))
        return out

    def search_whole(self, frame):
        """:meth:`candidates` as ``[(obs, pose)]``. Changes nothing the tracking reads
        (``benchmarks/fit_confidence.py`` calls it on any frame)."""
        return [(obs, pose) for obs, pose, _ in self.candidates(frame)]

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
            self._searches = 0
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

