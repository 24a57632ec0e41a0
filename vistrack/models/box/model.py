"""A generic box model for any object started from an ``--init`` box (real footage; beyond the seeds).

State
    ``(cx, cy, l, cx', cy', l')``, shape ``(N, 6)``: the box centre (px) and its log-scale
    ``l`` relative to the first box (``w = w_0 e^l``, ``h = h_0 e^l``), and the previous
    frame's values.
Dynamics (AR(2), as the contour and plate models)
    ``c_t = c_{t-1} + d (c_{t-1} - c_{t-2}) + σ_c e^{l_{t-1}} ε`` on the centre (``d = 0.5``,
    ``σ_c = sigma_xy · sqrt(w_0 h_0)``), a random walk ``l_t = l_{t-1} + σ_l ε`` on the
    log-scale. The prior ``p_0`` is a Gaussian about the first box with zero velocity.
Likelihood
    :class:`~vistrack.appearance.cues.Appearance`: colour histogram against the ring
    around the box (Bhattacharyya; the ring's weight ``κ`` 0.5 with the filter, 1 without)
    + normalised cross-correlation with a grey template,
    learned from the first frame and adapted on confident frames; with the correlation filter
    (``dcf``, on by default), plus ``λ_dcf`` times its response at the state
    (:class:`~vistrack.appearance.correlation.CorrelationFilter`: gradient-orientation and
    brightness-normalised grey features, a search at two scales about the dynamics' prediction,
    adapted on frames where the object is reported, anchored to the first frame's filter).
Local moves (thesis 001, §4.3–4.5)
    ``ls-n-ips``: ``LS_λ`` = mean shift on the back-projection of the target histogram
    (:meth:`Appearance.mean_shift`), the move rejected when it goes further than ``λ``
    (half the box's mean side) or lowers ``r`` (eq. 4.1). ``lis``: a grid of translations
    about the prediction with ``q`` from one per-frame map
    (:meth:`Appearance.proposal_map`; :class:`~vistrack.proposals.MapProposal`; the cell
    drawn by inversion of the cumulative ``q g``, the LIS step compiled in two calls:
    :meth:`lis_step`).
    ``lls``: the exact ``r`` on a grid of the window (:class:`~vistrack.proposals.Window`).
    With the correlation filter, ``lis``'s proposal is its response mixed with ``K``
    (:class:`~vistrack.models.box.correlation_proposal.CorrelationProposal`, exact density, proper weights).
Lost and found
    ``visible=0`` where the collapse test fires or, with the filter, the estimate's calibrated
    confidence is low; after a few such frames, a whole-frame search every third frame, coarse to fine,
    and the frames observed lean meanwhile (:mod:`~vistrack.models.box.lost`).
"""

from __future__ import annotations

import numpy as np

from ... import kernels
from ...appearance.correlation import CorrelationFilter
from ...appearance.cues import Appearance
from ...core.gaussian import diag_logpdf
from ...core.transition import is_prior
from ...proposals import MapProposal
from ...proposals.translation import TranslationMoves
from ..collapse import CollapseCheck
from ..innovation import ARInnovation
from ..protocol import VideoModelBase
from .correlation_proposal import CorrelationProposal
from .lost import LostAndFound
from .moves import BoxMoves
from .scale_filter import ScaleFilter

__all__ = ["Box"]


class Box(LostAndFound, BoxMoves, CollapseCheck, TranslationMoves, ARInnovation, VideoModelBase):
    """Box tracking model with appearance learned from the first frame.

    Parameters
    ----------
    frame : ndarray of shape (H, W, 3) uint8 BGR, or (H, W)
        The first frame.
    box : tuple of float
        ``(x, y, w, h)`` of the object in ``frame``.
    sigma_xy : float, > 0 or None
        Std of the centre's innovation per frame, as a share of ``sqrt(w_0 h_0)`` (``None``: 0.25 with
        the correlation filter, whose likelihood lets fast objects such as a kicked ball be followed;
        0.06 without).
    sigma_scale : float, > 0 or None
        Std of the log-scale's innovation per frame (``None``: 0.02 with the filter, whose scale search
        then moves the scale; 0.002 without).
    damping : float in [0, 1]
        ``d``: share of the last frame's velocity carried over.
    prior_std : tuple of float, > 0
        Std of ``p_0`` on the centre (share of ``sqrt(w_0 h_0)``) and on the log-scale.
    window : float, > 0
        LIS/LLS window std as a multiple of the innovation's std.
    map_stride : int, >= 1
        The LIS proposal map's step in working pixels (:meth:`Appearance.proposal_map`): 2 makes
        ``cv2.matchTemplate`` about 4x cheaper (0.12 against 0.46 ms on girl_otb) but lowers the success
        AUC on the real clips (girl 0.632 against 0.650, 12 seeds; hand 0.39 against 0.44, 24 and 36 seeds;
        car4 0.813 against 0.819): 1 by default (``docs/experiments.md``, speed).
    dcf : bool
        Learn a correlation filter (:class:`~vistrack.appearance.correlation.CorrelationFilter`) whose
        response is LIS's proposal (:class:`~vistrack.models.box.correlation_proposal.CorrelationProposal`) and a
        term ``λ_dcf y`` of ``log r``; ``False``: the colour/template map proposal alone.
    lambda_dcf : float, >= 0
        ``λ_dcf``, the weight of the response ``y`` (about 1 at the object) in ``log r``.
    dcf_share : float in [0, 1]
        ``β``: the share of particles drawn from the response (the rest from ``K``).
    dcf_tempering : tuple of float
        ``(t, s)``: the response's cells drawn ``∝ (1 - s) exp(t (y - max y)) / Σ + s / C``.
    dcf_scale_std : float, > 0
        ``σ_l`` of the proposal's log-scale about the best scale of the search.
    collapse_drop : float, > 0
        With the filter, the collapse test's ``drop`` (:attr:`collapse_options`: 55 without it): ``log r``
        at the estimate falls by 43-47 on the synthetic clip of ``tests/models/box/test_box_dcf.py`` when the object
        vanishes; 28 (the 7-clip mean AUC 0.690 against 0.685 with 35, and with the filter's rate 0.004
        0.695 and the hand held on 6 of 6 seeds: ``docs/experiments.md``).
    confidence, lost_confidence, redetect, reentry, every_cue
        What is reported lost and the confidence: :meth:`~vistrack.models.box.lost.LostAndFound.init_lost`.
    redetect_after, redetect_every, search_crop, search_peaks, search_stride, lean_when_lost
        How it is found again: :meth:`~vistrack.models.box.lost.LostAndFound.init_search`.
    dcf_options : dict or None
        Passed to :class:`~vistrack.appearance.correlation.CorrelationFilter` (unless given: its ``padding``
        ``4 sigma_xy``, so that the search region about the dynamics' prediction holds 4 innovation stds; two
        scales, ``n_scales`` 2: mean AUC over the 18 real clips 0.561, against 0.553 with one scale and 0.562 with
        three, which take a third more time; ``reuse``, the adaptation on the search's own patch:
        ``docs/experiments.md``).
    scale_filter : bool or dict
        Learn DSST's scale filter (:class:`~vistrack.models.box.scale_filter.ScaleFilter`, a dict: its
        options) beside the correlation filter; ``False``: none.
    lambda_scale : float, >= 0
        ``λ_s``, the weight of the scale filter's response at each state's log-scale in ``log r``.
    scale_proposal : {"filter", "dcf"}
        The correlation proposal's log-scale centre: the scale filter's refined peak, or the best of the
        correlation filter's scales. The scale filter with ``λ_s`` 20 and its peak as the proposal's
        scale were chosen by leave-one-clip-out cross-validation over the 18 real clips (mean AUC 0.548
        without it, 0.556–0.563 with it; each part alone less: ``benchmarks/tune_box.py``,
        ``docs/experiments.md``).
    **appearance
        Passed to :class:`~vistrack.appearance.cues.Appearance` (with the filter, ``lambda_colour`` 12,
        ``lambda_template`` 8, ``kappa`` 0.5, ``template_points`` 128 and ``whole_factor`` unless given).
    """

    dim = 6
    #: lost (``visible=0``) when ``log r`` at the estimate falls 55 below its running level
    #: (:mod:`~vistrack.models.collapse`): the largest fall while tracking girl, hand and car4
    #: (27 runs) was 43, an object that vanishes from a textured background falls by 75
    collapse_options = {"drop": 55.0}

    def __init__(self, frame, box, *, sigma_xy=None, sigma_scale=None, damping=0.5, prior_std=(0.04, 0.02),
                 window=2.5, map_stride=1, dcf=True, lambda_dcf=60.0, dcf_share=0.5, dcf_tempering=(60.0, 0.05),
                 dcf_scale_std=0.02, redetect=0.5, reentry=0.05, collapse_drop=28.0,
                 dcf_options=None, scale_filter=True, lambda_scale=20.0, scale_proposal="filter",
                 confidence=True, lost_confidence=None, redetect_after=3, redetect_every=3, search_crop=1.0,
                 search_peaks=3, search_stride=2, lean_when_lost=True, every_cue=False, **appearance):
        x, y, w, h = (float(v) for v in box)
        if not (np.isfinite([x, y, w, h]).all() and w > 0 and h > 0):
            raise ValueError(f"the init box needs a finite position and a positive size, got {tuple(box)}")
        self.frame_size = (frame.shape[1], frame.shape[0])
        self.size0 = np.array([w, h])
        if dcf:  # the colour and template terms weaker beside the filter's, and the colour ring's pull to larger
            # boxes halved (κ 0.5, not 1: with 1 the estimate's scale is 10-14 % too large on car4 and blurred
            # girl; 7-clip mean AUC 0.685 against 0.670, blur 0.639 against 0.588; docs/experiments.md)
            # (a 128-point template and a whole shrink factor: the same AUC over the 18 real clips for less time)
            appearance = {"lambda_colour": 12.0, "lambda_template": 8.0, "kappa": 0.5, "template_points": 128,
                          "whole_factor": True, **appearance}
        self.app = Appearance(frame, (x, y, w, h), **appearance)
        if sigma_xy is None:
            sigma_xy = 0.25 if dcf else 0.06
        if sigma_scale is None:
            sigma_scale = 0.02 if dcf else 0.002
        side = float(np.sqrt(w * h))
        self.sigma = np.array([sigma_xy * side, sigma_xy * side, sigma_scale])
        self.damping = np.array([damping, damping, 0.0])
        self.prior_std = np.array([prior_std[0] * side, prior_std[0] * side, prior_std[1]])
        self.init_pose = np.array([x + w / 2, y + h / 2, 0.0])
        self.prior_mean = np.concatenate([self.init_pose, self.init_pose])
        self.window = float(window)
        self.map_stride = int(map_stride)
        self.blob_cell = 0.25 * side  # the colour-blob proposal's cell (frame px)
        self.learn_blob(frame, _inner_ellipse(frame.shape[:2], (x, y, w, h)))
        # the search region: the box grown by 4 innovation stds of the centre on each side, about the prediction
        dcf_options = {"padding": 4.0 * sigma_xy, "n_scales": 2, "reuse": True, **(dcf_options or {})}
        self.cf = CorrelationFilter(frame, (x, y, w, h), **dcf_options) if dcf else None
        self._reach = 1.0 if dcf else 1.0 + self.window  # the observed region's reach, in 4 innovation stds
        if dcf:  # log r's scale with the filter's term: lost 28 below the running level
            self.collapse_options = {"drop": float(collapse_drop)}
        self.lambda_dcf, self.dcf_share, self.dcf_scale_std = float(lambda_dcf), float(dcf_share), float(dcf_scale_std)
        self.dcf_tempering = tuple(float(v) for v in dcf_tempering)
        self._d = self.damping  # this frame's damping: 0 on the frame after a re-detection (no velocity)
        if scale_proposal not in ("filter", "dcf"):
            raise ValueError(f"scale_proposal is 'filter' or 'dcf', got {scale_proposal!r}")
        sf_options = scale_filter if isinstance(scale_filter, dict) else {}
        self.sf = ScaleFilter(frame, (x, y, w, h), **sf_options) if (dcf and scale_filter) else None
        self.lambda_scale = float(lambda_scale)
        self.scale_proposal = scale_proposal
        self.init_lost(dcf, confidence, lost_confidence, redetect, reentry, every_cue)
        self.init_search(redetect_after, redetect_every, search_crop, search_peaks, search_stride, lean_when_lost)

    # -- geometry ---------------------------------------------------------------------
    def boxes(self, states):
        """``(N, 4)`` boxes ``(cx, cy, w, h)`` of ``states``."""
        s = np.atleast_2d(states)
        wh = self.size0 * np.exp(s[:, 2:3])
        return np.concatenate([s[:, :2], wh], axis=1)

    def box(self, states):
        """``(N, 4)`` boxes ``(x, y, w, h)`` (top-left corner) of ``states``."""
        b = self.boxes(states)
        return np.concatenate([b[:, :2] - b[:, 2:] / 2, b[:, 2:]], axis=1)

    def outline(self, states):
        """Box corners ``(N, 4, 2)`` for drawing."""
        x, y, w, h = self.box(states).T
        return np.stack([np.stack([x, y], 1), np.stack([x + w, y], 1), np.stack([x + w, y + h], 1),
                         np.stack([x, y + h], 1)], axis=1)

    def describe(self, state):
        """Track-file fields of one state: ``cx, cy, w, h, angle_deg, scale``."""
        cx, cy, w, h = self.boxes(state)[0]
        return {"cx": cx, "cy": cy, "w": w, "h": h, "angle_deg": 0.0, "scale": float(np.exp(np.ravel(state)[2]))}

    # -- dynamics ---------------------------------------------------------------------
    def _std(self, old):
        """Innovation std ``(N, 3)``: the centre's scales with the old box."""
        sd = np.broadcast_to(self.sigma, (len(old), 3)).copy()
        sd[:, :2] *= np.exp(old[:, 2:3])
        return sd

    def innovation_std(self, old):
        """Std ``(N, 3)`` of the current values given ``old`` (:class:`~vistrack.models.innovation.ARInnovation`)."""
        return self._std(old)

    def blob_image(self, obs):
        """The colour-blob proposal looks at the observation's region at the working resolution."""
        return obs.image, obs.x0, obs.y0, obs.f

    def predict_mean(self, states):
        """The mean of the AR(2) ``K``: ``z + d (z - z')``, with ``z`` as the new previous pose; ``(N, 6)`` ->
        ``(N, 6)``."""
        z1, z2 = states[:, :3], states[:, 3:]
        return np.concatenate([z1 + self._d * (z1 - z2), z1], axis=1)

    def predict(self, states, rng):
        """A draw from ``K``: the mean plus ``σ_c e^{l}`` noise on the centre and ``σ_l`` on the log-scale;
        ``(N, 6)`` -> ``(N, 6)``. On a frame of re-detection (the track lost, :attr:`redetect`) ``K`` has
        a share ``reentry`` of a centre uniform over the frame (drawn with ``rng.random((N, 3))`` after
        the normals)."""
        noise = rng.standard_normal((len(states), 3))
        if kernels.use():
            from .kernels import ar2_predict

            out = ar2_predict(np.ascontiguousarray(states, float), self._d, self.sigma, noise,
                              np.empty((len(states), 6)))
        else:
            out = self.predict_mean(states)
            out[:, :3] += self._std(states) * noise
        if self._reentry:
            u = rng.random((len(states), 3))
            pick = u[:, 0] < self.reentry
            out[pick, 0] = u[pick, 1] * self.frame_size[0]
            out[pick, 1] = u[pick, 2] * self.frame_size[1]
        return out

    def transition_logpdf(self, new, old):
        """``log K(new|old)``: Gaussian in the current values; the previous values of ``new``
        are the current values of ``old``. On a frame of re-detection, the centre's density is
        ``(1 - ε) N + ε / (W H)`` (:meth:`predict`)."""
        if kernels.use():
            from .kernels import ar2_logpdf

            out = ar2_logpdf(np.ascontiguousarray(new, float), np.ascontiguousarray(old, float), self._d,
                             self.sigma, np.empty(len(new)))
        else:
            out = diag_logpdf(new[:, :3], self.predict_mean(old)[:, :3], self._std(old))
        if self._reentry:
            log_l = diag_logpdf(new[:, 2:3], old[:, 2:3], self.sigma[2:3])
            w, h = self.frame_size
            out = log_l + np.logaddexp(np.log1p(-self.reentry) + out - log_l, np.log(self.reentry) - np.log(w * h))
        return out

    # -- observation --------------------------------------------------------------------
    def observe(self, maps, particles):
        """The frame's :class:`~vistrack.appearance.cues.AppearanceFrame` over the region the
        particles can reach: their predicted boxes grown by 4 innovation stds, the LIS window's
        reach (not with the correlation filter: its proposal has no window) and the velocity (the
        first box and the prior's spread on the first frame); with the
        correlation filter, that region and the filter's search region, and the filter's response
        there as ``obs.dcf``; while the track is lost, about a whole-frame search's find (:meth:`_redetect`)."""
        self._reentry = False
        self._d = np.zeros(3) if self._found else self.damping
        self._found = False
        if particles is None:
            states = self.prior_mean[None]
            reach = 4 * self.prior_std[0] * (1 + self.window)
            roi = self.app.roi(self.boxes(states), reach)
        elif kernels.use():
            from ...appearance.frame_kernels import predicted_roi

            roi = predicted_roi(np.ascontiguousarray(particles.states, float), self._d, self.size0,
                                4 * self.sigma[0], self._reach, float(self.app.ring), np.empty(4, np.int64))
            roi = tuple(int(v) for v in roi)
        else:
            states = self.predict_mean(particles.states)
            reach = 4 * self.sigma[0] * np.exp(states[:, 2].max()) * self._reach
            roi = self.app.roi(self.boxes(states), reach)
        if particles is None or self.cf is None:
            obs = self.app.frame(maps.frame, roi)
            obs.dcf, obs.dcf_share, obs.redetected, obs.frame_image = None, self.dcf_share, False, maps.frame
            return obs
        pred = self._pred = particles.weights @ self.predict_mean(particles.states)[:, :3]
        if self.search_due():
            found = self._redetect(maps.frame)
            if found is not None:
                return found
        return self._dcf_frame(maps.frame, roi, pred, self.dcf_share, False, lean=self.lean())

    def _dcf_frame(self, frame, roi, centre, share, redetected, scale=True, lean=False):
        """The observation over ``roi`` and the correlation filter's search region about ``centre``
        ``(cx, cy, l)``, with its response (``obs.dcf``; ``lean``: at ``l`` alone), ``β``, whether it is a
        re-detection and (``scale``, not ``lean``) the scale filter's response (:meth:`scale_response`)."""
        resp = self.cf.detect(frame, centre[:2], float(centre[2]), scales=(0.0,) if lean else None)
        (ox, oy), a = resp.cell_origin()
        h, w = resp.maps.shape[1:]
        grow = self.app.ring * float(np.sum(self.size0 * np.exp(resp.log_scales[-1])))
        x1, y1 = ox + a * (w - 0.5), oy + a * (h - 0.5)
        roi = (min(roi[0], int(np.floor(ox - grow))), min(roi[1], int(np.floor(oy - grow))),
               max(roi[2], int(np.ceil(x1 + grow))), max(roi[3], int(np.ceil(y1 + grow))))
        obs = self.app.frame(frame, roi)
        obs.dcf, obs.dcf_share, obs.redetected, obs.frame_image = resp, share, redetected, frame
        if scale and not lean:
            self.scale_response(frame, obs, centre)
        return obs

    def scale_response(self, frame, obs, centre):
        """The scale filter's response about the correlation filter's peak at the scales about ``centre[2]``
        (``obs.scale``) and, with ``scale_proposal`` ``"filter"``, its peak as the proposal's log-scale centre."""
        obs.scale = None if self.sf is None else self.sf.detect(frame, obs.dcf.peak_xy, float(centre[2]))
        if self.scale_proposal == "filter" and obs.scale is not None:
            obs.scale_centre = obs.scale.peak_log_scale

    def loglik(self, obs, states):
        """``log r`` of ``states (N, 6)``, shape ``(N,)``: the colour and template terms, plus
        ``λ_dcf`` times the correlation filter's response where the frame has one, plus ``λ_s`` times the
        scale filter's response at each state's log-scale where it has one."""
        out = self.collapse_loglik(obs, states)
        if obs.scale is not None and self.lambda_scale:
            out = out + self.lambda_scale * obs.scale.read(np.atleast_2d(states)[:, 2])
        return out

    def collapse_loglik(self, obs, states):
        """:meth:`loglik` without the scale filter's term, which says how well a size fits, not whether the
        object is there: the collapse test's ``log r`` (its ``drop`` was set on it; the scale term, about 20
        on the frames after the first and 5-10 once the filter has adapted, would otherwise lower the
        running level's reference and report a tracked object lost)."""
        if kernels.use():
            out = self.app.loglik_states(obs, np.ascontiguousarray(states, float), self.size0)
        else:
            out = self.app.loglik(obs, self.boxes(states))
        resp = obs.dcf
        if resp is not None and self.lambda_dcf:
            out = out + self.lambda_dcf * resp.read(np.atleast_2d(states))
        return out

    def estimate(self, particles):
        """The weighted mean state."""
        return particles.mean()

    def adapt(self, obs, estimate):
        """On a frame where the object is reported, adapt the appearance to the estimate where it is confident
        (:meth:`Appearance.adapt`) and the correlation filter (:meth:`CorrelationFilter.adapt`); a frame
        reported lost changes nothing."""
        if self._lost:
            return False
        done = self.app.adapt(obs, self.boxes(estimate)[0])
        resp = obs.dcf
        if resp is not None:
            e = np.asarray(estimate, float).ravel()
            self.cf.adapt(obs.frame_image, e[:2], float(e[2]), resp)
            if self.sf is not None:
                self.sf.adapt(obs.frame_image, e[:2], float(e[2]), obs.scale)
        return done

    # -- local moves (and :class:`~vistrack.models.box.moves.BoxMoves`) ------------------------
    def lis_proposal(self, kernel=None):
        """LIS's proposal for a step with ``kernel``: the correlation filter's response mixed with ``K``
        (:class:`CorrelationProposal`) with the filter after the first frame, else the colour/template map on a
        grid (:class:`MapProposal`)."""
        if self.cf is not None and kernel is not None and not is_prior(kernel):
            return CorrelationProposal(self, kernel)
        return MapProposal(self, kernel=kernel)


def _inner_ellipse(shape, box, share=0.8):
    """Mask ``(H, W)`` of the ellipse inscribed in ``share`` of the box (its corners are background)."""
    import cv2

    x, y, w, h = box
    mask = np.zeros(shape, np.uint8)
    cv2.ellipse(mask, (int(round(x + w / 2)), int(round(y + h / 2))),
                (max(1, int(round(share * w / 2))), max(1, int(round(share * h / 2)))), 0, 0, 360, 1, -1)
    return mask
