"""Landmarks from video: synthetic clips, blob detection, `vistrack run --model landmarks`."""

import numpy as np
import pytest

from cli_helpers import run
from vistrack.appearance.features import FeatureMaps, blob_peaks
from vistrack.data_synth.landmark_clip import draw_blob, make_landmark_clip
from vistrack.io.clips import load_clip, read_groundtruth_csv
from vistrack.io.video import open_video
from vistrack.scoring.metrics import landmark_error


@pytest.fixture(scope="module")
def clip_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("lm") / "clip"
    make_landmark_clip(out, k=5, frames=60, size=(640, 480), seed=3)
    return out


def test_blob_peaks_are_subpixel_accurate():
    rng = np.random.default_rng(0)
    img = np.full((120, 160), 60.0, np.float32)
    truth = np.column_stack([rng.uniform(15, 145, 6), rng.uniform(15, 105, 6)])
    for x, y in truth:
        draw_blob(img, x, y, 2.4, 150.0)
    img += rng.normal(0, 2, img.shape).astype(np.float32)
    peaks, val = blob_peaks(FeatureMaps(np.dstack([img] * 3).clip(0, 255).astype(np.uint8)).dog_small, 25.0)
    d = np.linalg.norm(truth[:, None] - peaks[None], axis=2)
    assert len(peaks) == 6 and np.all(np.diff(val) <= 0)
    assert d.min(axis=1).max() < 0.35  # sub-pixel
    assert len(blob_peaks(np.zeros((50, 50), np.float32), 1.0)[0]) == 0


@pytest.mark.slow
def test_synth_landmarks_clip_files(clip_dir):
    t = read_groundtruth_csv(clip_dir / "groundtruth.csv")
    assert {f"lx{i}" for i in range(5)} | {"ly4", "occ4", "angle_deg", "scale"} <= set(t) and len(t["frame"]) == 60
    src = open_video(clip_dir / "video.mp4")
    assert src.frame_count == 60 and src.size == (640, 480)
    pts = np.stack([np.column_stack([t[f"lx{i}"], t[f"ly{i}"]]) for i in range(5)], axis=1)
    assert np.allclose(pts.mean(axis=1), [320, 240], atol=1e-2)  # centred configuration
    assert np.all((pts > 0) & (pts < [640, 480]))
    step = np.linalg.norm(np.diff(pts, axis=0), axis=2)
    assert step.mean() > 0.5  # the landmarks move
    clip = load_clip(clip_dir)
    assert clip.model_name == "landmarks" and clip.meta["k"] == 5


@pytest.mark.slow
def test_run_pf_eis_mt_tracks_landmarks(clip_dir, tmp_path, capsys):
    track = tmp_path / "t.csv"
    video = tmp_path / "a.mp4"
    code, out, err = run(["run", str(clip_dir / "video.mp4"), "--track", str(track), "--out", str(video),
                          "--seed", "1", "-n", "60"], capsys)
    assert code == 0, err
    assert "mean landmark error" in out
    rows = read_groundtruth_csv(track)
    assert {"lx0", "ly4", "ess", "ms"} <= set(rows) and len(rows["frame"]) == 60
    as_rows = [{k: rows[k][i] for k in rows} for i in range(60)]
    err_px = landmark_error(as_rows, read_groundtruth_csv(clip_dir / "groundtruth.csv"), 5)
    assert err_px.mean() < 3.0, err_px
    assert open_video(video).frame_count == 60
    # same seed, same track
    track2 = tmp_path / "t2.csv"
    run(["run", str(clip_dir), "--track", str(track2), "--seed", "1", "-n", "60", "-q"], capsys)
    rows2 = read_groundtruth_csv(track2)
    assert all(np.array_equal(rows[k], rows2[k]) for k in rows if k != "ms")


@pytest.mark.parametrize("args, message", [
    (["--algo", "lis"], "does not run on the landmarks model"),
    (["--init", "1,2,3,4"], "--init is a box"),
])
def test_run_landmarks_bad_input(clip_dir, capsys, args, message):
    code, out, err = run(["run", str(clip_dir), "-q"] + args, capsys)
    assert code != 0 and message in err


def test_landmarks_without_a_start_is_a_clear_error(tmp_path, capsys):
    from vistrack.io.video import VideoWriter

    with VideoWriter(tmp_path / "v.mp4", 30, (160, 120)) as w:
        for _ in range(3):
            w.write(np.zeros((120, 160, 3), np.uint8))
    code, out, err = run(["run", str(tmp_path / "v.mp4"), "--model", "landmarks", "-q"], capsys)
    assert code != 0 and "needs the first frame's landmarks" in err
