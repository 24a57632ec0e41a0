"""One rule for the random streams (issue 46, item 5): eval's run r on a clip is `run --seed S --run r`'s
track (`eval --runs 1 --seed S` is `run --seed S`'s), whatever the number of clips and workers; the
reproductions keep the streams their published tables were computed with."""

import json

import numpy as np
import pytest

from cli_helpers import run
from vistrack.core.seeds import run_rng, run_seed
from vistrack.io.clips import read_groundtruth_csv


def test_run_0_is_the_seed_itself_and_runs_are_independent():
    assert np.array_equal(run_rng(7).random(5), np.random.default_rng(7).random(5))
    draws = {(s, r): tuple(run_rng(s, r).random(3)) for s in (0, 1, 7) for r in (0, 1, 2)}
    assert len(set(draws.values())) == len(draws)
    with pytest.raises(ValueError, match="non-negative"):
        run_seed(1, -1)


@pytest.fixture(scope="module")
def clips(tmp_path_factory):
    from vistrack.data_synth.contour_clip import make_contour_clip

    root = tmp_path_factory.mktemp("seeds")
    for k in (1, 2):
        make_contour_clip(root / "suite" / f"c{k}", frames=10, size=(128, 96), seed=k, clutter="low",
                          distractor=False)
    return root / "suite"


def boxes_of_run(clip, tmp_path, *args):
    track = tmp_path / "t.csv"
    code, _, err = run(["run", str(clip), "--init-gt", "-n", "30", "--track", track, "-q", *args])
    assert code == 0, err
    t = read_groundtruth_csv(track)
    return np.column_stack([t["cx"], t["cy"], t["w"], t["h"]])


def boxes_of_eval(out, clip_index, clip, run_no):
    task = json.loads((out / "tasks" / f"{clip_index:03d}_{clip.name}__lis__N30__r{run_no}.json").read_text())
    b = np.array(task["boxes"], float)
    return np.column_stack([b[:, 0] + b[:, 2] / 2, b[:, 1] + b[:, 3] / 2, b[:, 2], b[:, 3]])


@pytest.mark.slow
def test_eval_runs_are_run_seed_and_run(clips, tmp_path):
    out = tmp_path / "ev"
    code, _, err = run(["eval", clips, "--algos", "lis", "--particles", "30", "--runs", "2", "--seed", "5",
                        "--in-process", "--workers", "2", "--out", out, "-q"])
    assert code == 0, err
    second = clips / "c2"
    for r, extra in ((0, []), (1, ["--run", "1"])):
        want = boxes_of_run(second, tmp_path, "--seed", "5", *extra)
        np.testing.assert_allclose(boxes_of_eval(out, 1, second, r), want, atol=2e-3)  # 3 decimals each
    other = boxes_of_run(second, tmp_path, "--seed", "6")
    assert np.abs(boxes_of_eval(out, 1, second, 0) - other).max() > 0.01  # the check can fail


@pytest.mark.slow
def test_eval_runs_1_on_a_single_clip_is_run_seed(clips, tmp_path):
    out = tmp_path / "one"
    code, _, err = run(["eval", clips / "c1", "--algos", "lis", "--particles", "30", "--runs", "1", "--seed", "3",
                        "--in-process", "--workers", "1", "--out", out, "-q"])
    assert code == 0, err
    np.testing.assert_allclose(boxes_of_eval(out, 0, clips / "c1", 0),
                               boxes_of_run(clips / "c1", tmp_path, "--seed", "3"), atol=2e-3)


def test_the_reproductions_keep_their_streams():
    from types import SimpleNamespace

    from vistrack.evaluation.experiment import entry_tasks

    cfg = SimpleNamespace(clips=["a", "b"], entries=[("lis", 30)], runs=3, seed=4)
    tasks = entry_tasks(cfg, "contour")
    want = [np.random.SeedSequence(4).spawn(2)[c].spawn(3)[r] for c in range(2) for r in range(3)]
    assert [t["seed_seq"].generate_state(4).tolist() for t in tasks] == [w.generate_state(4).tolist() for w in want]


def test_help_says_how_eval_runs_relate_to_run_seed():
    _, out, _ = run(["eval", "--help"])
    assert "--seed S --run r" in " ".join(out.split()) and "eval --runs 1 --seed S" in " ".join(out.split())
    _, out, _ = run(["run", "--help"])
    assert "--run" in out and "eval --runs 1 --seed S" in " ".join(out.split())


def test_a_deterministic_opencv_tracker_runs_once_mil_as_often_as_the_filters():
    from vistrack.evaluation.experiment import EvalConfig, task_list

    tasks = task_list(EvalConfig(clips=["c"], algos=["lis", "opencv-mil", "opencv-kcf"], particles=[30], runs=3,
                                 seed=1, model="box"), ["c"])
    assert [(t["algo"], t["run"]) for t in tasks] == [("lis", 0), ("lis", 1), ("lis", 2), ("opencv-mil", 0),
                                                      ("opencv-mil", 1), ("opencv-mil", 2), ("opencv-kcf", 0)]
