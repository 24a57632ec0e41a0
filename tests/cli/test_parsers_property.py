"""Property tests of every parser of user input (issue 38): whatever the input, a valid value or
one clear line (click's usage error, a ``VideoError`` naming the file), never a traceback.

``--init`` boxes, ``--size``, ``--particles`` / ``--algos`` lists, ground-truth files (OTB
rectangles, VOT polygons, GOT-10k and LaSOT layouts), ``groundtruth.csv``, ``meta.json`` and
template files. Kept fast: modest ``max_examples``, files written to one temporary folder."""

from __future__ import annotations

import json
import math
import tempfile
from pathlib import Path

import click
import cv2
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from vistrack.cli.options import Box, FloatList, IntList, Size, StrList
from vistrack.io.video import VideoError

FAST = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])

#: number-ish tokens: what a user types, and what breaks parsers
NUMBER = st.one_of(st.floats(allow_nan=True, allow_infinity=True).map(repr), st.integers(-10**20, 10**20).map(str),
                   st.sampled_from(["nan", "-inf", "1e300", "-0", "1_000", "0x10", "", " ", "1e", "½", "٣"]))
TOKENS = st.one_of(NUMBER, st.text(max_size=6))
LINE = st.lists(TOKENS, max_size=9).flatmap(
    lambda ts: st.sampled_from([",", " ", "\t", ", "]).map(lambda sep: sep.join(ts)))


def one_line(message):
    """A clear message: one line, short enough to read."""
    assert "\n" not in message.strip() and 0 < len(message) < 400, message


def usage_error(ptype, value):
    """``ptype.convert(value)``: the value, or ``None`` after checking the error is one line."""
    try:
        return ptype.convert(value, None, None)
    except click.BadParameter as e:
        one_line(e.format_message())
        return None


# ------------------------------------------------------------------ options


@pytest.mark.slow
@FAST
@given(st.one_of(LINE, st.lists(NUMBER, min_size=4, max_size=4).map(",".join), st.text(max_size=40)))
def test_init_box_is_four_finite_numbers_with_a_positive_size_or_one_line(text):
    v = usage_error(Box(), text)
    if v is not None:
        assert len(v) == 4 and all(math.isfinite(x) for x in v) and v[2] > 0 and v[3] > 0


@FAST
@given(st.one_of(st.tuples(st.integers(-10, 10**5), st.integers(-10, 10**5)).map(lambda t: f"{t[0]}x{t[1]}"),
                 st.text(max_size=20)))
def test_size_is_a_valid_frame_size_or_one_line(text):
    v = usage_error(Size(), text)
    if v is not None:
        w, h = v
        assert 64 <= w <= 8192 and 48 <= h <= 8192 and w * h <= 4096 * 4096


@FAST
@given(st.one_of(st.lists(st.integers(-5, 10**6).map(str) | TOKENS, max_size=6).map(",".join), st.text(max_size=30)))
def test_particle_lists_are_distinct_integers_or_one_line(text):
    v = usage_error(IntList(), text)
    if v is not None:
        assert all(isinstance(n, int) for n in v) and len(set(v)) == len(v)


@FAST
@given(st.one_of(st.lists(st.sampled_from(["lis", "bootstrap", "avpf", " lis", ""]) | st.text(max_size=5),
                          max_size=6).map(",".join), st.text(max_size=30)))
def test_algorithm_lists_are_distinct_names_or_one_line(text):
    v = usage_error(StrList(), text)
    if v is not None:
        assert all(a and a == a.strip() for a in v) and len(set(v)) == len(v)


@FAST
@given(st.one_of(st.lists(NUMBER, max_size=5).map(",".join), st.text(max_size=30)))
def test_float_lists_are_finite_or_one_line(text):
    v = usage_error(FloatList(), text)
    if v is not None:
        assert all(math.isfinite(x) for x in v)


# ------------------------------------------------------------------ files

_TMP = tempfile.TemporaryDirectory(prefix="vistrack-parsers-")
ROOT = Path(_TMP.name)


def _clip(layout):
    """A 2-frame 160x120 clip folder in ``layout`` (its ground truth written by the test)."""
    d = ROOT / layout
    if not d.exists():
        frames = {"otb": d / "img", "lasot": d / "img", "vot": d / "color", "got10k": d}[layout]
        frames.mkdir(parents=True)
        for i in range(2):
            cv2.imwrite(str(frames / f"{i + 1:08d}.jpg"), np.full((120, 160, 3), 90 + 40 * i, np.uint8))
        if layout == "lasot":
            (d / "full_occlusion.txt").write_text("0,0\n")
            (d / "out_of_view.txt").write_text("0,1\n")
    return d


GT_NAME = {"otb": "groundtruth_rect.txt", "lasot": "groundtruth.txt", "vot": "groundtruth.txt",
           "got10k": "groundtruth.txt"}
POLYGON = st.lists(st.floats(-1e4, 1e4, allow_nan=False), min_size=8, max_size=8).map(
    lambda v: ",".join(f"{x:.2f}" for x in v))
GT_TEXT = st.one_of(
    st.lists(st.one_of(LINE, POLYGON), max_size=4).map("\n".join),
    st.binary(max_size=60).map(lambda b: b.decode("latin-1")),
    st.lists(st.lists(NUMBER, min_size=4, max_size=4).map(",".join), max_size=3).map(
        lambda rows: "\ufeff" + "\n".join(rows)))


def _load(path_text_pairs, folder):
    from vistrack.io.clips import load_clip

    for name, data in path_text_pairs:
        (folder / name).write_bytes(data if isinstance(data, bytes) else data.encode("utf-8", "surrogatepass"))
    try:
        return load_clip(folder)
    except VideoError as e:
        one_line(str(e))
        return None


@FAST
@given(st.sampled_from(["otb", "lasot", "vot", "got10k"]), GT_TEXT)
def test_ground_truth_files_give_finite_boxes_or_one_line_naming_the_file(layout, text):
    folder = _clip(layout)
    try:
        data = text.encode("utf-8")
    except UnicodeEncodeError:
        return
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            clip = _load([(GT_NAME[layout], data)], folder)
        except VideoError as e:  # pragma: no cover - _load catches
            raise AssertionError(e) from None
    if clip is None:
        return
    t = clip.truth
    vis = t["visible"] > 0
    for k in ("cx", "cy", "w", "h"):
        assert np.all(np.isfinite(t[k][vis])) and np.all(np.abs(t[k][vis]) <= 2e6)
    assert np.all(t["w"][vis] > 0) and np.all(t["h"][vis] > 0)


def test_ground_truth_errors_name_the_file_and_line():
    from vistrack.io.video import read_rects

    p = ROOT / "named.txt"
    for text, words in (("1,2,3,4\n1,2,x,4\n", "line 2"), ("1,2,3\n", "line 1"), ("1e300,2,3,4\n", "line 1"),
                        (b"\x00\xff\xfe", "not a text file")):
        p.write_bytes(text if isinstance(text, bytes) else text.encode())
        with pytest.raises(VideoError) as e:
            read_rects(p)
        assert str(p) in str(e.value) and words in str(e.value)


JSON = st.recursive(st.none() | st.booleans() | st.floats(allow_nan=False) | st.text(max_size=8),
                    lambda children: st.lists(children, max_size=3) | st.dictionaries(st.text(max_size=8), children,
                                                                                     max_size=3), max_leaves=8)
META = st.one_of(JSON, st.fixed_dictionaries({"model": JSON}, optional={"template": JSON, "layout": JSON}))


@FAST
@given(st.one_of(META.map(json.dumps), st.binary(max_size=40).map(lambda b: b.decode("latin-1"))))
def test_meta_json_is_an_object_or_one_line(text):
    from vistrack.io.clips import read_meta

    p = ROOT / "meta.json"
    p.write_bytes(text.encode("utf-8", "surrogatepass"))
    try:
        meta = read_meta(p)
    except VideoError as e:
        one_line(str(e))
        assert str(p) in str(e)
        return
    assert isinstance(meta, dict) and isinstance(meta.get("model", ""), str)


@pytest.mark.slow
@FAST
@given(st.one_of(st.lists(LINE, max_size=6).map("\n".join), META.map(json.dumps),
                 st.lists(st.tuples(NUMBER, NUMBER), max_size=6).map(lambda ps: "\n".join(f"{a} {b}" for a, b in ps))),
       st.sampled_from([".txt", ".json"]))
def test_template_files_are_finite_points_or_one_line(text, suffix):
    from vistrack.registry.builders import read_support_points

    p = ROOT / f"template{suffix}"
    p.write_text(text)
    try:
        pts = read_support_points(p)
    except VideoError as e:
        one_line(str(e))
        assert str(p) in str(e)
        return
    assert pts.ndim == 2 and pts.shape[1] == 2 and len(pts) >= 4 and np.all(np.isfinite(pts))


@FAST
@given(st.lists(st.lists(NUMBER, min_size=6, max_size=7), max_size=3))
def test_groundtruth_csv_is_numbers_or_one_line(rows):
    folder = ROOT / "csvclip"
    if not folder.exists():
        _clip("otb").joinpath("img")  # frames
        import shutil

        shutil.copytree(ROOT / "otb" / "img", folder / "img")
    text = "frame,visible,cx,cy,w,h\n" + "\n".join(",".join(r) for r in rows)
    clip = _load([("groundtruth.csv", text)], folder)
    if clip is not None:
        t = clip.truth
        vis = t["visible"] > 0
        assert all(np.all(np.abs(np.nan_to_num(t[k][vis])) <= 1e6) for k in ("cx", "cy", "w", "h"))


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.one_of(st.lists(NUMBER, min_size=4, max_size=4).map(",".join),
                 st.tuples(st.floats(-400, 400), st.floats(-400, 400), st.floats(0.5, 1e13), st.floats(0.5, 1e13))
                 .map(lambda b: ",".join(f"{v:.6g}" for v in b))))
def test_run_with_any_init_box_tracks_or_says_one_line(box):
    """The whole ``run`` path (parse, frame check, model): exit 0, or one ``Error:`` line."""
    import contextlib
    import io

    from vistrack.cli import main

    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()), pytest.raises(SystemExit) as e:
        main(["run", str(_clip("otb")), "--init", box, "-n", "10", "--max-frames", "1", "-q", "--model", "box"])
    text = err.getvalue()
    assert "Traceback" not in text
    if e.value.code not in (0, None):
        lines = [ln for ln in text.splitlines() if ln.startswith("Error:")]
        assert len(lines) == 1, text
        one_line(lines[0])
