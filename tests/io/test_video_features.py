"""Video I/O and per-frame feature maps: known answers, round trips, clear errors."""

import warnings

import cv2
import numpy as np
import pytest

from path_helpers import REAL
from vistrack.appearance.features import FeatureMaps, box_dog, box_sums
from vistrack.io.video import VideoDecodeWarning, VideoError, VideoWriter, find_groundtruth, open_video, read_rects


def moving_square(i, size=(96, 64)):
    w, h = size
    f = np.full((h, w, 3), 40, np.uint8)
    x = 10 + 2 * i
    f[20:40, x : x + 20] = (200, 180, 160)
    return f


# -- feature maps -------------------------------------------------------------
def test_sobel_of_a_step_edge_is_four_times_the_step():
    g = np.zeros((20, 30), np.uint8)
    g[:, 15:] = 10
    fm = FeatureMaps(g)
    expect = np.zeros((20, 30), np.float32)
    expect[:, 14:16] = 40.0
    assert fm.gx == pytest.approx(expect)
    assert fm.gy == pytest.approx(np.zeros((20, 30)))
    assert fm.mag == pytest.approx(expect)


def test_zero_and_constant_frames_give_zero_maps():
    for value in (0, 77):
        fm = FeatureMaps(np.full((24, 32, 3), value, np.uint8))
        for name in ("gx", "gy", "mag", "dog_small", "dog_large"):
            assert np.abs(getattr(fm, name)).max() == pytest.approx(0.0, abs=1e-3), name


def test_dog_responds_to_a_thin_bright_line():
    g = np.zeros((40, 40), np.float32)
    g[:, 20] = 90.0
    d = box_dog(g, 3, 7)
    assert d[20, 20] == pytest.approx(90 / 3 - 90 / 7, rel=1e-5)
    assert d[20, 20] > 0 and d[20, 30] == pytest.approx(0.0, abs=1e-4)
    with pytest.raises(ValueError):
        box_dog(g, 7, 3)


def test_maps_are_computed_once(monkeypatch):
    fm = FeatureMaps(moving_square(0))
    calls = []
    real = cv2.Sobel
    monkeypatch.setattr(cv2, "Sobel", lambda *a, **k: calls.append(1) or real(*a, **k))
    for _ in range(3):
        fm.gx, fm.mag, fm.integral("abs_gx")
    assert len(calls) == 2  # gx, then gy for the magnitude; never again



def test_smoothed_gradient_keeps_a_ramp_and_evens_out_blurred_edges():
    # Gaussian smoothing leaves a linear ramp alone: Sobel of a·x is 8a inside
    ramp = np.tile(np.arange(60, dtype=np.float32) * 2.0, (40, 1))
    fm = FeatureMaps(ramp)
    g, _ = fm.gradient(1.5)
    assert g[10:30, 10:50, 0] == pytest.approx(16.0, abs=1e-3)
    assert g[10:30, 10:50, 1] == pytest.approx(0.0, abs=1e-3)
    assert fm.gradient(0)[0] is fm.gxy and fm.gradient(1.5)[0] is g  # raw maps; cached per sigma

    # a step edge blurred over 5 px (motion blur) loses less of its peak after smoothing
    sharp = np.zeros((20, 60), np.float32)
    sharp[:, 30:] = 100.0
    blurred = cv2.blur(sharp, (5, 1), borderType=cv2.BORDER_REFLECT)

    def ratio(sigma):
        peak = [FeatureMaps(im).gradient(sigma)[0][10, :, 0].max() for im in (blurred, sharp)]
        return peak[0] / peak[1]

    assert ratio(0) == pytest.approx(0.4, abs=1e-4)  # a 2-px difference: 40 of the ramp vs the whole step of 100
    assert ratio(1.0) == pytest.approx(0.6, abs=0.02)  # (a pure Gaussian derivative: 1/sqrt(1 + 25/12) = 0.57)
    assert ratio(2.0) > ratio(1.0) + 0.15  # ... wider smoothing, evener still

    # sampled at pixel centres it is the map itself
    y, x = np.mgrid[5:8, 20:24].astype(np.float32)
    assert fm.sample_gradient(x, y, 1.5) == pytest.approx(g[5:8, 20:24])

def test_box_sums_from_integral_images_match_direct_sums(rng):
    """:func:`~vistrack.appearance.features.box_sums` (what the box model's colour maps read) against direct
    sums: boxes clipped to the map, an empty box summing to 0."""
    fm = FeatureMaps(rng.integers(0, 255, (50, 70, 3)).astype(np.uint8))
    ii = fm.integral("abs_gx")
    x0, y0 = rng.integers(0, 30, 20), rng.integers(0, 20, 20)
    x1, y1 = x0 + rng.integers(1, 50, 20), y0 + rng.integers(1, 40, 20)
    got = box_sums(ii, x0, y0, x1, y1)
    direct = [np.abs(fm.gx[b:d, a:c]).sum() for a, b, c, d in zip(x0, y0, x1, y1)]
    assert got == pytest.approx(direct, rel=1e-5)
    assert box_sums(ii, 5, 5, 5, 9) == 0.0


# -- video --------------------------------------------------------------------
def test_write_then_read_round_trip(tmp_path):
    path = tmp_path / "clip.mp4"
    with VideoWriter(path, 25, (96, 64)) as w:
        for i in range(30):
            w.write(moving_square(i))
    src = open_video(path)
    container_rate = src.fps  # frames per second written in the container header
    assert src.frame_count == 30 and src.size == (96, 64)
    assert container_rate == pytest.approx(25)
    frames = list(src)
    assert [i for i, _ in frames] == list(range(30))
    assert np.abs(frames[7][1].astype(int) - moving_square(7)).mean() < 8
    # a clip folder with video.mp4 opens the same way
    path.rename(tmp_path / "video.mp4")
    assert open_video(tmp_path).frame_count == 30


def test_image_folder_in_otb_layout(tmp_path):
    (tmp_path / "img").mkdir()
    for i in range(5):
        cv2.imwrite(str(tmp_path / "img" / f"{i + 1:04d}.png"), moving_square(i))
    (tmp_path / "groundtruth_rect.txt").write_text("10,20,20,20\n12\t20\t20\t20\n")
    src = open_video(tmp_path)
    assert src.frame_count == 5 and src.size == (96, 64)
    assert all(np.array_equal(f, moving_square(i)) for i, f in src)
    gt = read_rects(find_groundtruth(tmp_path))
    assert gt.tolist() == [[10, 20, 20, 20], [12, 20, 20, 20]]


@pytest.mark.parametrize(
    "kind, message",
    [
        ("missing", "does not exist"),
        ("empty", "is empty"),
        ("text", "not a video"),
        ("folder", "holds no video and no images"),
    ],
)
def test_bad_sources_raise_one_clear_error(tmp_path, kind, message):
    path = tmp_path / ("nothing" if kind == "folder" else f"{kind}.mp4")
    if kind == "empty":
        path.write_bytes(b"")
    elif kind == "text":
        path.write_text("not a video at all\n" * 50)
    elif kind == "folder":
        path.mkdir()
    with pytest.raises(VideoError, match=message):
        open_video(path)


def test_bad_rect_file(tmp_path):
    p = tmp_path / "gt.txt"
    p.write_text("1,2,3,4\n1,2,x,4\n")
    with pytest.raises(VideoError, match="line 2"):
        read_rects(p)


def test_truncated_stream_warns_and_keeps_frames(tmp_path):
    path = tmp_path / "clip.avi"
    w = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 25, (96, 64))
    for i in range(40):
        w.write(moving_square(i))
    w.release()
    data = path.read_bytes()
    path.write_bytes(data[: len(data) * 6 // 10])
    try:
        src = open_video(path)
    except VideoError:
        pytest.skip("this OpenCV build cannot open a truncated AVI at all")
    if src.frame_count is None or src.frame_count < 40:
        pytest.skip("container does not announce the frame count after truncation")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        n = sum(1 for _ in src)
    assert 0 < n < 40
    assert any(issubclass(c.category, VideoDecodeWarning) for c in caught)


# -- real clips (skipped when ../shared/data is absent) ------------------------
@pytest.mark.skipif(not (REAL / "car4_otb_first100").is_dir(), reason="shared real data not present")
def test_real_otb_folder_and_video():
    src = open_video(REAL / "car4_otb_first100")
    assert src.frame_count == 100 and src.size == (360, 240)
    assert read_rects(find_groundtruth(REAL / "car4_otb_first100")).shape == (100, 4)
    plate = open_video(REAL / "plate_in_polo_dashcam" / "plate_in_polo_dashcam.mp4")
    assert plate.size == (552, 530) and plate.frame_count == 138


@pytest.mark.parametrize("size", [(96, 64), (97, 63)], ids=["even", "odd"])
def test_annotated_video_is_h264_with_every_frame(tmp_path, size):
    """The ``auto`` writer: H.264 (browsers, Jupyter) with the clip's frame count, readable by cv2;
    odd sizes padded by a pixel. Skipped where PyAV cannot encode H.264."""
    from vistrack.io.video import VideoWriter

    pytest.importorskip("av")
    w = VideoWriter(tmp_path / "a.mp4", 25, size, codec="auto")
    if w.codec != "h264":
        pytest.skip(w.note)
    for i in range(12):
        w.write(np.full((size[1], size[0], 3), 20 * i, np.uint8))
    w.close()
    cap = cv2.VideoCapture(str(tmp_path / "a.mp4"))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == 12
    assert int(cap.get(cv2.CAP_PROP_FOURCC)).to_bytes(4, "little") in (b"h264", b"avc1")
    ok, f = cap.read()
    assert ok and abs(f.shape[1] - size[0]) <= 1 and abs(f.shape[0] - size[1]) <= 1


def test_annotated_video_falls_back_to_mp4v_with_a_note(tmp_path, monkeypatch):
    import builtins

    from vistrack.io.video import VideoWriter

    real = builtins.__import__

    def no_av(name, *a, **k):
        if name == "av":
            raise ImportError("No module named 'av'")
        return real(name, *a, **k)

    monkeypatch.setattr(builtins, "__import__", no_av)
    w = VideoWriter(tmp_path / "a.mp4", 25, (96, 64), codec="auto")
    assert w.codec == "mp4v" and "pip install av" in w.note
    for i in range(5):
        w.write(np.zeros((64, 96, 3), np.uint8))
    w.close()
    assert int(cv2.VideoCapture(str(tmp_path / "a.mp4")).get(cv2.CAP_PROP_FRAME_COUNT)) == 5


def _atoms(path):
    """Top-level MP4 box types in file order."""
    data, out, i = path.read_bytes(), [], 0
    while i + 8 <= len(data):
        size = int.from_bytes(data[i:i + 4], "big")
        out.append(data[i + 4:i + 8].decode("latin-1"))
        if size == 1:
            size = int.from_bytes(data[i + 8:i + 16], "big")
        if size < 8:
            break
        i += size
    return out


def test_the_annotated_video_s_codec_fits_its_container(tmp_path):
    """--out picks a codec its container holds: H.264 in .mp4 with the index first (faststart),
    H.264 in .mkv, Motion JPEG in .avi (with a note); another name is one clear error."""
    pytest.importorskip("av")
    frame = np.zeros((64, 96, 3), np.uint8)
    for name in ("a.mp4", "a.mkv", "a.avi"):
        with VideoWriter(tmp_path / name, 25, (96, 64), codec="auto") as w:
            for k in range(5):
                w.write(frame + k)
        cap = cv2.VideoCapture(str(tmp_path / name))
        fourcc = int(cap.get(cv2.CAP_PROP_FOURCC)).to_bytes(4, "little").decode("latin-1").lower()
        n = 0
        while cap.read()[0]:
            n += 1
        cap.release()
        assert n == 5
        if name == "a.avi":
            assert w.codec == "mjpg" and fourcc == "mjpg" and "Motion JPEG" in w.note
        else:
            assert w.codec == "h264" and fourcc in ("avc1", "h264") and w.note is None
    atoms = _atoms(tmp_path / "a.mp4")
    assert atoms.index("moov") < atoms.index("mdat"), atoms
    with pytest.raises(VideoError, match=r"give a file name ending in \.mp4"):
        VideoWriter(tmp_path / "a.webm", 25, (96, 64), codec="auto")
