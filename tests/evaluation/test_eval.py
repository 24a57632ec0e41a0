"""`vistrack eval`: files, JSON schema, plots, resume and worker-count invariance, bad input."""

import csv
import json
import shutil

import matplotlib.image as mpimg
import numpy as np
import pytest

from cli_helpers import run
from clip_helpers import tiny_otb_clip
from eval_helpers import strip_timing
from vistrack.data_synth.contour_clip import make_contour_clip

SUMMARY_KEYS = {"clip", "algo", "particles", "runs", "mean_error", "p_lost", "p_lost_final", "p_lost_per_frame",
                "error_per_frame", "success_auc", "success_curve", "precision_20px", "frames_per_s", "mean_ess",
                "mean_error_all", "precision_curve"}




@pytest.fixture(scope="module")
def suite(tmp_path_factory):
    d = tmp_path_factory.mktemp("suite")
    for s in (1, 2):
        make_contour_clip(d / f"c{s}", frames=10, size=(128, 96), seed=s, clutter="low", distractor=False)
    return d


def grid(suite, out, *extra):
    return ["eval", str(suite), "--algos", "lis,bootstrap", "--particles", "10,20", "--runs", "3", "--seed", "4",
            "--out", str(out), "-q", *extra]


@pytest.mark.slow
def test_eval_files_schema_resume_and_workers(suite, tmp_path, capsys):
    full = tmp_path / "full"
    code, _, err = run(grid(suite, full, "--in-process", "--workers", "2"), capsys)
    assert code == 0, err
    data = json.loads((full / "results.json").read_text())
    assert set(data) == {"config", "results"}
    assert len(data["results"]) == 2 * 2 * 2  # clip × algo × N
    for r in data["results"]:
        assert set(r) >= SUMMARY_KEYS and r["runs"] == 3
        assert 0 <= r["success_auc"] <= 1 and 0 <= r["p_lost"] <= 1 and len(r["p_lost_per_frame"]) == 10
    with open(full / "results.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 2 * 2 * 2 * 3
    for png in ("error_vs_frame.png", "p_lost_vs_frame.png", "error_vs_n.png", "fps_vs_n.png", "success.png",
                "precision.png"):
        assert mpimg.imread(full / png).ndim == 3
    report = (full / "report.md").read_text()
    assert "| lis | 10 |" in report and "## Per clip" in report and report.count("### ") == 2
    for r in data["results"]:  # precision curve: non-decreasing, its 20-px point is precision_20px
        assert np.all(np.diff(r["precision_curve"]) >= 0) and r["precision_curve"][20] == r["precision_20px"]
        assert r["mean_error_all"] >= 0

    # killed midway: half the task files gone; --resume finishes with the same results, on one
    # worker what two computed
    part = tmp_path / "part"
    shutil.copytree(full, part)
    for p in sorted((part / "tasks").iterdir())[::2]:
        p.unlink()
    (part / "results.json").unlink()
    code, _, err = run(grid(suite, part, "--in-process", "--workers", "1", "--resume"), capsys)
    assert code == 0, err
    assert strip_timing(json.loads((part / "results.json").read_text())) == strip_timing(data)

    # --resume under another seed reuses nothing: every task file is recomputed (no mixing)
    one = part
    before = {p.name: json.loads(p.read_text()) for p in (one / "tasks").iterdir()}
    code, _, err = run(grid(suite, one, "--in-process", "--workers", "1", "--resume", "--seed", "2"), capsys)
    assert code == 0, err
    assert f"{len(before)} of {len(before)} task files come from other options, seed" in err
    after = {p.name: json.loads(p.read_text()) for p in (one / "tasks").iterdir()}
    assert all(after[k]["fingerprint"] != before[k]["fingerprint"] for k in before)
    assert sum(after[k]["error"] != before[k]["error"] for k in before) > len(before) // 2
    assert json.loads((one / "results.json").read_text())["config"]["seed"] == 2


@pytest.mark.slow
def test_eval_bad_input(suite, tmp_path, capsys):
    empty = tmp_path / "empty"
    empty.mkdir()
    code, _, err = run(["eval", str(empty), "--out", str(tmp_path / "o")], capsys)
    assert code != 0 and "holds no clips" in err
    nogt = tmp_path / "nogt"
    nogt.mkdir()
    shutil.copy(suite / "c1" / "video.mp4", nogt / "video.mp4")
    code, _, err = run(["eval", str(nogt), "--out", str(tmp_path / "o")], capsys)
    assert code != 0 and "eval needs ground truth" in err
    code, _, err = run(["eval", str(suite), "--algos", "lis,nope", "--out", str(tmp_path / "o")], capsys)
    assert code != 0 and "unknown algorithm 'nope'" in err
    import cv2

    if not hasattr(cv2, "TrackerCSRT_create"):
        code, _, err = run(["eval", str(suite), "--algos", "opencv-csrt", "--out", str(tmp_path / "o")], capsys)
        assert code != 0 and "opencv-contrib" in err
    code, _, err = run(["eval", str(suite / "c1"), "--runs", "1", "--particles", "5", "--scheduler",
                        "tcp://127.0.0.1:9", "--timeout", "2", "--out", str(tmp_path / "o")], capsys)
    assert code != 0 and "cannot reach the Dask scheduler" in err
    code, _, err = run(["eval", str(suite / "c1"), "--scheduler", "notaurl", "--out", str(tmp_path / "o")], capsys)
    assert code != 0 and err.startswith("Error: cannot reach the Dask scheduler at notaurl") and err.count("\n") == 1


def test_synth_suite(tmp_path, capsys):
    code, _, err = run(["synth-suite", "--kind", "contour", "--clips", "2", "--seed", "5", "--frames", "5",
                        "--size", "96x72", "--out", str(tmp_path / "s"), "-q"], capsys)
    assert code == 0, err
    names = sorted(p.name for p in (tmp_path / "s").iterdir())
    assert names == ["contour-05", "contour-06"]
    assert json.loads((tmp_path / "s" / "contour-06" / "meta.json").read_text())["seed"] == 6


@pytest.mark.slow
def test_demo_writes_videos_tracks_and_reports(tmp_path, capsys):
    import cv2

    out = tmp_path / "demo"
    real = tiny_otb_clip(tmp_path / "Tiny")
    code, stdout, err = run(["demo", "--out", str(out), "--frames", "12", "--runs", "2", "--real-clip", str(real),
                             "--real-frames", "10"], capsys)
    assert code == 0, err
    for name in [f"jumps-{a}" for a in ("ls-n-ips", "lis", "bootstrap")]:
        cap = cv2.VideoCapture(str(out / f"{name}.mp4"))
        assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == 12
        with open(out / f"{name}.csv", newline="") as f:
            rows = list(csv.DictReader(f))
        assert len(rows) == 12 and {"visible", "lost_reason"} <= set(rows[0])
    assert (out / "eval" / "report.md").is_file() and str(out) in stdout
    # issue 46: the clip names the model the demo tracked it with; the file list has report.html
    assert json.loads((out / "clips" / "jumps" / "meta.json").read_text())["model"] == "box"
    assert f"  {out / 'eval' / 'report.html'} (the same in a browser" in stdout
    assert f"  {out / 'eval-real' / 'report.html'} (the same in a browser" in stdout
    assert "comparing them over 2 runs" in stdout and "beside OpenCV MIL, 2 runs each" in stdout
    res = json.loads((out / "eval" / "results.json").read_text())
    assert res["config"]["model"] == "box"
    assert [(r["algo"], r["particles"], r["runs"]) for r in res["results"]] == [
        ("ls-n-ips", 30, 2), ("lis", 30, 2), ("bootstrap", 150, 2)]
    real_res = json.loads((out / "eval-real" / "results.json").read_text())["results"]
    assert [(r["algo"], r["particles"], r["runs"]) for r in real_res] == [("lis", 100, 2), ("opencv-mil", 1, 2)]
    assert len(real_res[0]["p_lost_per_frame"]) == 10  # the excerpt: the first 10 frames
    # no N for a tracker without particles; its true run count (issue 37)
    assert "| opencv-mil | – | 2 |" in stdout and "| lis | 100 | 2 |" in stdout


@pytest.mark.slow
def test_demo_skips_a_missing_real_clip(tmp_path, capsys, monkeypatch):
    import importlib

    demo_module = importlib.import_module("vistrack.demo.steps")
    monkeypatch.setattr(demo_module, "DEMO_ENTRIES", (("bootstrap", 20),))  # the skip is what is tested
    out = tmp_path / "demo"
    code, stdout, err = run(["demo", "--out", str(out), "--frames", "10", "--runs", "1", "--real-clip",
                             str(tmp_path / "nowhere")], capsys)
    assert code == 0, err
    assert f"4/4 skipped: no real clip at {tmp_path / 'nowhere'}" in stdout
    assert (out / "eval" / "report.md").is_file() and not (out / "eval-real").exists()


def test_engine_workers_keep_freed_memory():
    """Under glibc the engine's workers turn glibc's fresh-mmap-per-array behaviour (set off by
    Dask's MALLOC_TRIM_THRESHOLD_) back into heap reuse; elsewhere it is a no-op."""
    import platform

    from vistrack.system.resources import keep_freed_memory

    if platform.libc_ver()[0] != "glibc":
        pytest.skip("no glibc: keep_freed_memory is a no-op")
    assert keep_freed_memory() is True


def test_lost_rules_known_answers():
    """The plate rule (docs/architecture.md): lost where a plate is in view and none is reported, or the summed
    vertex error exceeds a third of the plate height; never in a frame without a plate. Without
    vertex truth, and for other models, the centre rule (50 px at 240-px width)."""
    from vistrack.scoring.metrics import lost_frames

    square = np.array([[0, 0], [60, 0], [60, 30], [0, 30]], float) + 100  # width 60, aspect 2: height 30
    truth = {"frame": np.arange(5), "visible": np.array([1, 1, 1, 0, 1.0]), "scale": np.full(5, 60.0)}
    for i in range(4):
        truth[f"x{i}"], truth[f"y{i}"] = np.full(5, square[i, 0]), np.full(5, square[i, 1])
    # summed vertex errors: 4 x 1.41 = 5.7 px (<= 30 / 3), 4 x 4.24 = 17 px (> 10), then exact
    est = np.stack([square + 1.0, square + 3.0, square, square, square])
    reported = [True, True, False, True, True]  # frame 2: not reported; frame 3: no plate in view
    lost = lost_frames("plate", np.zeros(5), 320, truth=truth, reported=reported, vertices=est, aspect=2.0)
    np.testing.assert_array_equal(lost, [False, True, True, False, False])
    centre = lost_frames("centre", np.array([10.0, 70.0]), 320)  # threshold 66.7 px at 320 px
    np.testing.assert_array_equal(centre, [False, True])
    no_vertices = {k: v for k, v in truth.items() if k[0] not in "xy"}
    np.testing.assert_array_equal(lost_frames("plate", np.array([10.0, 70.0]), 320, truth=no_vertices,
                                              reported=[1, 1], vertices=est[:2], aspect=2.0), [False, True])
    with pytest.raises(ValueError, match="unknown lost rule"):
        lost_frames("nope", np.zeros(2), 320)


@pytest.mark.slow
def test_eval_plate_uses_the_plate_lost_rule(tmp_path, capsys):
    """``eval --model plate`` on a plate clip: frames without a plate are never lost, and every task
    result's lost flags are the plate rule's on its own reported flags and vertices."""
    code, _, err = run(["synth", "plate", "--out", str(tmp_path / "p"), "--frames", "16", "--size", "320x240",
                        "--seed", "3"], capsys)
    assert code == 0, err
    code, _, err = run(["eval", str(tmp_path / "p"), "--model", "plate", "--algos", "lis", "--particles", "50",
                        "--runs", "1", "--in-process", "--out", str(tmp_path / "ev"), "-q"], capsys)
    assert code == 0, err
    (task,) = [json.loads(p.read_text()) for p in (tmp_path / "ev" / "tasks").glob("*.json")]
    vis = np.array(task["visible"], bool)
    assert not np.any(np.array(task["lost"], bool) & ~vis)
