"""`vistrack run` on a URL and a camera (issue 37, item 5): an mp4 served over HTTP on 127.0.0.1 by
`python -m http.server`, tracked like the file with --max-frames; a camera index that is not there is
one line. What URLs do besides (range requests, the cache, errors): tests/io/test_urls.py."""

import socket
import subprocess
import sys

import numpy as np
import pytest

from cli_helpers import run
from process_helpers import listening, wait_until
from vistrack.io.clips import read_groundtruth_csv
from vistrack.io.video import VideoWriter, is_stream


def test_what_is_a_stream(tmp_path, monkeypatch):
    """A camera or a live stream, read as it comes; a video's URL is a file (issue 46: read with seeking
    or downloaded), and a file or folder named like a camera wins over it."""
    monkeypatch.chdir(tmp_path)
    assert is_stream("0") and is_stream("rtsp://cam/live") and is_stream("https://h/live/index.m3u8?t=1")
    assert not is_stream("http://h:8/v.mp4?x=1") and not is_stream("http://h:8/girl_otb/")
    assert not is_stream("video.mp4") and not is_stream("clips/0a")
    (tmp_path / "0").mkdir()
    assert not is_stream("0")


@pytest.fixture
def served(tmp_path):
    with VideoWriter(tmp_path / "v.mp4", 25, (96, 72), codec="h264") as w:
        for t in range(30):
            img = np.full((72, 96, 3), 40, np.uint8)
            img[20:40, 20 + t:40 + t] = (40, 60, 220)
            w.write(img)
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    server = subprocess.Popen([sys.executable, "-m", "http.server", str(port), "--bind", "127.0.0.1"], cwd=tmp_path,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wait_until(lambda: listening(port), "the HTTP server listening", proc=server)
    yield f"http://127.0.0.1:{port}/v.mp4", tmp_path / "v.mp4"
    server.kill()
    server.wait()


def test_run_tracks_a_stream_as_it_tracks_the_file(served, tmp_path, capsys):
    url, local = served
    tracks = []
    for src, name in ((url, "s.csv"), (str(local), "f.csv")):
        code, _, err = run(["run", src, "--init", "20,20,20,20", "--max-frames", "12", "--seed", "2", "--track",
                            str(tmp_path / name), "-q"], capsys)
        assert code == 0, err
        tracks.append(read_groundtruth_csv(tmp_path / name))
    assert len(tracks[0]["cx"]) == 12
    np.testing.assert_allclose(tracks[0]["cx"], tracks[1]["cx"])


def test_a_camera_that_is_not_there_is_one_line(capsys):
    code, _, err = run(["run", "57", "--init", "1,1,5,5", "--max-frames", "3"], capsys)
    assert code != 0 and err.count("\n") == 1 and "no camera with that index" in err
