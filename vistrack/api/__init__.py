"""vistrack as a component: the OpenCV-shaped :class:`~vistrack.api.tracker.Tracker` and the TraX server."""
