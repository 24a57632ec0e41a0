"""One run: the frame loop (:mod:`~vistrack.track.loop`), ``vistrack run``'s session and summary,
signals, stage timing, the OpenCV-shaped :class:`~vistrack.track.tracker.Tracker` and the TraX
server."""
