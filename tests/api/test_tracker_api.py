"""vistrack.Tracker in the shape of OpenCV's trackers (issue 37, item 5) and over TraX (item 6)."""

import shutil
import subprocess
import sys

import cv2
import numpy as np
import pytest

import vistrack
from path_helpers import REAL


def frames(n=6):
    out = []
    for k in range(n):
        f = np.full((90, 120, 3), 50, np.uint8)
        cv2.rectangle(f, (30 + 2 * k, 30), (54 + 2 * k, 54), (40, 60, 230), -1)
        out.append(f)
    return out


def test_box_is_integers_that_opencv_draws_and_the_estimate_keeps_the_floats():
    fr = frames()
    t = vistrack.Tracker(seed=1)
    t.init(fr[0], (30.4, 30.2, 25.3, 24.9))
    for f in fr[1:]:
        ok, box = t.update(f)
    assert all(type(v) is int for v in box) and box == t.box
    assert all(type(v) is float for v in t.box_estimate)
    assert np.allclose(box, t.box_estimate, atol=0.5)
    cv2.rectangle(fr[-1], t.box, (0, 255, 0), 1)  # raised on float boxes


def test_reprs_are_one_short_line():
    fr = frames()
    t = vistrack.Tracker(seed=1)
    assert repr(t) == "Tracker(model='box', algo='lis', particles=100, seed=1; not started)"
    t.init(fr[0], (30, 30, 25, 25))
    t.update(fr[1])
    for text in (repr(t), repr(t.result)):
        assert "\n" not in text and len(text) < 200, text
    assert repr(t.result).startswith("FrameResult(index=1, estimate=[")


def _trax_boxes(clip_images, box, seed, n_frames):
    trax = pytest.importorskip("trax", reason="vot-trax is not installed")
    from trax.client import Client
    from trax.image import FileImage
    from trax.region import Rectangle

    proc = subprocess.Popen([sys.executable, "-m", "vistrack.api.trax_server", "--seed", str(seed)],
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE)
    try:
        log = []  # vot-trax 4 needs a logger
        client = Client((proc.stdin.fileno(), proc.stdout.fileno()), timeout=120, log=log.append)
        assert client.tracker_name == "vistrack"
        out = []
        objs, _ = client.initialize({"color": FileImage.create(str(clip_images[0]))},
                                    [(Rectangle.create(*box), {})], {})
        out.append(objs[0][0].bounds())
        for p in clip_images[1:n_frames]:
            objs, _ = client.frame({"color": FileImage.create(str(p))}, {}, [])
            out.append(objs[0][0].bounds())
        client.quit()
        del trax
        return np.array(out)
    finally:
        proc.stdin.close()
        proc.wait(timeout=30)


@pytest.mark.slow
@pytest.mark.skipif(not (REAL / "car4_otb_first100" / "img").is_dir(), reason="shared real clips absent")
def test_trax_client_gets_the_boxes_run_writes(tmp_path):
    """vot-trax's own client drives `python -m vistrack.api.trax_server` over a real clip's frames; the boxes it
    receives are those of `vistrack run` on the same frames from the same box and seed."""
    from vistrack.cli import main
    from vistrack.io.clips import read_groundtruth_csv

    images = sorted((REAL / "car4_otb_first100" / "img").glob("*.jpg"))[:12]
    clip = tmp_path / "img"
    clip.mkdir()
    for p in images:
        shutil.copy(p, clip / p.name)
    box = (69.0, 49.0, 107.0, 87.0)
    got = _trax_boxes(sorted(clip.iterdir()), box, 5, len(images))
    with pytest.raises(SystemExit) as e:
        main(["run", str(clip), "--init", ",".join(f"{v:g}" for v in box), "--seed", "5", "--track",
              str(tmp_path / "t.csv"), "-q"])
    assert e.value.code == 0
    t = read_groundtruth_csv(tmp_path / "t.csv")
    want = np.column_stack([t["cx"] - t["w"] / 2, t["cy"] - t["h"] / 2, t["w"], t["h"]])
    assert len(got) == len(want) == len(images)
    np.testing.assert_allclose(got, want, atol=2e-3)  # TraX sends float32
