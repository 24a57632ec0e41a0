"""Faults that break the data read: damaged, truncated, odd or empty videos and image folders, ground truth
and meta.json that are not what their layout says. Each frame of the input is accounted for, and bad data
is one line naming the file."""

from __future__ import annotations

import csv
import warnings

import cv2
import numpy as np
import pytest

from cli_helpers import run
from fault_helpers import (
    H,
    W,
    avi,
    damage_copy,
    decodable,
    image_folder,
    mp4,
    one_error,
    otb_folder,
    read_rows,
    write_video,
)


def test_truncated_and_empty_videos_are_clear_errors(tmp_path, capsys):
    video = tmp_path / "v.avi"
    write_video(video, 20)
    data = video.read_bytes()
    (tmp_path / "empty.avi").write_bytes(b"")
    (tmp_path / "head.avi").write_bytes(data[:200])
    for name in ("empty.avi", "head.avi"):
        code, _, err = run(["run", str(tmp_path / name), "--init", "48,51,24,18", "-q"], capsys)
        assert code != 0 and err.startswith("Error:") and "Traceback" not in err, (name, err)

def test_prefetch_gives_the_same_frames_and_stops_cleanly(tmp_path):
    import threading

    from vistrack.io.video import open_video, prefetch

    video = tmp_path / "v.avi"
    write_video(video, 30)
    src = open_video(video)
    direct = [(i, f.copy()) for i, f in src]
    ahead = list(prefetch(src, size=3))
    assert [i for i, _ in ahead] == [i for i, _ in direct]
    assert all(np.array_equal(a, b) for (_, a), (_, b) in zip(ahead, direct))
    before = set(threading.enumerate())
    gen = prefetch(src, size=2)
    next(gen)
    (decoder,) = [t for t in threading.enumerate() if t.name == "vistrack-decode" and t not in before]
    gen.close()  # stopping early ends the decoder thread: close() returns once it has ended
    assert not decoder.is_alive()

    def broken():
        yield 0, direct[0][1]
        raise VideoError_("disk gone")

    class VideoError_(RuntimeError):
        pass

    with pytest.raises(VideoError_, match="disk gone"):
        list(prefetch(broken()))

def test_an_undecodable_image_is_skipped_and_counted(tmp_path, capsys):
    """One bad image in an image folder: tracking goes on at the next frame, the bad frame has a row
    with visible=0, lost_reason "decode" (issue 38: every input frame accounted for; indices stay
    the stream's), and the warning says how many failed."""
    import warnings

    from vistrack.io.video import VideoDecodeWarning, open_video

    (tmp_path / "img").mkdir()
    for i in range(8):
        img = np.full((H, W, 3), 100, np.uint8)
        cv2.rectangle(img, (40 + 2 * i, 50), (64 + 2 * i, 68), (30, 60, 220), -1)
        cv2.imwrite(str(tmp_path / "img" / f"{i + 1:04d}.jpg"), img)
    (tmp_path / "img" / "0004.jpg").write_bytes(b"\xff\xd8 not a jpeg")
    src = open_video(tmp_path)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        idx = [i for i, _ in src]
    assert idx == [0, 1, 2, 4, 5, 6, 7] and src.skipped == [3]
    assert any(issubclass(w.category, VideoDecodeWarning) and "1 frame(s) of 8" in str(w.message) for w in caught)
    code, out, err = run(["run", str(tmp_path), "--init", "40,50,25,19", "--track", str(tmp_path / "t.csv")], capsys)
    assert code == 0, err
    rows = read_rows(tmp_path / "t.csv")
    assert [int(r["frame"]) for r in rows] == list(range(8))
    assert (rows[3]["visible"], rows[3]["lost_reason"]) == ("0", "decode")
    assert "1 frame(s) failed to decode: 3 (their rows have visible=0" in err

def test_damaged_videos_give_the_frames_opencv_decodes(tmp_path, capsys):
    """Cut at 60 % with the moov atom at the front: the frames before the cut; at the end (no index):
    one error line; bytes overwritten mid-stream: every frame OpenCV still decodes, in order."""
    mp4(tmp_path / "front.mp4", 20, True)
    mp4(tmp_path / "end.mp4", 20, False)
    write_video(tmp_path / "v.avi", 20)
    for name in ("front.mp4", "end.mp4"):
        data = (tmp_path / name).read_bytes()
        (tmp_path / f"cut_{name}").write_bytes(data[: int(0.6 * len(data))])
    data = bytearray((tmp_path / "v.avi").read_bytes())
    k = len(data) // 2
    data[k:k + 1500] = bytes(range(256)) * 5 + bytes(220)
    (tmp_path / "hit.avi").write_bytes(bytes(data))
    for name in ("cut_front.mp4", "hit.avi"):
        t = tmp_path / f"{name}.csv"
        code, _, err = run(["run", str(tmp_path / name), "--init", "48,51,24,18", "-n", "20", "-q", "--track", str(t)],
                           capsys)
        n = decodable(tmp_path / name)
        assert code == 0 and "Traceback" not in err and 0 < n < 20 or name == "hit.avi", (name, n, err)
        rows = [int(r["frame"]) for r in read_rows(t)]
        assert len(rows) == n and rows == sorted(rows)
    code, _, err = run(["run", str(tmp_path / "cut_end.mp4"), "--init", "48,51,24,18", "-q"], capsys)
    assert code != 0 and "is not a video OpenCV can decode" in err and err.count("\n") == 1

@pytest.mark.parametrize("kind", ["1-frame", "8x8", "3840x2160", "grey", "4-channel"])
def test_odd_frames_track(tmp_path, capsys, kind):
    """One frame, 8x8 and 3840x2160 frames, grey and 4-channel images: a track with a row per frame."""
    init = "48,51,24,18"
    if kind in ("1-frame", "8x8", "3840x2160"):
        size = {"1-frame": (W, H), "8x8": (8, 8), "3840x2160": (3840, 2160)}[kind]
        n = 1 if kind == "1-frame" else 2
        video = tmp_path / "v.mp4"
        mp4(video, n, True, size)
        init = {"8x8": "1,1,5,5", "3840x2160": "1400,1000,300,200"}.get(kind, init)
    else:
        video, n = tmp_path / "img", 3
        video.mkdir()
        for i in range(n):
            img = np.full((H, W, 3), 90, np.uint8)
            cv2.rectangle(img, (48 + i, 51), (72 + i, 69), (30, 60, 220), -1)
            img = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY) if kind == "grey" else cv2.cvtColor(img, cv2.COLOR_BGR2BGRA)
            cv2.imwrite(str(video / f"{i + 1:04d}.png"), img)
    t = tmp_path / "t.csv"
    code, _, err = run(["run", str(video), "--init", init, "-n", "20", "-q", "--track", str(t)], capsys)
    assert code == 0, err
    rows = read_rows(t)
    assert len(rows) == n and all(np.isfinite(float(r[c])) for r in rows for c in ("cx", "cy", "w", "h"))

def test_3_frames_of_another_size_are_one_error_line(tmp_path, capsys):
    image_folder(tmp_path / "c", 6)
    cv2.imwrite(str(tmp_path / "c" / "img" / "0004.png"), np.zeros((240, 320, 3), np.uint8))
    for extra in (["--out", str(tmp_path / "a.mp4")], []):
        code, _, err = run(["run", str(tmp_path / "c"), "--init", "40,50,25,19", "--track", str(tmp_path / "t.csv"),
                            "-q", *extra], capsys)
        one_error(code, err, "0004.png", "320x240", "160x120")
        assert [r["frame"] for r in read_rows(tmp_path / "t.csv")] == ["0", "1", "2"]  # the frames before it, kept

@pytest.mark.parametrize("meta", ["[1, 2, 3]", '"hello"', "3", '{"model": [1]}'])
def test_5_meta_json_that_is_not_an_object(tmp_path, capsys, meta):
    image_folder(tmp_path / "c", 2)
    (tmp_path / "c" / "meta.json").write_text(meta)
    code, _, err = run(["run", str(tmp_path / "c"), "--init", "40,50,25,19", "-q"], capsys)
    one_error(code, err, "meta.json")
    code, _, err = run(["eval", str(tmp_path / "c"), "--algos", "lis", "--particles", "10", "--runs", "1",
                        "--out", str(tmp_path / "e"), "-q"], capsys)
    one_error(code, err, "meta.json")

def test_6_every_input_frame_gets_a_row_and_a_results_line(tmp_path, capsys):
    image_folder(tmp_path / "c", 10)
    for k in (0, 4, 5, 9):  # the first, two in the middle and the last
        (tmp_path / "c" / "img" / f"{k + 1:04d}.png").write_bytes(b"not a png")
    track, res, out = tmp_path / "t.csv", tmp_path / "r.txt", tmp_path / "a.mp4"
    code, _, err = run(["run", str(tmp_path / "c"), "--init", "42,50,25,19", "--track", str(track), "--results",
                        str(res), "--out", str(out), "-q"], capsys)
    assert code == 0, err
    rows = read_rows(track)
    assert [int(r["frame"]) for r in rows] == list(range(10))
    bad = [int(r["frame"]) for r in rows if r["lost_reason"] == "decode"]
    assert bad == [0, 4, 5, 9] and all(rows[k]["visible"] == "0" for k in bad)
    lines = res.read_text().splitlines()
    assert len(lines) == 10 and all(lines[k] == "0.00,0.00,0.00,0.00" for k in bad)
    assert lines[1] != "0.00,0.00,0.00,0.00"
    assert int(cv2.VideoCapture(str(out)).get(cv2.CAP_PROP_FRAME_COUNT)) == 10
    assert "4 frame(s) failed to decode: 0, 4, 5, 9" in err

def test_9_init_gt_starts_at_the_first_frame_with_a_box(tmp_path, capsys):
    truth = image_folder(tmp_path / "c", 10)
    lines = (tmp_path / "c" / "groundtruth_rect.txt").read_text().splitlines()
    (tmp_path / "c" / "groundtruth_rect.txt").write_text("\n".join(["NaN,NaN,NaN,NaN"] * 4 + lines[4:]) + "\n")
    res, track = tmp_path / "r.txt", tmp_path / "t.csv"
    code, out, err = run(["run", str(tmp_path / "c"), "--init-gt", "--results", str(res), "--track", str(track)],
                         capsys)
    assert code == 0, err
    assert "no box before frame 4: tracking starts there" in err
    got = np.array([[float(v) for v in ln.split(",")] for ln in res.read_text().splitlines()])
    assert len(got) == 10 and not got[:4].any()
    assert [r["lost_reason"] for r in read_rows(track)[:4]] == ["not started"] * 4
    err_px = np.hypot(*(got[4:, :2] + got[4:, 2:] / 2 - truth[4:, :2] - truth[4:, 2:] / 2).T)
    assert err_px.max() < 6, err_px  # learned on the box at frame 4, not on frame 0's background
    assert "vs ground truth (6 frames with the object)" in out

def test_10_image_folders_are_read_in_natural_order(tmp_path):
    from vistrack.io.video import FrameOrderWarning, open_video

    image_folder(tmp_path / "c", names=[f"frame{i}.png" for i in range(1, 13)])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        src = open_video(tmp_path / "c")
    assert [p.name for p in src._images] == [f"frame{i}.png" for i in range(1, 13)]
    image_folder(tmp_path / "d", names=["1.png", "01.png", "2.png"])
    with pytest.warns(FrameOrderWarning, match="ambiguous"):
        open_video(tmp_path / "d")

def test_12_a_video_that_ends_early_says_where(tmp_path, capsys):
    avi(tmp_path / "v.avi", 40)
    data = (tmp_path / "v.avi").read_bytes()
    (tmp_path / "t.avi").write_bytes(data[: int(0.6 * len(data))])
    code, _, err = run(["run", str(tmp_path / "t.avi"), "--init", "40,50,25,19", "-q"], capsys)
    assert code == 0, err
    assert "ended early: decoding stopped at frame" in err and "of the 40 its header announces" in err

def test_13_absurd_ground_truth_values_are_one_short_line(tmp_path, capsys):
    image_folder(tmp_path / "c", 3)
    (tmp_path / "c" / "groundtruth_rect.txt").write_text("41,51,25,19\n1e300,5,6,7\n41,51,25,19\n")
    code, _, err = run(["run", str(tmp_path / "c"), "--init-gt", "-q"], capsys)
    line = one_error(code, err, "groundtruth_rect.txt, line 2", "not a pixel coordinate")
    assert len(line) < 300

def test_14_binary_bom_and_nan_input_files(tmp_path, capsys):
    image_folder(tmp_path / "c", 3)
    gt = tmp_path / "c" / "groundtruth_rect.txt"
    text = gt.read_text()
    gt.write_bytes(b"\x89PNG\r\n\x1a\n\xff\xfe" + bytes(range(256)))
    code, _, err = run(["run", str(tmp_path / "c"), "--init-gt", "-q"], capsys)
    one_error(code, err, str(gt), "not a text file")
    gt.write_bytes(b"\xef\xbb\xbf" + text.encode())  # a UTF-8 byte-order mark
    code, _, err = run(["run", str(tmp_path / "c"), "--init-gt", "-q"], capsys)
    assert code == 0, err
    tpl = tmp_path / "t.txt"
    tpl.write_text("10 10\nnan 12\n14 14\n20 20\n")
    code, _, err = run(["run", str(tmp_path / "c"), "--model", "contour", "--init", "40,50,25,19", "--template",
                        str(tpl), "-q"], capsys)
    one_error(code, err, str(tpl), "support point 2 is not a finite pixel position")

def test_init_gt_with_missing_first_boxes_keeps_the_redetected_column(tmp_path):

    seq = otb_folder(tmp_path / "seq", 8)
    rows = (seq / "groundtruth_rect.txt").read_text().splitlines()
    (seq / "groundtruth_rect.txt").write_text("\n".join(["NaN,NaN,NaN,NaN"] * 3 + rows[3:]) + "\n")
    code, _, err = run(["run", seq, "--init-gt", "-n", "30", "-q", "--track", tmp_path / "t.csv"])
    assert code == 0, err
    with open(tmp_path / "t.csv", newline="") as f:
        track = list(csv.DictReader(f))
    assert list(track[0]) == ["frame", "visible", "cx", "cy", "w", "h", "angle_deg", "scale", "redetected", "ess", "ms",
                              "lost_reason", "confidence"]
    assert [r["lost_reason"] for r in track[:3]] == ["not started"] * 3
    assert {r["redetected"] for r in track[:3]} == {"0"}

@pytest.mark.parametrize("gt, words", [
    ("1,1,0.5,0.5", "is smaller than 2 px (0.5x0.5)"),
    ("500,500,20,20", "lies outside the 160x120 frame"),
])
def test_a_tiny_ground_truth_box_is_called_tiny_not_outside(tmp_path, gt, words):
    seq = otb_folder(tmp_path / "seq", 3)
    (seq / "groundtruth_rect.txt").write_text(f"{gt}\n" * 3)
    code, _, err = run(["run", seq, "--init-gt", "-q"])
    one_error(code, err, words)

def test_fit_plate_refuses_clips_without_plates(tmp_path, capsys):
    from vistrack.data_synth.contour_clip import make_contour_clip

    make_contour_clip(tmp_path / "c1", frames=2, size=(96, 72), seed=1, clutter="low", distractor=False)
    code, _, err = run(["fit-plate", str(tmp_path)], capsys)
    assert code != 0 and "c1 is not a plate clip (its groundtruth.csv has no plate vertices x0..y3)" in err


# ------------------------------------------------------------------ the fourth sweep (issue 55)


@pytest.mark.parametrize("name, flags, words", [
    ("full_occlusion.txt", "0,0,1,0", "has 4 flags for the 8 rows of the ground truth; the frames past its end"),
    ("out_of_view.txt", "0,1,0,0,0,0,0,0,0,0", "has 10 flags for the 8 rows of the ground truth; its extra flags"),
    ("absence.label", "0\n0\n1\n", "has 3 flags for the 8 rows of the ground truth; the frames past its end"),
], ids=["lasot-occlusion-short", "lasot-out-of-view-long", "got10k-absence-short"])
def test_flag_files_are_checked_against_the_clip(tmp_path, name, flags, words):
    """Occlusion or absence flag files shorter than the clip were accepted without a word."""
    from vistrack.io.clips import GroundTruthWarning, load_clip

    image_folder(tmp_path / "c", 8)
    (tmp_path / "c" / name).write_text(flags)
    with pytest.warns(GroundTruthWarning, match=words):
        clip = load_clip(tmp_path / "c")
    assert clip.truth["excluded"].tolist()[:4] == [v == "1" for v in flags.replace("\n", ",").split(",")[:4]]


def test_webp_frames_are_read(tmp_path, capsys):
    """An OTB folder of .webp frames gave 'holds no video and no images' (OpenCV reads WebP)."""
    (tmp_path / "c" / "img").mkdir(parents=True)
    for i in range(4):
        cv2.imwrite(str(tmp_path / "c" / "img" / f"{i + 1:04d}.webp"), textured(i))
    (tmp_path / "c" / "groundtruth_rect.txt").write_text("41,51,25,19\n" * 4)
    code, _, err = run(["run", tmp_path / "c", "--init-gt", "-n", "20", "-q", "--track", tmp_path / "t.csv"], capsys)
    assert code == 0, err
    assert len(read_rows(tmp_path / "t.csv")) == 4
    (tmp_path / "e").mkdir()
    (tmp_path / "e" / "notes.xyz").write_text("x")
    code, _, err = run(["run", tmp_path / "e", "--init", "1,1,5,5", "-q"], capsys)
    one_error(code, err, f"{tmp_path / 'e'} holds no video and no images (in the folder, img/ or color/: images",
              ".webp", "it holds .xyz files")


def textured(i):
    from fault_helpers import textured_frame

    return textured_frame(i)


def _mp4_clip(path):
    """A small mp4v video with its index at the end (a server without range requests serves it whole)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    wr = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), 25, (W, H))
    for i in range(12):
        wr.write(textured(i))
    wr.release()
    return path


@pytest.mark.parametrize("damage, words", [
    ("cut", "held 3000 bytes of v.mp4, not the"),
    ("changed", "held v.mp4 changed since its download (another SHA-256)"),
    ("folder", "lost v.mp4 (or it is not a file any more)"),
], ids=["cut-short", "bytes-changed", "replaced-by-a-folder"])
def test_a_damaged_cached_copy_is_downloaded_again(tmp_path, serve, monkeypatch, damage, words):
    """A cached download with bytes changed in its middle was used and called 'unchanged on the server'; one
    cut short was refused as 'not a video' on every later run, never fetched again, although its recorded
    length showed it short. Copies are checked by length and SHA-256 before use, and fetched again."""
    import shutil

    monkeypatch.setenv("VISTRACK_CACHE", str(tmp_path / "cache"))
    _mp4_clip(tmp_path / "www" / "v.mp4")
    url = serve(tmp_path / "www") + "/v.mp4"
    args = ["run", url, "--init", "48,51,24,18", "-n", "20", "--track", tmp_path / "t.csv"]
    code, _, err = run(args)
    assert code == 0 and "downloaded" in err, err
    (copy,) = (tmp_path / "cache").rglob("v.mp4")
    data = copy.read_bytes()
    damage_copy(copy, damage)
    code, _, err = run(args)
    assert code == 0, err
    assert f"downloaded {url} again into {copy}: the cached copy {words}" in err, err
    assert copy.read_bytes() == data
    code, _, err = run(args)
    assert code == 0 and "using the cached copy" in err and "as downloaded (its length and SHA-256)" in err, err
    shutil.rmtree(tmp_path / "cache")


@pytest.mark.parametrize("cache", ["read-only", "a-file", "full"])
def test_a_cache_that_cannot_be_written_names_the_cache_and_how_to_move_it(tmp_path, serve, monkeypatch, cache):
    """cache_readonly, cache_is_file and cache_full said 'Operation not permitted: rocache/clips', 'Not a
    directory: ...' and 'No space left on device': none said that the download cache was at fault."""
    import os

    _mp4_clip(tmp_path / "www" / "v.mp4")
    url = serve(tmp_path / "www") + "/v.mp4"
    root = tmp_path / "cache"
    if cache == "a-file":
        root.write_text("not a folder")
    elif cache == "read-only":
        (root / "clips").mkdir(parents=True)
        monkeypatch.setattr(os, "replace", _refuse(os.replace, "clips", 1))  # EPERM (tests may run as root)
    else:
        (root / "clips").mkdir(parents=True)
        monkeypatch.setattr(os, "replace", _refuse(os.replace, "clips", 28))
    monkeypatch.setenv("VISTRACK_CACHE", str(root))
    code, _, err = run(["run", url, "--init", "48,51,24,18", "-n", "20", "-q"])
    one_error(code, err, f"cannot write the download cache {root / 'clips'}",
              "set VISTRACK_CACHE to a writable folder to keep downloads elsewhere")


def _refuse(real, where, errno_):
    """``os.replace`` failing with ``errno_`` for paths under a folder named ``where``."""
    import os

    def replace(src, dst, *a, **kw):
        if f"{os.sep}{where}{os.sep}" in str(dst):
            raise OSError(errno_, os.strerror(errno_), str(dst))
        return real(src, dst, *a, **kw)

    return replace


def test_urls_are_named_as_given_and_never_taken_for_paths(tmp_path, serve):
    """url_range_flaky_server printed the URL with one slash (http:/127...); --init-gt URL said it did not
    exist (a local path with one slash); --out and --track URLs said their folder did not exist; a redirect
    loop gave three lines; an ftp:// URL nobody answers said only 'Connection refused'."""
    import socket

    from fault_helpers import looping_server
    from vistrack.io.video import VideoSource

    _mp4_clip(tmp_path / "www" / "v.mp4")
    from server_helpers import RangeHandler

    url = serve(tmp_path / "www", RangeHandler) + "/v.mp4"
    assert VideoSource(url).shown == url
    v = tmp_path / "v.avi"
    write_video(v, 3)
    for opt in ("--out", "--track", "--results"):
        code, _, err = run(["run", v, "--init", "48,51,24,18", "-q", opt, f"{url}x.mp4"])
        one_error(code, err, f"'{opt}': {url}x.mp4 is a URL; vistrack writes its outputs to local files")
    code, _, err = run(["run", v, "--init-gt", f"{url}.txt", "-q"])
    one_error(code, err, f"--init-gt {url}.txt: a URL; give a local ground-truth file")

    with looping_server() as base:
        loop = f"{base}/v.mp4"
        code, _, err = run(["run", loop, "--init", "1,1,5,5", "-q"])
        one_error(code, err, f"cannot read {loop}: the server redirects it in a loop (HTTP 302")
        assert err.count("\n") == 1
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        closed = s.getsockname()[1]
    code, _, err = run(["run", f"ftp://127.0.0.1:{closed}/v.mp4", "--init", "1,1,5,5", "-q"])
    one_error(code, err, f"cannot read ftp://127.0.0.1:{closed}/v.mp4: connection refused")
