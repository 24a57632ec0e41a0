"""The small items of issue 54 (item 5), each with its exact message: a missing camera is one ``Error:`` line
(none of OpenCV's own), a start box whose centre is outside the frame is refused with one line, and a
progress bar whose length is known has its total (``synth longterm``'s)."""

import json
import re
import subprocess
import sys

import cv2
import pytest

from cli_helpers import run


def test_a_missing_camera_is_one_error_line(tmp_path):
    if cv2.VideoCapture(0).isOpened():
        pytest.skip("this machine has a camera 0")
    res = subprocess.run([sys.executable, "-c", "from vistrack.cli import main; main()", "run", "0", "--init",
                          "1,1,10,10"], capture_output=True, text=True, cwd=tmp_path)  # OpenCV writes to fd 2
    assert res.returncode == 1
    assert res.stderr == "Error: cannot read 0: no camera with that index (and no file or folder named 0 here)\n"


@pytest.mark.parametrize("box, centre", [("150,100,30,30", "165,115"), ("-20,50,30,30", "-5,65"),
                                         ("10,110,20,30", "20,125")])
def test_a_start_box_whose_centre_is_outside_the_frame_is_refused(synth_clip, box, centre):
    clip = synth_clip("contour", frames=3, size=(160, 120), seed=1)
    code, _, err = run(["run", clip, "--model", "box", "--init", box, "-q"])
    assert code == 2
    assert err == (f"Error: --init box {box} lies outside the 160x120 frame (its centre {centre} is not in it): give "
                   "a box on the object\n")


def test_the_python_api_refuses_it_too():
    import numpy as np

    import vistrack

    with pytest.raises(ValueError) as e:
        vistrack.Tracker().init(np.zeros((120, 160, 3), np.uint8), (150, 100, 30, 30))
    assert str(e.value) == ("start box 150,100,30,30 lies outside the 160x120 frame (its centre 165,115 is not in "
                            "it): give a box on the object")


def test_synth_longterm_s_bar_has_its_total(tmp_path):
    code, out, err = run(["synth", "longterm", "--out", tmp_path / "lt", "--size", "160x120", "--gap", "0.2"])
    assert code == 0, err
    frames = json.loads((tmp_path / "lt" / "meta.json").read_text())["frames"]
    counts = re.findall(r"(\d+)/(\d+) \[", err)
    assert counts and all(int(t) == frames for _, t in counts) and counts[-1] == (str(frames), str(frames)), err
