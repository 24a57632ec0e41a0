"""Adding a model is one class and one registry call: a constant-velocity point tracked from
its noisy detected position then runs in ``vistrack.Tracker``, ``vistrack run`` and ``vistrack
eval`` with every filter its protocols allow, and filters it cannot serve say so in one line."""

from __future__ import annotations

import json

import cv2
import numpy as np
import pytest

import vistrack
from cli_helpers import run
from vistrack.models.protocol import VideoModelBase
from vistrack.registry import MODELS, ModelSpec, make_filter, register

H, W = 120, 160
_LOG2PI = np.log(2 * np.pi)


class Point(VideoModelBase):
    """State ``(x, y, vx, vy)``; constant velocity plus noise; ``Y_t`` the brightest pixel."""

    dim = 4

    def __init__(self, frame, box, *, sigma_v=0.5, sigma_obs=1.5):
        x, y, w, h = box
        self.size = np.array([w, h], float)
        self.mean0 = np.array([x + w / 2, y + h / 2, 0.0, 0.0])
        self.std0 = np.array([2.0, 2.0, 2.0, 2.0])
        self.sigma_v, self.sigma_obs = sigma_v, sigma_obs
        self.prior_mean = self.mean0

    def sample_prior(self, n, rng):
        return self.mean0 + self.std0 * rng.standard_normal((n, 4))

    def prior_logpdf(self, states):
        e = (states - self.mean0) / self.std0
        return -0.5 * np.sum(e * e, axis=1) - np.sum(np.log(self.std0)) - 2 * _LOG2PI

    def predict_mean(self, states):
        out = states.copy()
        out[:, :2] += states[:, 2:]
        return out

    def predict(self, states, rng):
        out = self.predict_mean(states)
        out[:, 2:] += self.sigma_v * rng.standard_normal((len(states), 2))
        out[:, :2] += self.sigma_v * rng.standard_normal((len(states), 2))
        return out

    def transition_logpdf(self, new, old):
        e = (new - self.predict_mean(old)) / self.sigma_v
        return -0.5 * np.sum(e * e, axis=1) - 4 * np.log(self.sigma_v) - 2 * _LOG2PI

    def observe(self, maps, particles):
        """The brightest pixel's centre ``(2,)``."""
        y, x = np.unravel_index(np.argmax(maps.gray), maps.shape)
        return np.array([x + 0.5, y + 0.5])

    def loglik(self, obs, states):
        e = (states[:, :2] - obs) / self.sigma_obs
        return -0.5 * np.sum(e * e, axis=1)

    def box(self, states):
        s = np.atleast_2d(states)
        return np.concatenate([s[:, :2] - self.size / 2, np.broadcast_to(self.size, (len(s), 2))], axis=1)

    def outline(self, states):
        x, y, w, h = self.box(states).T
        return np.stack([np.stack([x, y], 1), np.stack([x + w, y], 1), np.stack([x + w, y + h], 1),
                         np.stack([x, y + h], 1)], axis=1)

    def describe(self, state):
        cx, cy = np.ravel(state)[:2]
        return {"cx": cx, "cy": cy, "w": self.size[0], "h": self.size[1], "angle_deg": 0.0, "scale": 1.0}


@pytest.fixture
def point_model():
    register(ModelSpec("point", ("bootstrap", "condensation", "avpf"), "a bright point, constant velocity",
                       from_box=Point))
    yield
    MODELS.pop("point")


def centre(t):
    return 30.0 + 3.0 * t, 40.0 + 1.5 * t


def frames(n=25, seed=0):
    rng = np.random.default_rng(seed)
    out = []
    for t in range(n):
        img = rng.integers(0, 60, (H, W, 3)).astype(np.uint8)
        cx, cy = centre(t)
        img[int(cy), int(cx)] = 255
        out.append(img)
    return out


def start_box():
    return (centre(0)[0] - 5, centre(0)[1] - 5, 10.0, 10.0)


@pytest.mark.parametrize("algo", ["bootstrap", "condensation", "avpf"])
def test_every_allowed_filter_tracks_the_registered_point(point_model, algo):
    fr = frames()
    t = vistrack.Tracker(model="point", algo=algo, particles=200, seed=2)
    t.init(fr[0], start_box())
    err = []
    for k in range(1, len(fr)):
        t.update(fr[k])
        x, y, w, h = t.box_estimate
        err.append(np.hypot(x + w / 2 - centre(k)[0] - 0.5, y + h / 2 - centre(k)[1] - 0.5))
    assert np.max(err) < 3.0, err


@pytest.mark.parametrize("algo, part", [("lis", "lis_proposal"), ("ls-n-ips", "local_search"),
                                        ("lls", "local_coords")])
def test_filters_the_model_cannot_serve_say_so_in_one_line(algo, part):
    with pytest.raises(ValueError, match=f"{algo} needs a model with .*{part}.*Point does not supply"):
        make_filter(algo, Point(frames(1)[0], start_box()))


def _write_clip(folder, fr):
    folder.mkdir()
    wr = cv2.VideoWriter(str(folder / "video.avi"), cv2.VideoWriter_fourcc(*"MJPG"), 25, (W, H))
    for f in fr:
        wr.write(f)
    wr.release()
    rows = [f"{centre(t)[0] - 4.5:.1f},{centre(t)[1] - 4.5:.1f},10,10" for t in range(len(fr))]
    (folder / "groundtruth_rect.txt").write_text("\n".join(rows) + "\n")


@pytest.mark.slow
def test_run_and_eval_take_the_registered_model(point_model, tmp_path, capsys):
    from vistrack.io.clips import read_groundtruth_csv

    clip = tmp_path / "clip"
    _write_clip(clip, frames())
    code, out, err = run(["run", str(clip / "video.avi"), "--model", "point", "--algo", "bootstrap", "--init",
                          ",".join(f"{v:g}" for v in start_box()), "--track", str(tmp_path / "t.csv"), "--seed",
                          "3"], capsys)
    assert code == 0, err
    track = read_groundtruth_csv(tmp_path / "t.csv")
    assert len(track["cx"]) == 25 and np.max(np.abs(track["cx"] - [centre(t)[0] + 0.5 for t in range(25)])) < 3
    code, out, err = run(["eval", str(clip), "--model", "point", "--algos", "bootstrap,avpf", "--particles", "100",
                          "--runs", "1", "--in-process", "--out", str(tmp_path / "ev"), "-q"], capsys)
    assert code == 0, err
    res = json.loads((tmp_path / "ev" / "results.json").read_text())
    rows = res["results"] if isinstance(res, dict) else res
    assert {r["algo"] for r in rows} == {"bootstrap", "avpf"}
    assert all(r["success_auc"] > 0.5 for r in rows)
    code, _, err = run(["run", str(clip / "video.avi"), "--model", "nosuch", "--init", "1,1,5,5"], capsys)
    assert code != 0 and "unknown model 'nosuch'" in err
