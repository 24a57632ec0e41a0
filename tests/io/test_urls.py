"""Any URL a user gives plays (issue 46, item 3; issue 47's url_stale and wording cases): a video over
HTTP is read by FFmpeg with range requests where the server takes them, else downloaded into a cache
kept by the URL and the server's validators, which are checked again on every use (a changed file is
downloaded again; run and eval's report say when a cached copy was used); the track is the local
file's; a local path wins over a camera index; errors name the URL and what failed."""

import os
import re
import socket

import cv2
import numpy as np
import pytest

from cli_helpers import run
from server_helpers import RangeHandler
from vistrack.io.clips import read_groundtruth_csv


@pytest.fixture(autouse=True)
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("VISTRACK_CACHE", str(tmp_path / "cache"))
    return tmp_path / "cache"


def index_last_mp4(path, shift=0, frames=30):
    """An mp4 with its index (``moov``) at the end, as ``hand_vot2013.mp4``: OpenCV's mp4v writer."""
    path.parent.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(shift)
    bg = cv2.GaussianBlur(rng.integers(30, 200, (72, 96, 3)).astype(np.uint8), (0, 0), 2)
    wr = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), 25, (96, 72))
    for t in range(frames):
        img = bg.copy()
        img[20 + shift:40 + shift, 20 + t:40 + t] = (40, 60, 220)
        wr.write(np.clip(img + rng.normal(0, 20, img.shape), 0, 255).astype(np.uint8))  # grain: a larger file
    wr.release()
    data = path.read_bytes()
    assert data.index(b"moov") > data.index(b"mdat")


def track(src, tmp_path, name, *extra):
    out = tmp_path / name
    code, _, err = run(["run", src, "--init", "20,20,20,20", "-n", "60", "--seed", "2", "--track", out, *extra])
    assert code == 0, err
    t = read_groundtruth_csv(out)
    return np.column_stack([t["cx"], t["cy"], t["w"], t["h"]]), err


@pytest.mark.slow
def test_a_server_without_range_requests_downloads_once_and_again_when_the_file_changed(serve, tmp_path, cache):
    video = tmp_path / "served" / "v.mp4"
    index_last_mp4(video)
    url = serve(tmp_path / "served") + "/v.mp4"
    local, _ = track(video, tmp_path, "local.csv")
    first, err = track(url, tmp_path, "first.csv")
    assert f"downloaded {url} into the cache" in err and "Last-Modified" in err
    np.testing.assert_array_equal(first, local)
    again, err = track(url, tmp_path, "again.csv")
    assert f"{url}: using the cached copy" in err and "unchanged on the server" in err
    np.testing.assert_array_equal(again, local)
    index_last_mp4(video, shift=10)  # the file changes on the server (its time too: a second's resolution)
    os.utime(video, (video.stat().st_atime, video.stat().st_mtime + 10))
    changed_local, _ = track(video, tmp_path, "changed-local.csv")
    changed, err = track(url, tmp_path, "changed.csv")
    assert f"downloaded {url} into the cache" in err
    np.testing.assert_array_equal(changed, changed_local)
    assert np.abs(changed - local).max() > 5  # the new file's track, not the old copy's
    assert len([p for p in cache.rglob("v.mp4")]) == 1  # the old copy is gone


def test_a_server_with_range_requests_is_read_with_seeking(serve, tmp_path, cache):
    video = tmp_path / "served" / "v.mp4"
    index_last_mp4(video)
    RangeHandler.starts = []
    url = serve(tmp_path / "served", RangeHandler) + "/v.mp4"
    got, err = track(url, tmp_path, "ranged.csv", "--max-frames", "12")
    assert f"reading {url} from the server (it takes range requests" in err
    np.testing.assert_array_equal(got, track(video, tmp_path, "local.csv", "--max-frames", "12")[0])
    assert any(s > 0 for s in RangeHandler.starts)  # FFmpeg sought (the index is at the end)
    assert not cache.exists() or not any(cache.rglob("v.mp4"))  # nothing downloaded


def test_url_errors_name_the_url_and_what_failed(serve, tmp_path):
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        closed = s.getsockname()[1]  # nothing listens there once the socket is closed
    (tmp_path / "served").mkdir()
    (tmp_path / "served" / "notes.mp4").write_text("not a video\n" * 100)
    base = serve(tmp_path / "served")
    cases = [
        (f"http://127.0.0.1:{closed}/v.mp4",
         f"Error: cannot read http://127.0.0.1:{closed}/v.mp4: connection refused (no server listening there)"),
        (f"{base}/missing.mp4", f"Error: cannot read {base}/missing.mp4: the server answered HTTP 404 File not found"),
        (f"{base}/notes.mp4", f"Error: {base}/notes.mp4 is not a video (downloaded to "),
    ]
    for url, message in cases:
        code, _, err = run(["run", url, "--init", "1,1,5,5", "-q"])
        assert code != 0 and err.startswith(message) and err.count("\n") == 1, err


def test_a_local_path_wins_over_a_camera_index(tmp_path, monkeypatch):
    index_last_mp4(tmp_path / "0.mp4")
    os.rename(tmp_path / "0.mp4", tmp_path / "0")
    monkeypatch.chdir(tmp_path)
    code, _, err = run(["run", "0", "--init", "20,20,20,20", "-n", "30", "--track", "t.csv"])
    assert code == 0, err
    assert len(read_groundtruth_csv(tmp_path / "t.csv")["cx"]) == 30


@pytest.mark.slow
def test_eval_of_a_url_clip_checks_the_server_every_time(serve, tmp_path):
    """issue 47's url_stale: the ground truth changed on the server; eval reads the new one (the scores
    of the changed copy read locally) and its report says when a cached copy was used."""
    import json

    from clip_helpers import square_clip

    served = tmp_path / "served"
    square_clip(served / "sq", 10)
    url = serve(served) + "/sq/"
    grid = ["--algos", "lis", "--particles", "30", "--runs", "2", "--in-process", "--workers", "1", "-q"]

    def auc(clip, out):
        code, _, err = run(["eval", clip, *grid, "--out", tmp_path / out])
        assert code == 0, err
        return json.loads((tmp_path / out / "results.json").read_text())["results"][0]["success_auc"], \
            (tmp_path / out / "report.md").read_text()

    first, report = auc(url, "e1")
    said = re.search(rf"read as the server had them: {re.escape(url)} \((2 files, .*?)\): (\d) of 2 task", report)
    assert said, report
    # in-process workers share the client's cache: the client fetched the clip when it found it
    assert auc(url, "e2")[1].count("2 of 2 task(s) used a cached copy checked against the server") == 1
    gt = served / "sq" / "groundtruth_rect.txt"
    gt.write_text("20,20,20,20\n" + "70,45,20,20\n" * 9)  # the true boxes moved away from the square
    os.utime(gt, (gt.stat().st_atime, gt.stat().st_mtime + 10))  # Last-Modified has a second's resolution
    changed, report = auc(url, "e3")
    again = re.search(rf"read as the server had them: {re.escape(url)} \((2 files, .*?)\): ", report)
    assert again and again[1] != said[1], report  # the new version was read, not the cached copy
    assert changed == auc(served / "sq", "e4")[0] and changed < first - 0.2


def test_an_fsspec_url_is_fetched_and_checked_again_on_every_use(tmp_path):
    """Any fsspec filesystem (here ``memory://``): the clip folder is copied into the cache, used from
    there while its files' validators stay, and copied again once one changed."""
    import fsspec

    from clip_helpers import square_clip

    square_clip(tmp_path / "sq", 6)
    fs = fsspec.filesystem("memory")
    for f in (tmp_path / "sq").iterdir():
        fs.pipe(f"/suite46/sq/{f.name}", f.read_bytes())
    url = "memory://suite46/sq"
    said = []
    for k in range(3):
        if k == 2:  # a changed ground truth (another length) on the "server"
            fs.pipe("/suite46/sq/groundtruth_rect.txt", b"21,20,20,20\n" * 6)
        code, _, err = run(["run", url, "--init-gt", "-n", "30", "--track", tmp_path / f"t{k}.csv"])
        assert code == 0, err
        said.append(next(line for line in err.replace("\r", "\n").splitlines()
                         if line.startswith((f"downloaded {url}", f"{url}:"))))
    assert said[0].startswith(f"downloaded {url} into the cache") and "2 files" in said[0]
    assert said[1].startswith(f"{url}: using the cached copy")
    assert said[2].startswith(f"downloaded {url} into the cache")
    fs.rm("/suite46", recursive=True)
