"""Lost frames drawn (issue 54, item 4): on a frame reported lost (``visible=0``) the annotated video shows the
last box reported, dashed, with a red ``lost: <reason>`` tag, and a re-detected frame a green
``re-detected`` tag. Checked by the pixels of the written video against the clip's own frames."""

import csv

import cv2
import numpy as np
import pytest

from vistrack.session.plan import track_video

#: a long-term clip tracked into an H.264 video (over 2 s: conftest.py's rule)
pytestmark = pytest.mark.slow


def _frames(path):
    cap = cv2.VideoCapture(str(path))
    out = []
    while True:
        ok, frame = cap.read()
        if not ok:
            return out
        out.append(frame.astype(int))


def _tag(frame, source, colour):
    """The pixels of ``frame`` in the tag's ``colour`` (red or green, as written after H.264) that are not
    so in the clip's own ``source`` frame."""
    b, g, r = (frame[..., k] for k in range(3))
    sb, sg, sr = (source[..., k] for k in range(3))
    if colour == "red":
        return int(((r > 150) & (g < 90) & (b < 90) & ~((sr > 150) & (sg < 90) & (sb < 90))).sum())
    return int(((g > 120) & (r < 90) & (b < 90) & ~((sg > 120) & (sr < 90) & (sb < 90))).sum())


@pytest.fixture(scope="module")
def drawn(tmp_path_factory):
    """A long-term clip whose object leaves the frame (reported lost) and is found again, tracked into an
    annotated video: ``(rows, annotated frames, source frames)``."""
    from vistrack.data_synth.longterm_clip import make_longterm_clip

    d = tmp_path_factory.mktemp("lost")
    make_longterm_clip(d / "lt", size=(160, 120), seed=1, gap=0.5)
    track_video(d / "lt", init_gt="", max_frames=100, outputs={"out_path": d / "a.mp4", "track_path": d / "t.csv"})
    with open(d / "t.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    return rows, _frames(d / "a.mp4"), _frames(d / "lt" / "video.mp4")


def test_frames_reported_lost_carry_the_red_lost_tag_and_tracked_ones_do_not(drawn):
    rows, annotated, source = drawn
    lost = [int(r["frame"]) for r in rows if r["visible"] == "0"]
    shown = [int(r["frame"]) for r in rows if r["visible"] == "1"]
    assert len(lost) >= 10 and len(annotated) == len(rows)
    red = {i: _tag(annotated[i], source[i], "red") for i in range(len(rows))}
    assert min(red[i] for i in lost) > 500, red  # the tag: about 1000 px at 160x120
    assert max(red[i] for i in shown) < 200, red


def test_the_lost_box_is_the_last_one_reported_drawn_dashed_in_grey(drawn):
    rows, annotated, source = drawn
    first = next(k for k, r in enumerate(rows) if r["visible"] == "0" and k > 0 and rows[k - 1]["visible"] == "1")
    prev = rows[first - 1]
    x0, y0 = float(prev["cx"]) - float(prev["w"]) / 2, float(prev["cy"]) - float(prev["h"]) / 2
    x1, y1 = x0 + float(prev["w"]), y0 + float(prev["h"])
    frame, src = annotated[first], source[first]
    grey = (np.abs(frame - 200).max(axis=2) < 40) & ~(np.abs(src - 200).max(axis=2) < 40)
    ys, xs = np.nonzero(grey)
    on_edge = ((np.abs(xs - x0) < 3) | (np.abs(xs - x1) < 3) | (np.abs(ys - y0) < 3) | (np.abs(ys - y1) < 3)) & \
        (xs > x0 - 3) & (xs < x1 + 3) & (ys > y0 - 3) & (ys < y1 + 3)
    assert on_edge.sum() >= 8, (first, prev)


def test_a_redetected_frame_carries_the_green_tag(drawn):
    rows, annotated, source = drawn
    found = [int(r["frame"]) for r in rows if r.get("redetected") == "1"]
    assert found, "the clip's object is found again within its first 100 frames"
    others = [int(r["frame"]) for r in rows if r.get("redetected") == "0" and r["visible"] == "1"]
    green = {i: _tag(annotated[i], source[i], "green") for i in found + others}
    assert min(green[i] for i in found) > 500 and max(green[i] for i in others) < 300, green
