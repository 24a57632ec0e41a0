"""The benchmark corpus and the tuning command's cross-validation (issue 43): start boxes as a user
types them, OTB's robustness starts, and leave-one-clip-out choices that are known and repeat."""

import numpy as np
import pytest
from real_corpus import find_clips, lost_runs, sre_starts, user_box
from tune_box import candidates, cross_validate


def test_leave_one_clip_out_choice_is_known_and_repeats():
    # 3 configurations x 4 clips: config 1 best on average, but clip 2 alone favours config 2
    scores = np.array([[0.50, 0.50, 0.50, 0.50],
                       [0.70, 0.70, 0.10, 0.70],
                       [0.10, 0.10, 0.95, 0.10]])
    chosen, held = cross_validate(scores)
    # leaving out clip 2, config 1 wins on the rest (0.70) and scores 0.10 there: the in-sample winner
    # does not carry over to the clip whose favourite was fitted on it
    np.testing.assert_array_equal(chosen, [1, 1, 1, 1])
    np.testing.assert_allclose(held, [0.70, 0.70, 0.10, 0.70])
    again = cross_validate(scores.copy())
    np.testing.assert_array_equal(again[0], chosen)
    np.testing.assert_array_equal(again[1], held)


def test_ties_go_to_the_earlier_configuration():
    chosen, held = cross_validate(np.array([[0.4, 0.6], [0.4, 0.6]]))
    np.testing.assert_array_equal(chosen, [0, 0])
    np.testing.assert_allclose(held, [0.4, 0.6])


def test_candidates_start_with_the_defaults_and_drop_repeats():
    got = candidates(grid={"a": [1, 2]}, configs={"same_as_a1": {"a": 1}, "b": {"b": 0}})
    assert got == [("defaults", {}), ("same_as_a1", {"a": 1}), ("b", {"b": 0}), ("a=2", {"a": 2})]


@pytest.mark.parametrize("text, want", [
    ("198,214,34,81\n", (198, 214, 34, 81)),  # OTB: as written
    ("130.5\t180.2\t57.6\t34.4\n", (130, 180, 58, 34)),  # whole pixels, rounded
    ("10,10,30,10,30,40,10,40\n", (10, 10, 20, 30)),  # a VOT polygon: its bounding box
    ("\n\n5 6 7 8\n", (5, 6, 7, 8)),
])
def test_the_users_start_box_is_the_first_line_in_whole_pixels(tmp_path, text, want):
    p = tmp_path / "groundtruth_rect.txt"
    p.write_text(text)
    assert user_box(p) == want


def test_robustness_starts_are_otbs_twelve():
    starts = sre_starts((100, 50, 40, 20))
    assert len(starts) == 12 and len(set(starts)) == 12
    assert (96, 48, 40, 20) in starts and (104, 52, 40, 20) in starts  # shifted by 10 % of w and h
    assert (100, 50, 40, 20) not in starts
    assert (104, 52, 32, 16) in starts and (96, 48, 48, 24) in starts  # scaled 0.8 and 1.2 about the centre


def test_lost_runs_count_only_runs_of_five_or_more():
    truth = np.tile([[10.0, 10, 10, 10]], (12, 1))
    boxes = truth.copy()
    boxes[2:5] = [100, 100, 10, 10]  # 3 frames off: not a run
    boxes[6:12] = [100, 100, 10, 10]  # 6 frames off
    truth[11] = 0  # no object on the last frame: not counted
    np.testing.assert_array_equal(np.flatnonzero(lost_runs(boxes, truth)), [6, 7, 8, 9, 10])


def test_the_corpus_is_every_folder_with_ground_truth(tmp_path):
    for name in ("b_clip", "a_clip"):
        (tmp_path / name).mkdir()
        (tmp_path / name / "groundtruth_rect.txt").write_text("1,2,3,4\n1,2,3,4\n")
    (tmp_path / "no_truth").mkdir()
    clips = find_clips(tmp_path)
    assert [c.name for c in clips] == ["a_clip", "b_clip"]
    assert clips[0].user_box == (1, 2, 3, 4)
    with pytest.raises(SystemExit, match="not found .* missing_clip"):
        find_clips(tmp_path, ["missing_clip"])
