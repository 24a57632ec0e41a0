"""Sizes a user gives, checked against memory, disk and sense before any work: particles, the task grid,
clips, frames, targets, steps and workers. Each too large is one line naming it and what fits."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from cli_helpers import run
from fault_helpers import (
    H,
    W,
    one_error,
)


def test_particle_memory_check_known_answer():
    from vistrack.registry import check_particle_memory

    assert check_particle_memory(1000, 32_000, "lis", available=2**30) == 32_000_000
    with pytest.raises(ValueError, match="use at most 2097"):  # half of 1 GiB / (32 KB x 8 for LLS)
        check_particle_memory(3000, 32_000, "lls", available=2**30)

def test_eval_refuses_particles_beyond_memory_and_reports_unwritable_results(tmp_path, capsys):
    from vistrack.data_synth.contour_clip import make_contour_clip

    make_contour_clip(tmp_path / "c1", frames=3, size=(96, 72), seed=1, clutter="low", distractor=False)
    grid = ["eval", str(tmp_path / "c1"), "--algos", "bootstrap", "--runs", "1", "--in-process", "-q"]
    code, _, err = run([*grid, "--particles", "100000000", "--out", str(tmp_path / "big")], capsys)
    assert code != 0 and "100000000 particles need about" in err and err.count("Error:") == 1
    out = tmp_path / "R"
    out.mkdir()
    (out / "results.json").symlink_to("/dev/full")
    code, _, err = run([*grid, "--particles", "10", "--out", str(out)], capsys)
    assert code != 0 and err.startswith(f"Error: cannot write the results into {out}: No space left on device")
    assert "Traceback" not in err and len(list((out / "tasks").glob("*.json"))) == 1

def test_the_task_grid_is_checked_against_memory_known_answers():
    from vistrack.evaluation.experiment import TASK_BYTES, TASK_FRAME_BYTES, check_grid_size
    from vistrack.system.resources import TooLarge

    each = TASK_BYTES + TASK_FRAME_BYTES * 100
    room = 2 * each * 1000  # half of it holds 1000 tasks
    assert check_grid_size(2, [("lis", 10), ("bootstrap", 10)], 250, 100, available=room) == 1000
    with pytest.raises(TooLarge, match=r"a grid of 1004 tasks \(2 clip\(s\) x 2 algorithm and N pair\(s\) x 251 "
                                       r"run\(s\)\) needs about .* give at most 250 runs"):
        check_grid_size(2, [("lis", 10), ("bootstrap", 10)], 251, 100, available=room)
    # a deterministic OpenCV tracker runs once, whatever --runs; MIL (randomised inside OpenCV) runs --runs times
    assert check_grid_size(2, [("lis", 10), ("opencv-kcf", 1)], 499, 100, available=room) == 1000
    assert check_grid_size(2, [("lis", 10), ("opencv-mil", 1)], 250, 100, available=room) == 1000

@pytest.mark.parametrize("argv, words", [
    (["eval", "{clip}", "--algos", "lis", "--particles", "20", "--runs", "100000000", "--workers", "1", "--out",
      "{d}/E"], ["a grid of 100000000 tasks", "give at most"]),
    (["synth-suite", "--kind", "contour", "--clips", "1000000000000", "--frames", "1", "--size", "64x48", "--out",
      "{d}/S"], ["1000000000000 clips of 1 frames at 64x48 need about", "free on", "give at most"]),
    (["run", "{noise}", "--targets", "90", "-n", "100000000", "--track", "{d}/t.csv"],
     ["100000000 particles of 90 targets need about"]),
    (["run", "{noise}", "--targets", "1000", "--track", "{d}/t.csv"],
     ["--targets 1000: a 160x120 frame holds at most 96 plates"]),
    (["reproduce", "bearings", "--steps", "1000000000", "--runs", "2", "--sequences", "2", "--particles", "50",
      "--in-process", "--out", "{d}/B"], ["1000000000 steps", "give at most"]),
    (["reproduce", "landmarks", "--steps", "1000000000", "--runs", "2", "--in-process", "--out", "{d}/L"],
     ["1000000000 steps", "give at most"]),
    (["reproduce", "contour", "--runs", "100000000", "--clips", "{d}/made", "--make", "2", "--frames", "3", "--size",
      "96x72", "--in-process", "--out", "{d}/C"], ["a grid of 400000000 tasks"]),
], ids=["eval-runs", "synth-suite-clips", "run-targets-memory", "run-targets-sense", "bearings-steps",
        "landmarks-steps", "reproduce-runs"])
def test_sizes_are_checked_before_work_starts(tmp_path, argv, words):
    """Issue 47's unbounded-memory cases: one line naming the size and what fits, at once; nothing
    made (no results folder, no clip)."""
    from vistrack.data_synth.contour_clip import make_contour_clip

    clip = tmp_path / "clip"
    make_contour_clip(clip, frames=3, size=(96, 72), seed=1, clutter="low", distractor=False)
    noise = tmp_path / "noise" / "img"
    noise.mkdir(parents=True)
    rng = np.random.default_rng(0)
    for i in range(3):
        cv2.imwrite(str(noise / f"{i + 1:04d}.png"), rng.integers(0, 255, (H, W, 3), dtype=np.uint8))
    before = sorted(p.name for p in tmp_path.iterdir())
    code, _, err = run([a.format(d=tmp_path, clip=clip, noise=noise.parent) for a in argv])
    one_error(code, err, *words)
    assert sorted(p.name for p in tmp_path.iterdir()) == before

def test_a_large_suite_is_named_lazily(tmp_path):
    """A suite's names are a range, not a list: a billion of them cost nothing, and an earlier
    suite's other clips are found by them all the same."""
    from vistrack.data_synth.scene import SuiteNames, prepare_suite

    names = SuiteNames("contour", 5, 10**9)
    assert len(names) == 10**9 and "contour-05" in names and "contour-1000000004" in names
    assert "contour-04" not in names and "contour-1000000005" not in names and "contour-5" not in names
    assert "plate-07" not in names and list(SuiteNames("plate", 9, 3)) == ["plate-09", "plate-10", "plate-11"]
    out = tmp_path / "s"
    from vistrack.data_synth.contour_clip import make_contour_clip

    for s in (1, 2, 7):
        make_contour_clip(out / f"contour-{s:02d}", frames=2, size=(96, 72), seed=s, clutter="low", distractor=False)
    assert prepare_suite(out, SuiteNames("contour", 2, 10**9)) == ["contour-01"]
    assert sorted(p.name for p in out.iterdir()) == ["contour-02", "contour-07"]


# ------------------------------------------------------------------ the fourth sweep (issue 55)


@pytest.mark.parametrize("argv, words", [
    (["synth", "contour", "--frames", "1000000000000", "--size", "64x48", "--out", "{d}/c"],
     ["a clip of 1000000000000 frames at 64x48 needs about", "not even one clip fits: give at most", "--frames"]),
    (["synth", "plate", "--frames", "1000000000000", "--out", "{d}/c"], ["a clip of 1000000000000 frames"]),
    (["synth", "landmarks", "--frames", "1000000000000", "--out", "{d}/c"], ["a clip of 1000000000000 frames"]),
    (["synth", "plate", "--cars", "1000000000", "--frames", "3", "--out", "{d}/c"],
     ["--cars 1000000000: their sprites need about", "give at most"]),
    (["synth", "landmarks", "--clutter-blobs", "1000000000", "--frames", "3", "--out", "{d}/c"],
     ["--clutter-blobs 1000000000: a 640x480 frame shows at most 5925 blobs apart; give at most 5925"]),
    (["synth", "landmarks", "--k", "100000", "--frames", "3", "--out", "{d}/c"],
     ["--k 100000: a 640x480 frame shows at most 94 landmarks apart on their ring; give at most 94"]),
    (["synth-suite", "--kind", "contour", "--clips", "2", "--frames", "1000000000000", "--out", "{d}/s"],
     ["2 clips of 1000000000000 frames", "not even one clip fits", "--frames"]),
    (["demo", "--runs", "1000000000", "--out", "{d}/demo"], ["a grid of 3000000000 tasks", "give at most"]),
    (["reproduce", "bearings", "--ships", "1000000", "--runs", "2", "--sequences", "2", "--steps", "5",
      "--particles", "50", "--in-process", "--out", "{d}/B"], ["1000000 ship(s)", "--ships"]),
], ids=["synth-contour-frames", "synth-plate-frames", "synth-landmarks-frames", "synth-plate-cars",
        "synth-landmarks-blobs", "synth-landmarks-k", "synth-suite-frames", "demo-runs", "bearings-ships"])
def test_every_size_is_checked_before_anything_is_made(tmp_path, argv, words):
    """synth --frames 10^12 started with an ETA of 170,000 hours; --cars, --clutter-blobs and --k ran out of
    memory (numpy's 'Unable to allocate 74.5 GiB' for --k); synth-suite advised 'give at most 0 clips';
    demo --runs made its clip and ran three trackers before refusing the grid; reproduce bearings --ships
    10^6 failed after 53 s with every worker killed. Each is one line naming the size, before work."""
    code, _, err = run([a.format(d=tmp_path) for a in argv])
    one_error(code, err, *words)
    assert "give at most 0" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == []


def test_clip_sizes_known_answers(tmp_path, monkeypatch):
    from vistrack.data_synth.clip_sizes import CAR_BYTES, check_clip_sizes
    from vistrack.system import resources
    from vistrack.system.resources import TooLarge

    check_clip_sizes(tmp_path, 10, (640, 480), cars=3, k=8, clutter_blobs=6)
    check_clip_sizes(tmp_path, 10, (640, 480), k=94, clutter_blobs=5925)  # the most a 640x480 frame shows apart
    for kw, words in ((dict(k=95), "--k 95"), (dict(clutter_blobs=5926), "--clutter-blobs 5926")):
        with pytest.raises(TooLarge, match=words):
            check_clip_sizes(tmp_path, 10, (640, 480), **kw)
    monkeypatch.setattr(resources, "available_memory", lambda: 200 * CAR_BYTES)  # half of it holds 100 cars
    check_clip_sizes(tmp_path, cars=100)
    with pytest.raises(TooLarge, match="give at most 100 cars"):
        check_clip_sizes(tmp_path, cars=101)


def test_eval_workers_are_capped_at_what_the_machine_and_the_tasks_use(tmp_path):
    """eval --workers 1000 started hundreds of worker processes and was killed for memory after 26 s."""
    from vistrack.system.resources import WORKER_BYTES, worker_count

    assert worker_count(1000, 6, available=2**40, cores=2) == (4, "note: --workers 1000 capped at 4 (two per core "
                                                                  "of the machine's 2 cores)")
    assert worker_count(1000, 3, available=2**40, cores=8)[0] == 3
    n, note = worker_count(1000, 600, available=20 * WORKER_BYTES, cores=64)
    assert n == 10 and "half the" in note
    assert worker_count(0, 600, available=2**40, cores=2) == (2, None)  # none given: one per core, no note
    assert worker_count(2, 6, available=2**40, cores=1) == (2, None)
    from vistrack.data_synth.contour_clip import make_contour_clip

    make_contour_clip(tmp_path / "c1", frames=3, size=(96, 72), seed=1, clutter="low", distractor=False)
    code, _, err = run(["eval", tmp_path / "c1", "--algos", "bootstrap", "--particles", "10", "--runs", "1",
                        "--workers", "1000", "--in-process", "--out", tmp_path / "E", "-q"])
    assert code == 0 and "note: --workers 1000 capped at 1 (1 task(s) to run)" in err, err
