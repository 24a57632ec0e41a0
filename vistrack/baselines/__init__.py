"""The trackers vistrack is compared with (OpenCV's)."""
