"""When a track has lost its object: the collapse test behind ``visible=0`` and ``lost_reason``.

The frame loop (:class:`~vistrack.loop.stepper.Stepper`) asks the model once per frame,
in order, :meth:`check_lost(obs, estimate) <CollapseCheck.check_lost>`; the answer is the
track CSV's ``visible`` and ``lost_reason`` columns and what ``vistrack run`` says when it
loses the object. A model whose estimate collapses is reported lost with one of
:data:`REASONS`:

``out-of-frame``
    the estimate's centre outside the frame;
``collapse``
    the estimate's scale below ``scale_floor`` (0.3) of the first frame's (the contour or
    box has shrunk towards a point), or ``log r`` at the estimate far below its running level
    (the median over the last ``window`` = 30 frames where the object was reported): more
    than ``drop`` below it (a difference, for likelihoods of any sign: the box model, 55), or
    under ``ratio`` times it (for a positive level: the contour's edge evidence, 0.15); or not
    finite (the detail says which);
``low-confidence``
    a model with a calibrated confidence (the box model's, :mod:`~vistrack.models.box.confidence`)
    found it below its threshold, the estimate unlike the object.

A frame reported lost does not enter the running level, so the track stays lost until
the likelihood at the estimate comes back. The test looks at the estimate only, not at
ground truth: a tracker that follows a look-alike (another face, skin of the same
colour) scores as well there as on the object and stays ``visible=1``; what it catches
is an estimate that no longer explains the frame (the object gone, occluded by
something unlike it, the curve shrunk to a point).
"""

from __future__ import annotations

from collections import deque

import numpy as np

from ..io.track_files import LOST_REASONS

__all__ = ["REASONS", "CollapseWatch", "CollapseCheck"]

#: the ``lost_reason`` codes a model's verdict gives (the track CSV's column) and what they mean: those of
#: :data:`vistrack.io.track_files.LOST_REASONS`, the one list, that are not about frames left untracked
REASONS = {k: LOST_REASONS[k] for k in ("low-confidence", "collapse", "out-of-frame", "not found")}


class CollapseWatch:
    """The running state of the collapse test of one track (module docstring).

    Parameters
    ----------
    scale_floor : float
        Lost when the scale is below this share of the first frame's scale.
    drop : float or None
        Lost when ``log r < level - drop``.
    ratio : float or None
        Lost when the level is positive and ``log r < ratio · level``.
    window : int
        Frames in the running level (their median).
    warmup : int
        Frames reported before the likelihood test starts.
    """

    def __init__(self, *, scale_floor=0.3, drop=None, ratio=None, window=30, warmup=5):
        self.scale_floor, self.drop, self.ratio = float(scale_floor), drop, ratio
        self.warmup = int(warmup)
        self.history = deque(maxlen=int(window))
        self.scale0 = None

    @property
    def level(self):
        """The running level of ``log r`` (``None`` before any frame was reported): the median of the
        history (finite values), as ``np.median`` computes it, by a sort of at most ``window`` floats."""
        if not self.history:
            return None
        s = sorted(self.history)
        k = len(s) // 2
        return float(s[k]) if len(s) % 2 else float((s[k - 1] + s[k]) / 2.0)

    def _likelihood(self, loglik):
        if not np.isfinite(loglik):
            return f"log r at the estimate is {loglik}"
        if len(self.history) < self.warmup:
            return ""
        level = self.level
        if self.drop is not None and loglik < level - self.drop:
            return f"log r at the estimate {loglik:.1f}, more than {self.drop:g} below its running level {level:.1f}"
        if self.ratio is not None and level > 0 and loglik < self.ratio * level:
            return f"log r at the estimate {loglik:.1f}, under {self.ratio:g} of its running level {level:.1f}"
        return ""

    def check(self, loglik, scale, centre, frame_size, low=""):
        """``(reason, detail)`` for one frame's estimate: ``("", "")`` when it is reported,
        else a :data:`REASONS` code and a sentence with the numbers (``low``: the model's sentence
        when its confidence is below its threshold, ``""`` otherwise). Updates the running level
        (a reported frame) and, on the first call, the reference scale."""
        if self.scale0 is None:
            self.scale0 = float(scale)
        (x, y), (w, h) = centre, frame_size
        if not scale >= self.scale_floor * self.scale0:
            out = "collapse", f"scale {scale:.3g}, below {self.scale_floor:g} of the first frame's {self.scale0:.3g}"
        elif not (0 <= x < w and 0 <= y < h):
            out = "out-of-frame", f"centre ({x:.1f}, {y:.1f}) outside the {w}x{h} frame"
        else:
            detail = self._likelihood(float(loglik))
            out = ("collapse", detail) if detail else ("low-confidence", low) if low else ("", "")
        if not out[0]:
            self.history.append(float(loglik))
        return out


class CollapseCheck:
    """Mixin for a video model with ``loglik``, ``describe`` (``cx``, ``cy``, ``scale``) and
    ``frame_size``: :meth:`check_lost` by a :class:`CollapseWatch` made from
    :attr:`collapse_options` on the first frame."""

    #: keyword arguments of the model's :class:`CollapseWatch`
    collapse_options: dict = {}
    _collapse = None

    @property
    def collapse_level(self):
        """The running level of ``log r`` (:attr:`CollapseWatch.level`; ``None`` before a frame was reported)."""
        return None if self._collapse is None else self._collapse.level

    def check_lost(self, obs, state, low=""):
        """``(reason, detail)``: ``("", "")`` when the object is reported at the frame's
        estimate ``state``, else why not (:data:`REASONS`; ``low``: the model's sentence when its
        confidence is below its threshold). Called once per frame, in order, by the frame loop (it
        keeps the running level)."""
        if self._collapse is None:
            self._collapse = CollapseWatch(**self.collapse_options)
        s = np.asarray(state, float).reshape(1, -1)
        scale, cx, cy = self.collapse_pose(s[0])
        return self._collapse.check(float(self.collapse_loglik(obs, s)[0]), float(scale), (float(cx), float(cy)),
                                    self.frame_size, low)

    def collapse_loglik(self, obs, states):
        """The ``log r`` the test watches (``(N,)`` of ``states``): :meth:`loglik` (a model whose ``log r``
        has terms that say how well a pose fits, not whether the object is there, leaves them out)."""
        return self.loglik(obs, states)

    def collapse_pose(self, state):
        """``(scale, cx, cy)`` of ``state`` that the test reads: :meth:`describe`'s (a model whose
        :meth:`describe` does more, e.g. the contour's outline, gives them directly)."""
        d = self.describe(state)
        return d["scale"], d["cx"], d["cy"]
