"""Faults that break synthetic clips and their folders: a failed, killed or terminated synth leaves the
earlier clip whole; a suite or clip written over another folder's data is refused; stressed copies say
what they did."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import warnings

import numpy as np
import pytest

from cli_helpers import run
from fault_helpers import (
    clip_bytes,
    image_folder,
    one_error,
    otb_folder,
)
from process_helpers import PATIENCE, wait_until


def test_a_failed_synth_leaves_the_old_clip_whole(tmp_path, monkeypatch):
    """The writer fails mid-clip (disk full) while a clip is overwritten: the old clip is intact,
    no partial folder is left, the user's own files in the folder survive a successful overwrite."""
    import vistrack.data_synth.contour_clip as contour
    from vistrack.io.clips import find_clips

    clip = tmp_path / "suite" / "c1"
    kw = dict(frames=4, size=(96, 72), clutter="low", distractor=False)
    contour.make_contour_clip(clip, seed=1, **kw)
    (clip / "notes.txt").write_text("mine")
    old = clip_bytes(clip)

    class Full(contour.VideoWriter):
        def write(self, frame):
            if self.frames == 2:
                raise OSError(28, "No space left on device")
            super().write(frame)

    monkeypatch.setattr(contour, "VideoWriter", Full)
    with pytest.raises(OSError, match="No space left"):
        contour.make_contour_clip(clip, seed=2, **kw)
    assert clip_bytes(clip) == old
    assert [p.name for p in (tmp_path / "suite").iterdir()] == ["c1"] and find_clips([tmp_path / "suite"]) == [clip]
    monkeypatch.undo()
    contour.make_contour_clip(clip, seed=2, **kw)
    new = clip_bytes(clip)
    assert new["notes.txt"] == b"mine" and new["groundtruth.csv"] != old["groundtruth.csv"]
    assert [p.name for p in (tmp_path / "suite").iterdir()] == ["c1"]
    with pytest.raises(ValueError, match="holds the current folder"):
        monkeypatch.chdir(clip)
        contour.make_contour_clip(".", seed=2, **kw)

def test_synth_killed_mid_clip_leaves_the_old_clip_and_no_clip_eval_takes(tmp_path, capsys):
    """kill -9 of ``vistrack synth`` overwriting a clip: the old video and ground truth are there, as
    they were; the partial render is a hidden folder that eval does not take for a clip, and the next
    synth into that folder removes it."""
    from vistrack.io.clips import find_clips

    clip = tmp_path / "c1"
    synth = ["synth", "contour", "--size", "96x72", "--clutter", "low", "--no-distractor", "-q"]
    code, _, err = run([*synth, "--frames", "3", "--out", str(clip)], capsys)
    assert code == 0, err
    old = clip_bytes(clip)
    proc = subprocess.Popen([sys.executable, "-m", "vistrack.cli", *synth, "--frames", "100000", "--seed", "2",
                             "--out", "c1"], cwd=tmp_path, stderr=subprocess.PIPE, text=True)
    partial = tmp_path / f".c1.partial-{proc.pid}" / "video.mp4"
    wait_until(lambda: partial.is_file() and partial.stat().st_size, "a partial render", proc=proc)
    proc.kill()
    proc.communicate()
    assert partial.is_file() and clip_bytes(clip) == old
    assert find_clips([tmp_path]) == [clip]
    code, _, err = run([*synth, "--frames", "3", "--seed", "3", "--out", str(clip)], capsys)
    assert code == 0 and "overwriting the clip" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c1"]

def test_synth_sigterm_stops_cleanly(tmp_path):
    """SIGTERM (as Ctrl-C) stops any command: exit 143 with one line, the partial clip removed, the
    old clip as it was."""
    from vistrack.data_synth.contour_clip import make_contour_clip

    make_contour_clip(tmp_path / "c1", frames=2, size=(96, 72), seed=1, clutter="low", distractor=False)
    old = clip_bytes(tmp_path / "c1")
    proc = subprocess.Popen([sys.executable, "-m", "vistrack.cli", "synth", "contour", "--out", "c1", "--frames",
                             "100000", "--size", "96x72", "-q"], cwd=tmp_path, stderr=subprocess.PIPE, text=True)
    partial = tmp_path / f".c1.partial-{proc.pid}" / "video.mp4"
    wait_until(partial.is_file, "a partial render", proc=proc)
    proc.terminate()
    _, err = proc.communicate(timeout=PATIENCE)
    assert proc.returncode == 143 and err.strip().endswith("\nTerminated.") and "Traceback" not in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c1"] and clip_bytes(tmp_path / "c1") == old

def test_11_a_suite_over_an_earlier_one_holds_the_new_clips_alone(tmp_path, capsys):
    su = tmp_path / "SU"
    args = ["synth-suite", "--kind", "contour", "--frames", "2", "--size", "64x48", "--out", str(su), "-q"]
    assert run([*args, "--clips", "3", "--seed", "1"], capsys)[0] == 0
    assert run([*args, "--clips", "2", "--seed", "5"], capsys)[0] == 0
    assert sorted(p.name for p in su.iterdir() if not p.name.startswith(".")) == ["contour-05", "contour-06"]
    (su / "notes.txt").write_text("mine")
    code, _, err = run([*args, "--clips", "1"], capsys)
    one_error(code, err, "notes.txt")

def test_11_synth_into_another_clips_folder_is_refused(tmp_path, capsys):
    image_folder(tmp_path / "otb", 3)
    code, _, err = run(["synth", "contour", "--out", str(tmp_path / "otb"), "--frames", "2", "--size", "64x48", "-q"],
                       capsys)
    one_error(code, err, "groundtruth_rect.txt", "img")
    assert sorted(os.listdir(tmp_path / "otb")) == ["groundtruth_rect.txt", "img"]
    # over a clip synth wrote: replaced whole (a plate clip's objects.csv does not stay beside a contour clip)
    clip = tmp_path / "clip"
    clip.mkdir()
    (clip / "video.mp4").write_bytes(b"x")
    (clip / "meta.json").write_text('{"kind": "plate", "model": "plate"}')
    (clip / "objects.csv").write_text("frame\n")
    (clip / "mine.txt").write_text("user's")
    code, _, err = run(["synth", "contour", "--out", str(clip), "--frames", "2", "--size", "64x48", "-q"], capsys)
    assert code == 0, err
    assert sorted(os.listdir(clip)) == ["groundtruth.csv", "meta.json", "mine.txt", "video.mp4"]

def test_13_a_plate_clip_without_a_plate_in_view_says_so(tmp_path, capsys):
    from vistrack.data_synth.plate_clip import NoPlateWarning

    with pytest.warns(NoPlateWarning, match=r"no plate comes wholly into view in the 3 frame\(s\)"):
        code, _, err = run(["synth", "plate", "--out", str(tmp_path / "p"), "--frames", "3", "--size", "160x120",
                            "-q"], capsys)
    assert code == 0, err

def _perturb_source(tmp_path):
    return otb_folder(tmp_path / "src", 10)

def test_perturb_gain_without_light_is_refused(tmp_path):
    from vistrack.data_synth.perturb import Perturbation

    code, _, err = run(["synth", "perturb", _perturb_source(tmp_path), "--out", tmp_path / "o", "--gain", "0.5:1"])
    one_error(code, err, "--gain sets the range of --light")
    assert not (tmp_path / "o").exists()
    assert Perturbation(light="ramp").gain == (0.3, 1.6) and Perturbation(blur=3).gain == (0.3, 1.6)

def test_perturb_marks_an_object_shaken_out_of_view_absent(tmp_path):
    from vistrack.data_synth.perturb import PerturbWarning

    with pytest.warns(PerturbWarning, match="moves the object wholly out of the frame in 10 of the 10 frames"):
        code, _, err = run(["synth", "perturb", _perturb_source(tmp_path), "--out", tmp_path / "o", "--shake", "1000",
                            "-q"])
    assert code == 0, err
    gt = np.loadtxt(tmp_path / "o" / "groundtruth_rect.txt", delimiter=",")
    assert np.all(gt == 0)
    with warnings.catch_warnings():
        warnings.simplefilter("error", PerturbWarning)
        code, _, err = run(["synth", "perturb", tmp_path / "src", "--out", tmp_path / "o6", "--shake", "6", "-q"])
    assert code == 0, err
    assert np.all(np.loadtxt(tmp_path / "o6" / "groundtruth_rect.txt", delimiter=",")[:, 2] > 0)

def test_perturb_overwrites_its_own_earlier_output(tmp_path):
    src = _perturb_source(tmp_path)
    for blur in ("3", "5"):
        code, _, err = run(["synth", "perturb", src, "--out", tmp_path / "o", "--blur", blur, "-q"])
        assert code == 0, err
    (tmp_path / "o" / "notes.txt").write_text("mine")
    code, _, err = run(["synth", "perturb", src, "--out", tmp_path / "o", "--blur", "7", "-q"])
    assert code == 0, err
    assert sorted(p.name for p in (tmp_path / "o").iterdir()) == ["groundtruth_rect.txt", "notes.txt", "perturb.json",
                                                                  "src.mp4"]

    assert json.loads((tmp_path / "o" / "perturb.json").read_text())["blur"] == 7
