"""Shared by the tests: tiny real-style clips (a video or ``img/`` and OTB's 1-based ``groundtruth_rect.txt``,
no meta.json), and frames of an object that vanishes."""

import cv2
import numpy as np

from vistrack.io.video import VideoWriter


def square_clip(folder, frames=8, name=None, codec="mp4v"):
    """``folder/<name>.mp4`` (96×72, 25 frames/s) of a red square moving right by 1 px a frame on a
    flat grey background, and its boxes in ``folder/groundtruth_rect.txt`` (OTB's file: 1-based); returns
    them 0-based ``(frames, 4)``."""
    folder.mkdir(parents=True)
    gt = []
    with VideoWriter(folder / f"{name or folder.name}.mp4", 25, (96, 72), codec=codec) as w:
        for t in range(frames):
            img = np.full((72, 96, 3), 40, np.uint8)
            img[20:40, 20 + t:40 + t] = (40, 60, 220)
            w.write(img)
            gt.append((20 + t, 20, 20, 20))
    np.savetxt(folder / "groundtruth_rect.txt", np.array(gt) + (1, 1, 0, 0), fmt="%d", delimiter=",")
    return np.array(gt, float)


def otb_clip(folder, n=8):
    """An OTB-style clip (img/ + 1-based groundtruth_rect.txt) of a square moving right."""
    (folder / "img").mkdir(parents=True)
    gt = []
    for t in range(n):
        img = np.full((72, 96, 3), 40, np.uint8)
        img[20:40, 20 + t:40 + t] = (40, 60, 220)
        cv2.imwrite(str(folder / "img" / f"{t + 1:04d}.png"), img)
        gt.append((20 + t + 1, 21, 20, 20))  # 1-based
    np.savetxt(folder / "groundtruth_rect.txt", gt, fmt="%d", delimiter=",")
    return np.array(gt, float) - [1, 1, 0, 0]


#: :func:`vanishing_frames`: the object vanishes from this frame on
GONE = 20
#: :func:`vanishing_frames`: the object's first box (x, y, w, h)
BOX = (36, 42, 28, 36)


def vanishing_frames(n=34, gone=GONE):
    """An orange ellipse moving right 1 px per frame over a smooth random texture, gone from ``gone``."""
    rng = np.random.default_rng(0)
    bg = cv2.GaussianBlur(rng.integers(60, 190, (120, 160, 3)).astype(np.uint8), (0, 0), 2)
    frames = []
    for t in range(n):
        f = bg.copy()
        if t < gone:
            cv2.ellipse(f, (50 + t, 60), (14, 18), 0, 0, 360, (30, 120, 230), -1)
        frames.append(f)
    return frames


def tiny_otb_clip(folder, frames=12):
    """An OTB-layout clip (img/ + 1-based groundtruth_rect.txt): a red square moving right on grey noise."""
    rng = np.random.default_rng(3)
    bg = cv2.GaussianBlur(rng.integers(40, 200, (72, 96, 3)).astype(np.uint8), (0, 0), 1.5)
    (folder / "img").mkdir(parents=True)
    lines = []
    for t in range(frames):
        f = bg.copy()
        f[26:46, 20 + t:40 + t] = (20, 30, 220)
        cv2.imwrite(str(folder / "img" / f"{t + 1:04d}.png"), f)
        lines.append(f"{21 + t},27,20,20")
    (folder / "groundtruth_rect.txt").write_text("\n".join(lines) + "\n")
    return folder
