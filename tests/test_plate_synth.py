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


def test_plate_likelihood_has_a_narrow_dominant_peak_at_the_plate(road):
    """Fig. 1.6: over a (u, w) grid at the true angle and scale, the maximum of r is at the
    true plate, and poses 15 % of the plate width away are far less likely."""
    from vistrack.features import FeatureMaps
    from vistrack.models.plate import PlateLikelihood

    clip = load_clip(road)
    t = clip.truth
    frames = dict(clip.source)
    lik = PlateLikelihood("jp")
    vis = np.flatnonzero(t["visible"] > 0)
    for k in vis[[len(vis) // 4, len(vis) // 2, 3 * len(vis) // 4]]:
        obs = FeatureMaps(frames[k])
        s, th = t["scale"][k], np.deg2rad(t["angle_deg"][k])
        du, dw = np.meshgrid(np.arange(-40, 41, 1.0), np.arange(-30, 31, 1.0))
        poses = np.stack([t["cx"][k] + du.ravel(), t["cy"][k] + dw.ravel(), np.full(du.size, th),
                          np.full(du.size, s)], axis=1)
        ll = lik.loglik(obs, poses)
        dist = np.hypot(du.ravel(), dw.ravel())
        assert dist[np.argmax(ll)] <= 0.08 * s + 1.5
        assert ll.max() - ll[dist > 0.15 * s].max() > 1.0
