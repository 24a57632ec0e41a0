"""eval reads the tracking toolkits' dataset roots (issue 37, item 2): a LaSOT root with category
folders, a GOT-10k split with list.txt and a VOT workspace, scored like the OTB-style folders of the
same frames, with the frames LaSOT/GOT-10k flag as occluded, out of view or absent left out."""

import json
import shutil

import numpy as np
import pytest

from cli_helpers import run
from path_helpers import REAL
from vistrack.io.clips import find_clips
from vistrack.io.video import read_rects

N = 30

pytestmark = pytest.mark.skipif(not (REAL / "girl_otb" / "img").is_dir(), reason="shared real clips absent")


def _images():
    return sorted((REAL / "girl_otb" / "img").glob("*.jpg"))[:N]


def _gt0():
    return read_rects(REAL / "girl_otb" / "groundtruth_rect.txt", origin=1)[:N]  # 0-based


def otb(root, absent=()):
    d = root / "girl"
    (d / "img").mkdir(parents=True)
    for p in _images():
        shutil.copy(p, d / "img" / p.name)
    gt = _gt0().copy()
    gt[list(absent)] = 0
    np.savetxt(d / "groundtruth_rect.txt", np.where(gt[:, 2:3] > 0, gt + [1, 1, 0, 0], 0), fmt="%g", delimiter=",")
    return root


def lasot(root, flagged=()):
    d = root / "person" / "person-1"
    (d / "img").mkdir(parents=True)
    for k, p in enumerate(_images()):
        shutil.copy(p, d / "img" / f"{k + 1:08d}.jpg")
    np.savetxt(d / "groundtruth.txt", _gt0() + [1, 1, 0, 0], fmt="%g", delimiter=",")  # LaSOT: 1-based
    occ = np.zeros(N, int)
    occ[list(flagged)[: len(flagged) // 2]] = 1
    oov = np.zeros(N, int)
    oov[list(flagged)[len(flagged) // 2:]] = 1
    (d / "full_occlusion.txt").write_text(",".join(map(str, occ)) + "\n")
    (d / "out_of_view.txt").write_text(",".join(map(str, oov)) + "\n")
    (root / "other").mkdir()  # a category folder holding no sequence is passed over
    return root


def got10k(root, flagged=()):
    split = root / "val"
    d = split / "GOT-10k_Val_000001"
    d.mkdir(parents=True)
    for k, p in enumerate(_images()):
        shutil.copy(p, d / f"{k + 1:08d}.jpg")
    np.savetxt(d / "groundtruth.txt", _gt0(), fmt="%g", delimiter=",")  # GOT-10k: 0-based
    absence = np.zeros(N, int)
    absence[list(flagged)] = 1
    (d / "absence.label").write_text("\n".join(map(str, absence)) + "\n")
    (split / "list.txt").write_text("GOT-10k_Val_000001\n")
    return split


def vot(root):
    d = root / "sequences" / "girl"
    (d / "color").mkdir(parents=True)
    for k, p in enumerate(_images()):
        shutil.copy(p, d / "color" / f"{k + 1:08d}.jpg")
    np.savetxt(d / "groundtruth.txt", _gt0(), fmt="%g", delimiter=",")
    (root / "sequences" / "list.txt").write_text("girl\n")
    return root


def auc(path, out, capsys):
    code, _, err = run(["eval", str(path), "--algos", "lis", "--particles", "30", "--runs", "1", "--seed", "3",
                        "--in-process", "--workers", "1", "--out", str(out), "-q"], capsys)
    assert code == 0, err
    res = json.loads((out / "results.json").read_text())["results"]
    assert len(res) == 1
    return res[0]["success_auc"], res[0]["precision_20px"]


def test_dataset_roots_are_found_in_their_own_layouts(tmp_path):
    assert [c.name for c in find_clips([lasot(tmp_path / "lasot")])] == ["person-1"]
    assert [c.name for c in find_clips([got10k(tmp_path / "got")])] == ["GOT-10k_Val_000001"]
    assert [c.name for c in find_clips([vot(tmp_path / "vot")])] == ["girl"]


@pytest.mark.slow
def test_every_layout_scores_as_the_otb_folder_and_flagged_frames_are_left_out(tmp_path, capsys):
    flagged = [10, 11, 12, 20]
    ref = auc(otb(tmp_path / "otb"), tmp_path / "e0", capsys)
    assert ref == auc(vot(tmp_path / "vot"), tmp_path / "e1", capsys)
    assert ref == auc(got10k(tmp_path / "got"), tmp_path / "e2", capsys)
    assert ref == auc(lasot(tmp_path / "lasot"), tmp_path / "e3", capsys)
    # flagged frames: scored as OTB scores frames without a box (not at all)
    want = auc(otb(tmp_path / "otb-absent", absent=flagged), tmp_path / "e4", capsys)
    assert want != ref
    assert want == auc(lasot(tmp_path / "lasot-f", flagged), tmp_path / "e5", capsys)
    assert want == auc(got10k(tmp_path / "got-f", flagged), tmp_path / "e6", capsys)
