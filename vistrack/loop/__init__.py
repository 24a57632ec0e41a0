"""The frame loop: one filter step per frame, and the timing of its stages."""
