"""Faults of the Python API: ``vistrack.Tracker`` checks every argument when it is made, takes any frame a
user may reasonably pass and refuses the rest with one ``ValueError`` line."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from fault_helpers import (
    api_frames,
    api_track,
    box_frame,
)


def test_4_the_python_api_checks_the_start_box_too():
    import vistrack

    for box, words in (((0, 0, 1e12, 1e12), "far larger than the 160x120 frame"),
                       ((-100, -100, 50, 50), "lies outside the 160x120 frame")):
        with pytest.raises(ValueError, match=words):
            vistrack.Tracker().init(box_frame(0), box)

@pytest.mark.parametrize("kw, words", [
    (dict(seed=-1), "seed must be an integer >= 0"),
    (dict(seed=1.5), "seed must be an integer >= 0"),
    (dict(particles=2.5), "particles must be an integer >= 1, got 2.5"),
    (dict(particles=0), "particles must be an integer >= 1, got 0"),
    (dict(ess_threshold=float("nan")), "ess_threshold must be a number in [0, 1]"),
    (dict(ess_threshold=-1), "ess_threshold must be a number in [0, 1]"),
    (dict(ess_threshold=5), "ess_threshold must be a number in [0, 1]"),
    (dict(resample="best"), "unknown resampling scheme 'best'; choose from"),
    (dict(model="box", frobnicate=3), "unknown option 'frobnicate' for the box model; its options include"),
    (dict(model="plate", frobnicate=3), "unknown option 'frobnicate' for the plate model; its options include"),
], ids=lambda v: str(v)[:30])
def test_the_tracker_checks_every_argument_when_it_is_made(kw, words):
    import vistrack

    with pytest.raises(ValueError) as e:
        vistrack.Tracker(**kw)
    assert words in str(e.value) and "\n" not in str(e.value)

def test_the_tracker_names_the_options_it_takes():
    import vistrack

    with pytest.raises(ValueError, match="lambda_dcf, lambda_scale, lean_when_lost, lost_confidence, map_stride"):
        vistrack.Tracker(model="box", frobnicate=3)
    vistrack.Tracker(model="box", lambda_dcf=30.0, lambda_template=2.0)  # the model's own and its appearance's

@pytest.mark.parametrize("convert", [
    lambda f: f.astype(np.float64) / 255, lambda f: f.astype(np.float32), lambda f: f.astype(np.uint16) * 257,
    lambda f: f.astype(np.int64), lambda f: f.tolist(), lambda f: cv2.cvtColor(f, cv2.COLOR_BGR2BGRA),
], ids=["float 0..1", "float 0..255", "uint16", "int64", "nested lists", "BGRA"])
def test_the_tracker_takes_any_reasonable_frame(convert):
    """Frames a user may pass are converted once into the uint8 BGR frame run decodes: the same track."""
    frames = api_frames()
    assert api_track([convert(f) for f in frames]) == api_track(frames)

def test_the_tracker_takes_grey_frames_of_one_channel():
    grey = [cv2.cvtColor(f, cv2.COLOR_BGR2GRAY) for f in api_frames()]
    assert api_track([g[:, :, None] for g in grey]) == api_track(grey)

@pytest.mark.parametrize("frame, words", [
    (np.ones((90, 120), bool), "dtype bool"),
    (np.ones((90, 120), complex), "dtype complex128"),
    (np.full((90, 120), np.nan), "NaN"),
    (np.full((90, 120), 300, np.int64), "values in 0..255"),
    (np.full((90, 120), -1.0), "values in 0..1 or 0..255"),
    (np.zeros((90, 120, 2), np.uint8), "shape (90, 120, 2)"),
    (np.zeros((2, 90, 120, 3), np.uint8), "shape (2, 90, 120, 3)"),
    (np.zeros((0, 120, 3), np.uint8), "shape (0, 120, 3)"),
    ([[1, 2], [3]], "ragged"),
    ("frame.png", "dtype <U9"),
], ids=["bool", "complex", "nan", "int over 255", "negative", "2 channels", "4-d", "empty", "ragged", "text"])
def test_the_tracker_refuses_a_frame_it_cannot_read_with_one_line(frame, words):
    import vistrack

    with pytest.raises(ValueError) as e:
        vistrack.Tracker().init(frame, (30, 30, 25, 25))
    assert words in str(e.value) and "\n" not in str(e.value)

def test_a_frame_size_or_kind_change_after_init_is_an_error_as_in_run():
    import vistrack

    frames = api_frames()
    t = vistrack.Tracker()
    t.init(frames[0], (30, 30, 25, 25))
    with pytest.raises(ValueError, match="this frame is 120x80 colour, but the tracker started on 120x90 colour"):
        t.update(frames[1][:80])
    with pytest.raises(ValueError, match="this frame is 120x90 grey, but the tracker started on 120x90 colour"):
        t.update(cv2.cvtColor(frames[1], cv2.COLOR_BGR2GRAY))
    ok, box = t.update(frames[1])  # the tracker goes on
    assert t.result.index == 1
    with pytest.raises(ValueError, match=r"box must be four numbers \(x, y, w, h\), got 3"):
        vistrack.Tracker().init(frames[0], (1, 2, 3))
    with pytest.raises(ValueError, match="box must be four numbers"):
        vistrack.Tracker().init(frames[0], "30,30,25,25")


# ------------------------------------------------------------------ the fourth sweep (issue 55)


@pytest.mark.parametrize("kw, words", [
    (dict(lambda_template="x"), "lambda_template must be a finite number >= 0, got 'x'"),
    (dict(lambda_template=float("nan")), "lambda_template must be a finite number >= 0, got nan"),
    (dict(prior_std=-1), "prior_std must be 2 finite numbers > 0, got -1"),
    (dict(prior_std=(0.1, float("nan"))), "prior_std must be 2 finite numbers > 0, got (0.1, nan)"),
    (dict(lost_confidence=2), "lost_confidence must be None or a finite number in [0, 1], got 2"),
    (dict(redetect="yes"), "redetect must be None or a finite number >= 0, got 'yes'"),
    (dict(map_stride=1.5), "map_stride must be an integer >= 1, got 1.5"),
    (dict(interpolation="cubic"), "interpolation must be one of 'area', 'linear', got 'cubic'"),
    (dict(dcf=1), "dcf must be True or False, got 1"),
], ids=lambda v: str(v)[:28])
def test_the_tracker_checks_each_model_option_against_its_declared_type_and_range(kw, words):
    """Tracker(lambda_template='x') was accepted (numpy's UFuncTypeError at init), prior_std=-1 raised
    'int object is not subscriptable', lambda_template=nan and lost_confidence=2 were accepted,
    redetect='yes' said 'could not convert string to float'. Each is now one line naming the option."""
    import vistrack

    with pytest.raises(ValueError) as e:
        vistrack.Tracker(model="box", **kw)
    assert str(e.value) == words


def test_good_model_options_pass_and_are_the_declared_ones():
    import vistrack
    from vistrack.registry import get_model_spec
    from vistrack.registry.option_types import declared_options

    vistrack.Tracker(model="box", lambda_template=2, lost_confidence=None, prior_std=[0.1, 0.05],
                     interpolation="linear")
    d = declared_options(get_model_spec("box"))
    assert d["lambda_template"].bounds == (0.0, False, float("inf"), False)  # Appearance's, passed on
    assert d["lost_confidence"].none_ok and d["lost_confidence"].bounds == (0.0, False, 1.0, False)
    assert d["prior_std"].kind == "tuple" and d["prior_std"].element == "float"


def test_the_tracker_attributes_before_init_are_none():
    """Tracker().box before init raised AttributeError: 'NoneType' object has no attribute 'box'."""
    import vistrack

    t = vistrack.Tracker()
    assert (t.box, t.box_estimate, t.visible, t.confidence, t.lost_reason, t.particles, t.result) == (None,) * 7
    assert "not started" in repr(t)


def test_run_checks_its_model_options_with_the_same_check():
    from vistrack.registry import model_params

    assert model_params("plate", {"--targets": 3}) == {"targets": 3}
    with pytest.raises(ValueError, match="targets must be an integer, got 2.5"):
        model_params("plate", {"--targets": 2.5})


@pytest.mark.parametrize("kw, words", [
    (dict(share=2), "share must be a finite number in [0, 1], got 2"),
    (dict(cells=0), "cells must be an integer >= 1, got 0"),
    (dict(widen=0.5), "widen must be a finite number >= 1, got 0.5"),
    (dict(hold_when_lost=1), "hold_when_lost must be True or False, got 1"),
    (dict(confidence="/nonexistent/siam.npz"),
     "confidence: cannot read a calibration from /nonexistent/siam.npz (No such file or directory)"),
], ids=lambda v: str(v)[:28])
def test_the_siam_model_declares_its_options_and_reads_a_calibration_path(kw, words):
    """The siam model's options are checked from its docstring as the box model's are; ``confidence`` takes a
    path as documented (a type line of several types was checked as its default's bool)."""
    import vistrack

    frame = np.zeros((120, 160, 3), np.uint8)
    with pytest.raises(ValueError) as e:
        vistrack.Tracker(model="siam", **kw).init(frame, (40, 40, 30, 30))
    assert str(e.value) == words
