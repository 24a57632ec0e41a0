"""Synthetic road clips (issue 6 groundwork): ground truth is where the plate is."""

import numpy as np
import pytest

from vistrack.clips import load_clip
from vistrack.cli import main
from vistrack.models.plate_layout import LAYOUTS, plate_vertices


@pytest.fixture(scope="module")
def road(tmp_path_factory):
    out = tmp_path_factory.mktemp("road")
    with pytest.raises(SystemExit) as e:
        main(["synth", "plate", "--out", str(out), "--frames", "60", "--size", "320x240", "--cars", "2",
              "--seed", "3", "-q"])
    assert e.value.code == 0
    return out


def test_plate_truth_matches_the_rendered_plate(road):
    clip = load_clip(road)
    t = clip.truth
    assert clip.meta["model"] == "plate" and len(t["frame"]) == 60
    vis = np.flatnonzero(t["visible"] > 0)
    assert 10 < len(vis) < 60  # plates in view, and stretches without one
    assert np.all(np.isnan(t["cx"][t["visible"] == 0]))
    frames = dict(clip.source)
    lay = LAYOUTS["jp"]
    for k in vis[:: max(1, len(vis) // 5)]:
        pose = np.array([t["cx"][k], t["cy"][k], np.deg2rad(t["angle_deg"][k]), t["scale"][k]])
        v = plate_vertices(pose, lay.aspect)[0]
        np.testing.assert_allclose(v[:, 0], [t[f"x{i}"][k] for i in range(4)], atol=2e-3)
        # the white plate: bright inside (between the character rows), darker around
        gray = frames[k].mean(axis=2)
        inner = gray[int(pose[1] - 0.3 * pose[3] / lay.aspect), int(pose[0] - 0.3 * pose[3])]
        assert inner > 150


def test_synth_plate_bad_size(tmp_path, capsys):
    with pytest.raises(SystemExit) as e:
        main(["synth", "plate", "--out", str(tmp_path / "p"), "--size", "100x80"])
    assert e.value.code != 0 and "too small" in capsys.readouterr().err
