"""One rule for 1-based ground truth (issue 54, item 3): the file's name and its dataset's convention decide
whether it counts pixels from 1, not whether an ``img/`` folder is beside it. The same OTB sequence as
``img/`` + ``groundtruth_rect.txt`` and as ``seq.mp4`` + ``groundtruth_rect.txt`` starts from the same box
and scores the same."""

import csv
import json
import shutil

import cv2
import numpy as np
import pytest

from cli_helpers import run
from vistrack.io.clip_files import groundtruth_origin
from vistrack.io.clips import load_clip
from vistrack.io.starts import start_box


@pytest.fixture(scope="module")
def layouts(tmp_path_factory):
    """``(img, mp4)``: one sequence as OTB's image folder and as a video beside the same 1-based
    ``groundtruth_rect.txt``; the images are the video's decoded frames, so both give the same pixels."""
    from vistrack.data_synth.contour_clip import make_contour_clip

    root = tmp_path_factory.mktemp("layouts")
    make_contour_clip(root / "synth", frames=8, size=(160, 120), seed=2, clutter="low", distractor=False, model="box")
    truth = load_clip(root / "synth").truth
    lines = "".join(f"{cx - w / 2 + 1:.2f},{cy - h / 2 + 1:.2f},{w:.2f},{h:.2f}\n"  # OTB: 1-based
                    for cx, cy, w, h in zip(truth["cx"], truth["cy"], truth["w"], truth["h"]))
    img, mp4 = root / "Seq", root / "seq_mp4"
    (img / "img").mkdir(parents=True)
    mp4.mkdir()
    cap = cv2.VideoCapture(str(root / "synth" / "video.mp4"))
    k = 0
    while True:
        ok, frame = cap.read()
        if not ok:
            break
        k += 1
        cv2.imwrite(str(img / "img" / f"{k:04d}.png"), frame)
    shutil.copy(root / "synth" / "video.mp4", mp4 / "seq.mp4")
    for folder in (img, mp4):
        (folder / "groundtruth_rect.txt").write_text(lines)
    return img, mp4, truth


def test_both_layouts_read_the_same_boxes_and_the_same_first_box(layouts):
    img, mp4, truth = layouts
    assert groundtruth_origin(img / "groundtruth_rect.txt") == groundtruth_origin(mp4 / "groundtruth_rect.txt") == 1
    a, b = load_clip(img).truth, load_clip(mp4 / "seq.mp4").truth
    for key in ("cx", "cy", "w", "h"):
        np.testing.assert_allclose(a[key], b[key])
        np.testing.assert_allclose(a[key], truth[key], atol=0.006)  # the 0-based truth, to the file's 2 decimals
    assert start_box(load_clip(img), None, "") == start_box(load_clip(mp4 / "seq.mp4"), None, "")


def test_both_layouts_track_and_score_the_same(layouts, tmp_path):
    img, mp4, _ = layouts
    said = []
    for name, clip in (("img", img), ("mp4", mp4 / "seq.mp4")):
        code, out, err = run(["run", clip, "--init-gt", "-n", "30", "--track", tmp_path / f"{name}.csv"])
        assert code == 0, err
        said.append(next(line for line in out.splitlines() if line.startswith("vs ground truth")))
    assert said[0] == said[1]

    def track(name):  # every column but the milliseconds spent
        with open(tmp_path / f"{name}.csv", newline="") as f:
            return [{k: v for k, v in row.items() if k != "ms"} for row in csv.DictReader(f)]

    assert track("img") == track("mp4")


def test_the_first_line_pasted_as_init_gets_the_note_in_both_layouts(layouts):
    img, mp4, _ = layouts
    first = (img / "groundtruth_rect.txt").read_text().splitlines()[0]
    x, y, w, h = (float(v) for v in first.split(","))
    for clip in (img, mp4 / "seq.mp4"):
        code, _, err = run(["run", clip, "--init", first, "--max-frames", "2", "-n", "20"])
        assert code == 0, err
        assert f"note: --init {x:g},{y:g},{w:g},{h:g} is the first box of " in err
        assert f"where that box is {x - 1:g},{y - 1:g},{w:g},{h:g}: --init-gt starts from it" in err


@pytest.mark.parametrize("name, beside, origin", [
    ("groundtruth_rect.txt", [], 1),                               # OTB's file, with or without img/
    ("groundtruth.txt", [], 0),                                    # VOT's, GOT-10k's
    ("groundtruth.txt", ["full_occlusion.txt"], 1),                # LaSOT's, by its flags
    ("groundtruth.txt", ["out_of_view.txt"], 1),
    ("groundtruth_rect.txt", ["perturb.json"], 0),                 # a clip vistrack wrote (synth perturb)
    ("groundtruth_rect.txt", ["composite.json"], 0),               # synth plate-on-car
    ("boxes.txt", [], 0),                                          # any other file (--init-gt FILE)
])
def test_the_name_and_the_dataset_decide_the_origin(tmp_path, name, beside, origin):
    for folder in ("with_img", "without"):
        d = tmp_path / folder
        d.mkdir()
        if folder == "with_img":
            (d / "img").mkdir()
        (d / name).write_text("10,10,5,5\n")
        for f in beside:
            (d / f).write_text(json.dumps({"source": "x"}) if f.endswith(".json") else "0\n")
        assert groundtruth_origin(d / name) == origin, (folder, name, beside)
