"""The toolkits' result files (issue 37, item 2): run --results-format otb|got10k|vot writes them,
eval --results-dir --results-format reads them, and a perfect result scores as the ground truth itself does in each."""

import json

import numpy as np
import pytest

from cli_helpers import run
from clip_helpers import otb_clip
from vistrack.io.results_format import format_line, read_result_file

pytestmark = pytest.mark.slow  # every test here (the rule: tests/conftest.py)


@pytest.mark.parametrize("fmt", ["otb", "got10k", "vot"])
def test_a_perfect_result_scores_one_in_every_format(tmp_path, capsys, fmt):
    gt0 = otb_clip(tmp_path / "sq")
    d = tmp_path / "perfect"
    if fmt == "otb":
        d.mkdir()
        path = d / "sq.txt"
    else:
        (d / "sq").mkdir(parents=True)
        path = d / "sq" / "sq_001.txt"
    path.write_text("\n".join(format_line(b, True, fmt, k) for k, b in enumerate(gt0)) + "\n")
    np.testing.assert_allclose(read_result_file(path, fmt)[1:], gt0[1:])
    code, _, err = run(["eval", str(tmp_path / "sq"), "--algos", "", "--results-dir", str(d), "--results-format", fmt,
                        "--out", str(tmp_path / "e"), "-q"], capsys)
    assert code == 0, err
    data = json.loads((tmp_path / "e" / "results.json").read_text())
    assert data["config"]["algos"] == [] and data["config"]["particles"] == []  # no default reported as used
    (r,) = data["results"]
    # every IoU is 1: above every threshold but the last (1.0 itself), as for the ground truth itself
    assert r["success_auc"] == pytest.approx(20 / 21) and r["precision_20px"] == 1.0 and r["mean_error_all"] < 1e-6


def test_run_writes_the_got10k_submission_layout_and_vot_results(tmp_path, capsys):
    otb_clip(tmp_path / "sq")
    code, _, err = run(["run", str(tmp_path / "sq"), "--init-gt", "--results", str(tmp_path / "sub"),
                        "--results-format", "got10k", "-q"], capsys)
    assert code == 0, err
    boxes = np.loadtxt(tmp_path / "sub" / "sq" / "sq_001.txt", delimiter=",")
    times = np.loadtxt(tmp_path / "sub" / "sq" / "sq_time.txt")
    assert boxes.shape == (8, 4) and times.shape == (8,) and np.all(times >= 0)
    code, _, err = run(["run", str(tmp_path / "sq"), "--init-gt", "--results", str(tmp_path / "vot"),
                        "--results-format", "vot", "-q"], capsys)
    assert code == 0, err
    lines = (tmp_path / "vot" / "sq" / "sq_001.txt").read_text().splitlines()
    assert lines[0] == "1" and len(lines) == 8 and lines[1].count(",") == 3
    otb = tmp_path / "r.txt"
    code, _, err = run(["run", str(tmp_path / "sq"), "--init-gt", "--results", str(otb), "-q"], capsys)
    assert code == 0, err
    np.testing.assert_allclose(np.loadtxt(otb, delimiter=",")[1:] - [1, 1, 0, 0], boxes[1:], atol=0.011)
    # and eval reads each back to the same scores
    scores = []
    for fmt, d in (("got10k", tmp_path / "sub"), ("vot", tmp_path / "vot")):
        code, _, err = run(["eval", str(tmp_path / "sq"), "--algos", "", "--results-dir", str(d), "--results-format",
                            fmt, "--out", str(tmp_path / f"e-{fmt}"), "-q"], capsys)
        assert code == 0, err
        scores.append(json.loads((tmp_path / f"e-{fmt}" / "results.json").read_text())["results"][0]["success_auc"])
    assert scores[0] == pytest.approx(scores[1], abs=0.02)
