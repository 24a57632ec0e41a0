"""`vistrack synth perturb`: stressed copies of a clip whose ground truth is transformed exactly.

A known bright square is rendered through each stress; its intensity-weighted centre and area
in the stressed frame must be where and as large as the transformed ground truth says."""

import numpy as np
import pytest
from click.testing import CliRunner

from vistrack.cli import cli as main
from vistrack.data_synth.perturb import Perturbation, perturb_frames
from vistrack.io.video import VideoWriter, open_video, read_rects

W, H, BG, FG = 160, 120, 30.0, 150.0
T = 24
ABSENT = 10  # a frame without the object: its row stays 0,0,0,0


def square_clip():
    """Grey frames ``(T, H, W)`` with a square moving on a flat background, and its boxes ``(T, 4)``
    (0-based edges: the square covers pixels ``x .. x + w - 1``)."""
    frames, gt = [], []
    for t in range(T):
        img = np.full((H, W), BG, np.uint8)
        x, y, s = 60 + t, 45 + t // 2, 22
        if t != ABSENT:
            img[y:y + s, x:x + s] = FG
            gt.append((x, y, s, s))
        else:
            gt.append((0, 0, 0, 0))
        frames.append(img)
    return frames, np.array(gt, float)


def measure(img):
    """Centre (edge coordinates) and area of the square from the pixel values alone: the flat
    background's level (the median) and the square's (the maximum) are read off the frame."""
    bg, fg = np.median(img), float(img.max())
    m = (img.astype(float) - bg) / (fg - bg)
    ys, xs = np.mgrid[0:img.shape[0], 0:img.shape[1]] + 0.5
    a = m.sum()
    return np.array([(m * xs).sum() / a, (m * ys).sum() / a]), a


STRESSES = {
    "ramp": Perturbation(light="ramp"),
    "flicker": Perturbation(light="flicker", seed=3),
    "blur": Perturbation(blur=7, seed=1),
    "shake": Perturbation(shake=6.0, seed=2),
    "zoom-in": Perturbation(zoom=(1.0, 1.8)),
    "zoom-out": Perturbation(zoom=(1.0, 0.5)),
    "drop": Perturbation(drop=3),
    "all": Perturbation(light="ramp", blur=5, shake=4.0, zoom=(1.0, 0.7), drop=4, seed=5),
}


@pytest.mark.parametrize("name", list(STRESSES))
def test_a_square_is_where_the_transformed_ground_truth_says(name):
    p = STRESSES[name]
    frames, gt = square_clip()
    out = list(perturb_frames(frames, gt, p))
    kept = [t for t in range(T) if not (p.drop and t % p.drop == p.drop - 1)]
    assert [t for t, _, _ in out] == kept
    if p.light == "ramp":
        gains = np.linspace(p.gain[0], p.gain[1], T)
    else:
        gains = None
    moved = False
    for t, img, box in out:
        assert img.shape == (H, W) and img.dtype == np.uint8
        if t == ABSENT:
            assert np.all(box == 0)
            continue
        g = np.median(img) / BG  # the gain of this frame, read off the flat background
        if gains is not None:
            assert g == pytest.approx(gains[t], abs=0.5 / BG)
        assert 0.3 - 0.02 <= g <= 1.6 + 0.02
        centre, area = measure(img)
        tol = 0.12 if p.light is None else 0.5 / g  # uint8 rounding of a dimmed frame
        np.testing.assert_allclose(centre, box[:2] + box[2:] / 2, atol=tol + (0.3 if p.blur else 0.0))
        assert area == pytest.approx(box[2] * box[3], rel=0.03 + (0.03 if p.light else 0.0))
        moved |= bool(np.abs(box - gt[t]).max() > 1.0)
    if p.shake or p.zoom:
        assert moved, "the geometry should move the ground truth"
    else:
        np.testing.assert_array_equal(np.array([b for _, _, b in out]), gt[kept])


def test_zoom_changes_the_size_from_a_to_b_about_the_object():
    frames, gt = square_clip()
    out = list(perturb_frames(frames, gt, Perturbation(zoom=(1.0, 0.5))))
    first, last = out[0][2], out[-1][2]
    assert first[2] == pytest.approx(gt[0, 2])
    assert last[2] == pytest.approx(0.5 * gt[-1, 2])
    np.testing.assert_allclose(last[:2] + last[2:] / 2, gt[-1, :2] + gt[-1, 2:] / 2)  # the centre stays


def test_the_same_seed_gives_the_same_copy():
    frames, gt = square_clip()
    p = Perturbation(blur=5, shake=3.0, light="flicker", seed=7)
    a = [(f.copy(), b) for _, f, b in perturb_frames(frames, gt, p)]
    b = [(f.copy(), b) for _, f, b in perturb_frames(frames, gt, p)]
    for (fa, ba), (fb, bb) in zip(a, b):
        np.testing.assert_array_equal(fa, fb)
        np.testing.assert_array_equal(ba, bb)


def test_cli_writes_a_clip_that_run_and_eval_read(tmp_path):
    frames, gt = square_clip()
    src = tmp_path / "sq"
    src.mkdir()
    with VideoWriter(src / "sq.mp4", 30, (W, H), codec="h264") as w:
        for f in frames:
            w.write(f)
    np.savetxt(src / "groundtruth_rect.txt", gt + (1, 1, 0, 0), fmt="%d", delimiter=",")  # OTB's file: 1-based
    out = tmp_path / "sq-shake"
    r = CliRunner().invoke(main, ["synth", "perturb", str(src), "--out", str(out), "--shake", "5", "--zoom",
                                  "1:0.7", "--drop", "5", "--seed", "1", "-q"])
    assert r.exit_code == 0, r.output
    boxes = read_rects(out / "groundtruth_rect.txt")
    decoded = [f for _, f in open_video(out)]
    assert len(decoded) == len(boxes) == T - T // 5
    for img, box in zip(decoded, boxes):
        if box[2] == 0:
            continue
        centre, _ = measure(img[..., 1] if img.ndim == 3 else img)
        np.testing.assert_allclose(centre, box[:2] + box[2:] / 2, atol=0.5)  # H.264 is lossy


@pytest.mark.parametrize("args, message", [
    (["--zoom", "1:0"], "expected two positive numbers"),
    (["--zoom", "abc"], "expected two numbers A:B"),
    (["--drop", "1"], "drop must be 0 (none) or at least 2"),
    (["--light", "strobe"], "'strobe' is not one of"),
])
def test_bad_options_are_one_line(tmp_path, args, message):
    frames, gt = square_clip()
    src = tmp_path / "sq"
    src.mkdir()
    with VideoWriter(src / "sq.mp4", 30, (W, H)) as w:
        for f in frames[:3]:
            w.write(f)
    np.savetxt(src / "groundtruth_rect.txt", gt[:3], fmt="%d", delimiter=",")
    r = CliRunner().invoke(main, ["synth", "perturb", str(src), "--out", str(tmp_path / "o"), *args])
    assert r.exit_code == 2 if "--light" in args or "--zoom" in args else r.exit_code == 1
    assert message in r.output
    assert "Traceback" not in r.output


def test_a_clip_without_ground_truth_is_refused(tmp_path):
    src = tmp_path / "v"
    src.mkdir()
    with VideoWriter(src / "v.mp4", 30, (W, H)) as w:
        w.write(np.zeros((H, W), np.uint8))
    r = CliRunner().invoke(main, ["synth", "perturb", str(src), "--out", str(tmp_path / "o"), "--blur", "3"])
    assert r.exit_code == 1 and "has no box ground truth" in r.output
    assert not (tmp_path / "o").exists()


def test_every_preset_is_remade_from_its_fields():
    """``dataclasses.replace`` of a preset (the benchmark's seed 1) gives the same stress: a perturbation
    without a light holds the default gain, which is not a --gain given without --light."""
    import dataclasses

    from vistrack.data_synth.perturb import STRESS_PRESETS

    for name, p in STRESS_PRESETS.items():
        q = dataclasses.replace(p, seed=1)
        assert (q.name, q.gain, q.seed) == (p.name, p.gain, 1), name
