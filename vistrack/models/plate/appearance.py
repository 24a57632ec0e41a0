"""The plate model's learned appearance on real footage: the box model's colour and template
terms and its correlation filter on the plate's box, learned from a start box or a detection, and the
plate searched for again while it is not reported. A mixin of :class:`~vistrack.models.plate.model.Plate`."""

from __future__ import annotations

import numpy as np

from .observation import PlateObservation

__all__ = ["PlateAppearance"]


class PlateAppearance:
    """What :class:`~vistrack.models.plate.model.Plate` learns of a real plate (module docstring)."""

    #: :class:`~vistrack.appearance.cues.Appearance` of the plate in the first frame
    #: (:meth:`learn_appearance`); ``None``: the plate likelihood alone
    app = None

    def learn_appearance(self, frame, box, **params):
        """Add the box model's appearance term, learned from the plate at ``box (x, y, w, h)``
        in the first ``frame``: ``log r = log r_plate + log r_app`` on the parallelogram's
        bounding box. The plate likelihood was fitted to rendered plates; the learned colour
        and template follow a plate of any colour and font (a yellow plate, a white plate on
        a white car). Returns the :class:`~vistrack.appearance.cues.Appearance`."""
        from ...appearance.cues import Appearance

        self.app = Appearance(frame, box, **{"anchor_min_ncc": self.anchor_min_ncc, "adapt_rate": self.adapt_rate,
                                             **params})
        if self.lambda_dcf:
            from ...appearance.correlation import CorrelationFilter

            self.cf = CorrelationFilter(frame, box, **self.dcf_options)
            self._s0 = float(box[2])
        return self.app

    #: the box model's correlation filter (:class:`~vistrack.appearance.correlation.CorrelationFilter`) on the
    #: plate's box, learned with the appearance; its response at a state's centre and width is the term
    #: ``λ_dcf y`` of ``log r`` (``lambda_dcf``; 0: none)
    cf = None
    _s0 = 1.0  # the start box's width: the filter's scale 1
    _reported = False  # the last frame's estimate was reported (:meth:`check_lost`)

    def dcf_states(self, states):
        """``(N, 3)`` ``(u, w, log(s / s_0))``: where the correlation filter's response is read."""
        s = np.atleast_2d(states)
        return np.stack([s[:, 0], s[:, 1], np.log(s[:, 3] / self._s0)], axis=1)

    #: the first view as anchor (:class:`~vistrack.appearance.cues.Appearance`'s ``anchor_min_ncc``):
    #: the learned appearance adapts only on frames whose estimate also matches the first frame's plate
    anchor_min_ncc = 0.5
    #: the learned appearance's adaptation rate (:class:`~vistrack.appearance.cues.Appearance`'s
    #: ``adapt_rate``): 0, the first view kept. The template reads the parallelogram's axis-aligned
    #: box, which grows with the angle; adapted (0.1, the box model's rate), it learns the taller box
    #: of a slightly tilted estimate and the angle drifts to 2 degrees on the dashcam clip (the
    #: reported box 12 % too high; docs/experiments.md). The correlation filter
    #: (:attr:`lambda_dcf`) is the part that adapts.
    adapt_rate = 0.0

    def observe(self, maps, particles):
        """The frame's :class:`~vistrack.models.plate.likelihood.PlateObservation`: the feature maps,
        the likelihood's 4-channel map and (when the model has an appearance) the appearance maps at
        the appearance's working resolution over the region the tracked particles can reach — their
        predicted boxes grown by 8 innovation stds (the start box and 4 of its stds on the first
        frame); births elsewhere get small frames of their own when their term is needed
        (:meth:`PlateObservation.appearance_frames`). All are cut from one resize of the whole
        frame, so a box scores as it would on the whole frame's maps whichever region holds it."""
        app = build = None
        if self.app is not None:
            frame = maps.frame
            if particles is None:
                states = self.prior_mean[None]
                reach = 4 * float(np.max(self.start[1][:2])) if self.start is not None else 0.0
            else:
                tracked = ~self.entering(particles.states)
                states = self.predict_mean(particles.states[tracked] if tracked.any() else particles.states)
                reach = 8 * float(np.max(self.sigma[:2])) + 2 * float(self.sigma[3])
            work = self.app.work_image(frame)  # one resampling for every region of this frame
            app = self.app.frame(frame, self.app.roi(self.app_boxes(states), reach), work)

            def build(roi):
                return self.app.frame(frame, roi, work)
        obs = PlateObservation(maps, self.lik.maps(maps), app, build)
        if self.cf is not None and particles is not None:
            tracked = ~self.entering(particles.states)
            x = particles.states[tracked] if tracked.any() else particles.states
            wt = particles.weights[tracked] if tracked.any() else particles.weights
            c = (wt / wt.sum()) @ self.dcf_states(self.predict_mean(x))
            obs.dcf = self.cf.detect(maps.frame, c[:2], float(c[2]))
        return obs

    def _app_terms(self, obs, states):
        """The appearance's ``(log r_c, log r_t, ncc)`` of ``states``, each box read on a frame that
        covers it (:meth:`PlateObservation.appearance_frames`)."""
        b = self.app_boxes(states)
        grow = self.app.ring * 0.5 * (b[:, 2] + b[:, 3])
        out = np.empty((3, len(b)))
        for frame, idx in obs.appearance_frames(b, grow, margin=float(np.median(b[:, 2]))):
            out[:, idx] = self.app.terms(frame, b[idx])
        return out

    def app_boxes(self, states):
        """The appearance's boxes ``(N, 4)`` ``(cx, cy, w, h)``: the parallelograms' axis-aligned boxes."""
        x, y, w, h = self.box(states).T
        return np.stack([x + w / 2, y + h / 2, w, h], axis=1)

    def adapt(self, obs, estimate):
        """Adapt the appearance on a confident frame (:meth:`Appearance.adapt`); with a :attr:`detector`,
        set the next step's births (:meth:`redetect`)."""
        if self.app is None:
            return False
        b = self.app_boxes(estimate)
        frame = obs.appearance_frames(b, self.app.ring * 0.5 * (b[:, 2] + b[:, 3]), margin=float(b[0, 2]))[0][0]
        adapted = self.app.adapt(frame, b[0])
        if obs.dcf is not None and self._reported:
            e = self.dcf_states(estimate)[0]
            self.cf.adapt(obs.maps.frame, e[:2], float(e[2]))
        if self.detector is not None:
            self.redetect(obs, estimate)
        return adapted

    # -- re-detection while the plate is not reported (real footage) ---------------------------
    #: a :class:`~vistrack.models.plate.detect.PlateDetector` (set for real footage, with a learned
    #: appearance): while the estimate is not reported, the plate is searched for again (:meth:`redetect`)
    detector = None
    #: the weight of the births at a re-detected plate (the entering component's, for the next step)
    redetect_weight = 0.2
    _births = None  # the saved (enter_weight, entering parts) while the births sit at a detection

    def redetect(self, obs, estimate):
        """The births of the next step (the entering component of ``K``, chosen after this frame, so a
        function of the frames so far): while the estimate is not reported (:meth:`visible`), a
        Gaussian about the detection (:attr:`detector`) that matches the first frame's plate best
        (template correlation at least :attr:`anchor_min_ncc`), with weight :attr:`redetect_weight`
        and the ``--init`` spread; else the model's own entering component (none for a plate from a
        box). A plate model started from a box has no births, so once lost (a shaking camera moved
        the plate out of the dynamics' reach) it stayed lost. Returns whether births were set."""
        s = np.asarray(estimate, float).reshape(1, -1)
        pose = None
        if not self.visible(obs, s[0]):
            dets = self.detector.detect(obs.maps.frame)
            if dets:
                boxes = np.array([[d.box[0] + d.box[2] / 2, d.box[1] + d.box[3] / 2, d.box[2], d.box[3]] for d in dets])
                grow = self.app.ring * 0.5 * (boxes[:, 2] + boxes[:, 3])
                ncc = np.full(len(boxes), -np.inf)
                for frame, idx in obs.appearance_frames(boxes, grow, margin=float(np.median(boxes[:, 2]))):
                    ncc[idx] = [self.app.anchor_ncc(frame, b) for b in boxes[idx]]
                k = int(np.argmax(ncc))
                if ncc[k] >= (self.anchor_min_ncc if self.anchor_min_ncc is not None else -np.inf):
                    pose = np.array([boxes[k, 0], boxes[k, 1], 0.0, boxes[k, 2]])
        if self._births is None and pose is not None:
            self._births = (self.enter_weight, self._enter_parts)
        if pose is not None:
            std = np.array([0.05 * pose[3], 0.05 * pose[3] / self.layout.aspect, 0.03, 0.05 * pose[3]])
            self.enter_weight, self._enter_parts = self.redetect_weight, [(1.0, pose, std)]
        elif self._births is not None:
            (self.enter_weight, self._enter_parts), self._births = self._births, None
        return pose is not None

    # -- likelihood and output ------------------------------------------------------
