"""Shared by the tests: a tiny real-style clip (a video and ``groundtruth_rect.txt``, no meta.json)."""

import numpy as np

from vistrack.io.video import VideoWriter


def square_clip(folder, frames=8, name=None, codec="mp4v"):
    """``folder/<name>.mp4`` (96×72, 25 frames/s) of a red square moving right by 1 px a frame on a
    flat grey background, and its 0-based boxes in ``folder/groundtruth_rect.txt``; returns them
    ``(frames, 4)``."""
    folder.mkdir(parents=True)
    gt = []
    with VideoWriter(folder / f"{name or folder.name}.mp4", 25, (96, 72), codec=codec) as w:
        for t in range(frames):
            img = np.full((72, 96, 3), 40, np.uint8)
            img[20:40, 20 + t:40 + t] = (40, 60, 220)
            w.write(img)
            gt.append((20 + t, 20, 20, 20))
    np.savetxt(folder / "groundtruth_rect.txt", gt, fmt="%d", delimiter=",")
    return np.array(gt, float)
