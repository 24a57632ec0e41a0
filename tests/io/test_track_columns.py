"""The track CSV is documented from one list (issue 54, item 2): every column a model writes and every
``lost_reason`` value the code can write (it writes no other: ``check_lost_reason``) appear in
``run --help`` and in docs/tracking.md."""

import csv
import re

import pytest

from cli_helpers import run
from path_helpers import ROOT
from vistrack.io.track_files import LOST_REASONS, TRACK_COLUMNS, check_lost_reason, column_name
from vistrack.models.collapse import REASONS
from vistrack.session.plan import track_video

DOCS = ROOT / "docs" / "tracking.md"


def _help():
    code, out, _ = run(["run", "--help"])
    assert code == 0
    return out


def test_every_column_and_lost_reason_is_in_run_help_and_the_docs():
    helptext, docs = _help(), DOCS.read_text()
    for name in [*TRACK_COLUMNS, *LOST_REASONS]:
        assert re.search(rf"^\s+{re.escape(name)}\s", helptext, re.M), name  # a line of its own in --help
        assert f"`{name}`" in docs, name


def test_the_models_own_verdicts_are_in_the_list_and_nothing_else_is_written():
    assert set(REASONS) <= set(LOST_REASONS)
    assert check_lost_reason("") == "" and check_lost_reason("collapse") == "collapse"
    with pytest.raises(ValueError, match="lost_reason 'vanished' is not one of collapse, low-confidence"):
        check_lost_reason("vanished")


def test_column_names_stand_for_their_numbered_columns():
    assert [column_name(c) for c in ("cx", "qx12", "qy0", "x3", "ly4", "lost_reason")] == [
        "cx", "qx0..", "qy0..", "x0..", "ly0..", "lost_reason"]


@pytest.mark.parametrize("kind, model, targets", [
    ("contour", "box", None), ("contour", "contour", None), ("plate", "plate", None), ("plate", "plate", 2),
    ("landmarks", "landmarks", None)])
def test_every_column_a_model_writes_is_listed(tmp_path, synth_clip, kind, model, targets):
    if kind == "landmarks":
        from vistrack.data_synth.landmark_clip import make_landmark_clip

        clip = tmp_path / "lm"
        make_landmark_clip(clip, frames=3, seed=1)
    else:
        small = {"frames": 3, "size": (160, 120)} if kind == "contour" else {"frames": 40}  # a plate in view
        clip = synth_clip(kind, seed=1, **small)
    track_video(clip, model=model, particles=20, init_gt="" if model in ("box", "contour") else None, targets=targets,
                outputs={"track_path": tmp_path / "t.csv"})
    with open(tmp_path / "t.csv", newline="") as f:
        header = next(csv.reader(f))
    assert header[:2] == ["frame", "visible"] and {column_name(c) for c in header} <= set(TRACK_COLUMNS), header
