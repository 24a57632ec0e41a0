"""A box model whose likelihood is a learned Siamese network's response (beyond the seeds; thesis 001 §4.5:
the local proposal may use any approximation of the likelihood, and a learned response is the best one to
hand).

State
    ``(cx, cy, lw, lh, cx', cy', lw', lh')``, shape ``(N, 8)``: the box's centre (px) and log-size relative to
    the first box (``w = w_0 e^lw``, ``h = h_0 e^lh``), and the previous frame's values.
Dynamics ``K`` (AR(2) on the centre, as the box, contour and plate models)
    ``c_t = c_{t-1} + d (c_{t-1} - c_{t-2}) + σ sqrt(w_{t-1} h_{t-1}) ε``, ``σ`` = ``σ_c``, or ``σ_j`` with
    probability ``ε_j`` (a jump); a random walk on the log-size
    whose scale ``(lw + lh) / 2`` moves with std ``σ_s`` and aspect ``lw - lh`` with ``σ_a``. ``p_0``: a
    Gaussian about the first box with zero velocity.
Observation ``Y_t`` (:class:`~vistrack.models.siam.observation.SiamFrame`)
    one search crop per frame, NanoTrack v3's (:mod:`~vistrack.models.siam.network`), centred on the mean of
    the dynamics' predictions and sized by the last reported box (the authors' ``s_x``; ``widen``: wider while
    the cloud is spread, off by default: it cost 0.16 of the mean AUC, the object smaller than the exemplar in
    the crop): the head's logit ``ℓ`` and box ``b`` per cell.
Likelihood ``log r`` (vectorised over particles)
    ``λ ℓ(c)`` — the logit bilinearly interpolated at the particle's centre ``c`` (the map's lowest value
    outside the crop) — plus the agreement of the particle's box with the head's box ``b`` of the cell nearest
    its centre: ``-½ [((c - b_c) / (σ_b · (w_b, h_b)))² + ((l - b_l) / σ_bl)²]``.
LIS's local proposal (:class:`~vistrack.models.siam.proposal.ResponseProposal`)
    a Gaussian mixture over the map's strongest cells about their boxes, mixed with ``K``: exact density,
    proper weights.
Estimate
    the weighted mean of the particles within half a box of the heaviest mode (:meth:`Siam.estimate`): the cloud
    may hold a look-alike's mode too without the estimate falling between them.
"""

from __future__ import annotations

import math

import numpy as np

from ... import kernels
from ..innovation import ARPrior
from ..protocol import VideoModelBase
from .lost import SiamLost
from .network import CONTEXT, EXEMPLAR, INSTANCE, SiamNetwork, cell_points, context_side, crop
from .observation import SiamFrame, cell_boxes, colour_histogram
from .proposal import ResponseProposal

__all__ = ["Siam"]

_POINTS = cell_points(15)


class Siam(SiamLost, ARPrior, VideoModelBase):
    """Box tracking with a learned Siamese likelihood (module docstring).

    Parameters
    ----------
    frame : ndarray of shape (H, W, 3) uint8 BGR, or (H, W)
        The first frame.
    box : tuple of float
        ``(x, y, w, h)`` of the object in ``frame``.
    sigma_xy : float, > 0
        ``σ_c``: the centre's innovation std per frame as a share of the box's side ``sqrt(w h)``.
    sigma_jump : float, > 0
        The std of a jump (a fast move, a shaking camera), as a share of the side.
    jump_share : float in [0, 1]
        The centre's innovation is a mixture: a share ``jump_share`` with std ``sigma_jump``, the rest ``σ_c``
        (0: Gaussian).
    jump_when_lost : bool
        The jump share only on frames after one reported lost (a tracked object moves as ``σ_c`` says).
    sigma_scale : float, >= 0
        ``σ_s``: the innovation std of the log-scale per frame.
    sigma_aspect : float, >= 0
        ``σ_a``: the innovation std of the log-aspect per frame.
    damping : float in [0, 1]
        ``d``: the share of the last frame's velocity carried over.
    prior_std : tuple of float, > 0
        ``p_0``'s std on the centre (share of the side) and on the log-sizes.
    lambda_logit : float, >= 0
        ``λ``: the weight of the logit in ``log r``.
    box_std : tuple of float, > 0
        ``(σ_b, σ_bl)``: the agreement's std of the centre (share of the head's box size) and of the log-sizes.
    box_gate : bool
        Weigh the agreement by the cell's object probability ``σ(ℓ)``.
    share : float in [0, 1]
        ``β``: the share of particles LIS draws from the response (the rest from ``K``).
    cells : int, >= 1
        ``C``: the strongest cells in the response mixture.
    tempering : float, >= 0
        ``τ``: the mixture's weights ``∝ exp(τ ℓ)``.
    spread : tuple of float, > 0
        ``(s_c, s_l)``: each mixture component's std of the centre (share of its box's size) and the log-sizes.
    mode_radius : float, > 0
        The estimate's mode: the particles within this share of the box's side of the heaviest one.
    widen : float, >= 1
        The search crop's side grows with the cloud's centre spread: ``s_x · max(1, min(widen, 1 + 2 spread / s_x))``
        (``1``: never).
    confidence : bool, str or tuple
        ``True``: the package's calibrations; ``False``: none; the path of an ``.npz`` holding them, or a pair of
        :class:`~vistrack.models.calibration.Calibration` (:meth:`~vistrack.models.siam.lost.SiamLost.init_lost`).
    lost_confidence : float in [0, 1] or None
        The threshold below which the object is reported lost (``None``: the calibration's).
    redetect_after : int, >= 1 or None
        The lost frames before the first wide search (``None``: never search).
    search_every : int, >= 1
        The lost frames between searches at first; the gap doubles up to ``search_cap``.
    search_peaks : int, >= 1
        The wide search's candidates, each confirmed with a normal crop.
    search_cap : int, >= 1
        The longest gap between searches.
    exemplar_rate : float in [0, 1]
        ``η`` of the exemplar's update (:meth:`adapt`): every ``exemplar_every``-th frame whose confidence is at
        least ``exemplar_confidence``, ``z ← (1 - η) z + η z_t`` with the exemplar features ``z_t`` of the
        estimate's box (0: the first frame's exemplar throughout).
    exemplar_every : int, >= 1
        The frames between the exemplar's updates.
    exemplar_confidence : float in [0, 1]
        The confidence a frame needs for the exemplar to learn from it.
    hold_when_lost : bool
        While the object is reported lost, the search crop stays about the last place it was reported (where a
        hidden object comes back), not about the cloud's prediction.
    network : SiamNetwork or None
        The network (a new one on the package's weights by default).
    """

    dim = 8

    def __init__(self, frame, box, *, sigma_xy=0.15, sigma_jump=0.6, jump_share=0.1, jump_when_lost=False,
                 sigma_scale=0.05, sigma_aspect=0.1, damping=0.5, prior_std=(0.04, 0.02), lambda_logit=1.0,
                 box_std=(0.03, 0.05), box_gate=False, share=0.7, cells=12, tempering=1.0, spread=(0.08, 0.05),
                 mode_radius=0.5, widen=1.0, confidence=True, lost_confidence=None, redetect_after=3, search_every=3,
                 search_peaks=3, search_cap=24, exemplar_rate=0.0, exemplar_every=5, exemplar_confidence=0.9,
                 hold_when_lost=False, network=None):
        x, y, w, h = (float(v) for v in box)
        if not (np.isfinite([x, y, w, h]).all() and w > 0 and h > 0):
            raise ValueError(f"the init box needs a finite position and a positive size, got {tuple(box)}")
        frame = _bgr(frame)
        self.frame_size = (frame.shape[1], frame.shape[0])
        self.size0 = np.array([w, h])
        self.side0 = float(np.sqrt(w * h))
        self.sigma_xy, self.damping = float(sigma_xy), float(damping)
        self.sigma_jump, self.jump_share = float(sigma_jump), float(jump_share)
        self.jump_when_lost = bool(jump_when_lost)
        self._jump = self.jump_share  # this frame's jump share
        self.sigma_scale, self.sigma_aspect = float(sigma_scale), float(sigma_aspect)
        self.prior_std = np.array([prior_std[0] * self.side0] * 2 + [prior_std[1]] * 2)
        self.init_pose = np.array([x + w / 2, y + h / 2, 0.0, 0.0])
        self.prior_mean = np.concatenate([self.init_pose, self.init_pose])  # p_0's mean: the first box, at rest
        self.lambda_logit = float(lambda_logit)
        self.box_std = tuple(float(v) for v in box_std)
        self.box_gate = bool(box_gate)
        self.share, self.cells, self.tempering = float(share), int(cells), float(tempering)
        self.spread = tuple(float(v) for v in spread)
        self.mode_radius, self.widen = float(mode_radius), float(widen)
        self.hold_when_lost = bool(hold_when_lost)
        self.net = network or SiamNetwork()
        self.fill = frame.reshape(-1, 3).mean(axis=0)
        s_z = float(context_side(w, h, CONTEXT))
        exemplar = crop(frame, self.init_pose[:2], s_z, EXEMPLAR, self.fill)
        self.net.set_exemplar(exemplar)
        half = 0.5 * EXEMPLAR / round(s_z) * np.array([w, h])  # the box in the exemplar crop
        c = (EXEMPLAR - 1) / 2
        self.colour0 = colour_histogram(exemplar, (c - half[0], c - half[1], c + half[0], c + half[1]))
        self.exemplar_rate, self.exemplar_every = float(exemplar_rate), max(1, int(exemplar_every))
        self.exemplar_confidence = float(exemplar_confidence)
        self._since_update = 0
        self.init_lost(confidence, lost_confidence, redetect_after, search_every, search_peaks, search_cap)

    # -- geometry --------------------------------------------------------------------------------------------
    def sizes(self, states):
        """``(N, 2)`` box sizes ``(w, h)`` of ``states``."""
        s = np.atleast_2d(states)
        return self.size0 * np.exp(s[:, 2:4])

    def box(self, states):
        """``(N, 4)`` boxes ``(x, y, w, h)`` (top-left corner) of ``states``."""
        s = np.atleast_2d(states)
        wh = self.sizes(s)
        return np.concatenate([s[:, :2] - wh / 2, wh], axis=1)

    def outline(self, states):
        """Box corners ``(N, 4, 2)`` for drawing."""
        x, y, w, h = self.box(states).T
        return np.stack([np.stack([x, y], 1), np.stack([x + w, y], 1), np.stack([x + w, y + h], 1),
                         np.stack([x, y + h], 1)], axis=1)

    def describe(self, state):
        """Track-file fields of one state: ``cx, cy, w, h, angle_deg, scale`` (the geometric mean of the
        two size ratios)."""
        s = np.ravel(state)
        w, h = self.sizes(s)[0]
        return {"cx": s[0], "cy": s[1], "w": w, "h": h, "angle_deg": 0.0, "scale": float(np.exp((s[2] + s[3]) / 2))}

    # -- dynamics --------------------------------------------------------------------------------------------
    def predict_mean(self, states):
        """The mean of ``K``: ``z + d (z - z')`` on the centre, ``z`` on the log-sizes; ``(N, 8)`` -> ``(N, 8)``."""
        z1, z2 = states[:, :4], states[:, 4:]
        mean = z1.copy()
        mean[:, :2] += self.damping * (z1[:, :2] - z2[:, :2])
        return np.concatenate([mean, z1], axis=1)

    def _innovation(self, old):
        """The centre's std ``(N,)`` (a share of the old box's side) and the log-size std pair."""
        return self.sigma_xy * self.side0 * np.exp((old[:, 2] + old[:, 3]) / 2)

    def predict(self, states, rng):
        """A draw from ``K``; ``(N, 8)`` -> ``(N, 8)`` (draws: ``rng.standard_normal((N, 4))``, then with a jump
        share ``rng.random(N)``: the centre's component)."""
        e = rng.standard_normal((len(states), 4))
        out = self.predict_mean(states)
        sc = self._innovation(states)
        if self._jump > 0:
            sc = np.where(rng.random(len(states)) < self._jump, sc * self.sigma_jump / self.sigma_xy, sc)
        out[:, :2] += sc[:, None] * e[:, :2]
        ds, da = self.sigma_scale * e[:, 2], self.sigma_aspect * e[:, 3]
        out[:, 2] += ds + da / 2
        out[:, 3] += ds - da / 2
        return out

    def transition_logpdf(self, new, old):
        """``log K(new|old)`` ``(N,)``: Gaussian in the centre, the log-scale and the log-aspect."""
        mean = self.predict_mean(old)
        sc = self._innovation(old)
        d = new[:, :2] - mean[:, :2]
        r2 = np.einsum("nk,nk->n", d, d)
        centre = -0.5 * r2 / sc ** 2 - 2 * np.log(sc)
        if self._jump > 0:
            sj = sc * self.sigma_jump / self.sigma_xy
            jump = np.log(self._jump) - 0.5 * r2 / sj ** 2 - 2 * np.log(sj)
            centre = np.logaddexp(np.log1p(-self._jump) + centre, jump)
        dl = new[:, 2:4] - mean[:, 2:4]
        ds = (dl[:, 0] + dl[:, 1]) / 2 / self.sigma_scale
        da = (dl[:, 0] - dl[:, 1]) / self.sigma_aspect
        return centre - 0.5 * (ds ** 2 + da ** 2) - np.log(self.sigma_scale * self.sigma_aspect) - 2 * np.log(2 * np.pi)

    # -- observation -------------------------------------------------------------------------------------------
    def search_side(self, pose, spread=0.0):
        """The search crop's side (frame px) about ``pose`` ``(cx, cy, lw, lh)``: the authors' ``s_x`` of its box,
        widened by the cloud's centre ``spread`` (px) up to :attr:`widen` times."""
        w, h = self.size0[0] * math.exp(pose[2]), self.size0[1] * math.exp(pose[3])
        p = CONTEXT * (w + h)
        s_x = math.sqrt((w + p) * (h + p)) * INSTANCE / EXEMPLAR  # the authors' s_z (context_side), scaled
        return s_x * max(1.0, min(self.widen, 1.0 + 2.0 * spread / s_x))

    def respond(self, frame, centre, side):
        """The network's response over the search crop of ``side`` px about ``centre``: a :class:`SiamFrame`."""
        patch = crop(frame, centre, side, INSTANCE, self.fill)
        logit, ltrb = self.net.search(patch)
        scale = INSTANCE / round(side)
        centre = np.array(centre, float)
        if kernels.use():
            from .kernels import cell_boxes_into

            boxes = cell_boxes_into(ltrb[0].astype(float), _POINTS, centre[0], centre[1], scale, self.size0[0],
                                    self.size0[1], np.empty((ltrb.shape[2] * ltrb.shape[3], 4)))
        else:
            boxes = cell_boxes(ltrb[0], centre, scale, self.size0)
        return SiamFrame(frame, centre, scale, logit[0].astype(float), boxes, self.size0, patch)

    def pose_terms(self, obs, pose):
        """``(ℓ, a)``: the logit at the centre of one ``pose`` ``(>=4,)`` and its box's agreement (the confidence's
        cues; ``log r = λ ℓ + a``)."""
        z = np.ascontiguousarray(pose, float)
        if kernels.use():
            from .kernels import pose_terms

            return tuple(pose_terms(z, *self.frame_args(obs), np.empty(2)))
        s = np.concatenate([z[:4], z[:4]])[None]
        return float(obs.logit_at(s[:, :2], float(obs.logit.min()))[0]), float(self.box_agreement(obs, s)[0])

    def colour_match(self, obs, pose):
        """The Bhattacharyya coefficient ``Σ sqrt(p q_0)`` of the colours in ``pose``'s box on the search crop with
        the first box's (a cue of the confidence: a look-alike of other colours scores low)."""
        if obs.crop is None:
            return 1.0
        half = 0.5 * obs.scale * self.size0 * np.exp(np.asarray(pose[2:4], float))
        c = (np.asarray(pose[:2], float) - obs.centre) * obs.scale + (obs.crop.shape[1] - 1) / 2
        p = colour_histogram(obs.crop, (c[0] - half[0], c[1] - half[1], c[0] + half[0], c[1] + half[1]))
        return float(np.sqrt(p * self.colour0).sum())

    def frame_args(self, obs):
        """What the compiled likelihood reads of a frame's response (:mod:`~vistrack.models.siam.kernels`): the
        logit map, the cells' boxes, the crop's geometry, the logit floor, ``σ_b``, ``σ_bl``, ``w_0``, ``h_0``, the
        gate."""
        return (obs.logit, obs.boxes, float(obs.centre[0]), float(obs.centre[1]), obs.scale / obs.cell_px,
                float(obs.size // 2), float(obs.logit.min()), self.box_std[0], self.box_std[1], float(self.size0[0]),
                float(self.size0[1]), self.box_gate)

    def observe(self, maps, particles):
        """The frame's :class:`SiamFrame`: one search crop about the mean of the dynamics' predictions
        (the first box on the first frame), sized by the predicted box and widened by the cloud's spread."""
        frame = _bgr(maps.frame)
        if particles is None:
            return self.respond(frame, self.init_pose[:2], self.search_side(self.init_pose))
        self._jump = self.jump_share if not self.jump_when_lost or self._lost_run else 0.0
        if self.searching():
            found = self.redetect_frame(frame)
            if found is not None:
                return found
        w = particles.weights
        if kernels.use():
            from .kernels import cloud_stats

            stats = cloud_stats(np.ascontiguousarray(particles.states, float), np.array(w), self.damping, np.empty(5))
            pred = self._pred = stats[:4]
            spread = float(stats[4])
        else:
            pred = self._pred = w @ self.predict_mean(particles.states)[:, :4]
            c = particles.states[:, :2] - w @ particles.states[:, :2]
            spread = float(np.sqrt(w @ np.einsum("ij,ij->i", c, c)))
        size = self.init_pose[2:] if self._reported is None else self._reported[2:]
        centre = self._reported[:2] if self.hold_when_lost and self._lost_run and self._reported is not None \
            else pred[:2]
        return self.respond(frame, centre, self.search_side(np.r_[centre, size], spread))

    def loglik(self, obs, states):
        """``log r`` of ``states (N, 8)`` -> ``(N,)``: ``λ`` times the logit at the centre plus the agreement
        with the nearest cell's box (module docstring)."""
        s = np.atleast_2d(states)
        floor = float(obs.logit.min())
        return self.lambda_logit * obs.logit_at(s[:, :2], floor) + self.box_agreement(obs, s)

    def box_agreement(self, obs, states):
        """The agreement ``(N,)`` of the boxes of ``states (N, >=4)`` with the head's box of the cell nearest each
        centre: ``-½ [((c - b_c) / (σ_b (w_b, h_b)))² + ((l - b_l) / σ_bl)²]``, with ``box_gate`` times the cell's
        object probability ``σ(ℓ)`` (a cell that sees no object says little of its size)."""
        k = obs.nearest_cell(states[:, :2])
        b = obs.boxes[k]
        wh = obs.size0 * np.exp(b[:, 2:4])
        dc = (states[:, :2] - b[:, :2]) / (self.box_std[0] * wh)
        dl = (states[:, 2:4] - b[:, 2:4]) / self.box_std[1]
        out = -0.5 * (np.einsum("nk,nk->n", dc, dc) + np.einsum("nk,nk->n", dl, dl))
        if self.box_gate:  # a cell's box counts as much as the head believes the object is there
            out = out / (1.0 + np.exp(-obs.logit.ravel()[k]))
        return out

    def estimate(self, particles):
        """The weighted mean of the particles within :attr:`mode_radius` of a box's side of the heaviest mode:
        the particle whose neighbours within that radius weigh most."""
        s, w = particles.states, particles.weights
        if kernels.use():
            from .kernels import mode_mean

            return mode_mean(np.ascontiguousarray(s, float), np.array(w), self.side0, self.mode_radius,
                             np.empty(s.shape[1]))
        side = self.side0 * np.exp((s[:, 2] + s[:, 3]) / 2)
        d = s[:, None, :2] - s[None, :, :2]
        near = np.einsum("ijk,ijk->ij", d, d) <= (self.mode_radius * side[:, None]) ** 2
        mass = near @ w
        k = int(np.argmax(mass))
        sel = near[k] * w
        return sel @ s / sel.sum()

    def adapt(self, obs, estimate):
        """Update the exemplar on a confident frame (the model's ``exemplar_*`` options); returns whether it did."""
        self._since_update += 1
        if (self.exemplar_rate <= 0 or self.conf_value is None or self.conf_value < self.exemplar_confidence
                or self._since_update < self.exemplar_every):
            return False
        s = np.ravel(estimate)
        w, h = self.size0 * np.exp(s[2:4])
        z = self.net.features(crop(obs.frame, s[:2], float(context_side(w, h, CONTEXT)), EXEMPLAR, self.fill))
        self.net.z = (1 - self.exemplar_rate) * self.net.z + self.exemplar_rate * z
        self._since_update = 0
        return True

    def lis_proposal(self, kernel=None):
        """LIS's proposal for a step with ``kernel``: the response mixture mixed with it
        (:class:`~vistrack.models.siam.proposal.ResponseProposal`)."""
        from ...core.transition import Transition

        return ResponseProposal(self, kernel if kernel is not None else Transition(self))


def _bgr(frame):
    """``frame`` as a BGR ``(H, W, 3)`` uint8 array (grey replicated)."""
    import cv2

    f = np.asarray(frame)
    return cv2.cvtColor(f, cv2.COLOR_GRAY2BGR) if f.ndim == 2 else f
