"""`vistrack synth contour --color`, `run --algo rb-ss-hs-sir|sir` and `reproduce hs-sir`."""

import csv
import json

import numpy as np
import pytest

from cli_helpers import run


@pytest.fixture(scope="module")
def colour_clip(tmp_path_factory):
    from vistrack.data_synth.contour_clip import make_contour_clip

    out = tmp_path_factory.mktemp("hs") / "clip"
    make_contour_clip(out, frames=12, size=(120, 90), seed=3, color=True)
    return out


def track_rows(path):
    with open(path, newline="") as f:
        return [{k: v for k, v in r.items() if k != "ms"} for r in csv.DictReader(f)]


def test_synth_color_gives_a_coloured_object_and_distractor(tmp_path, capsys):
    import cv2

    code, _, err = run(["synth", "contour", "--out", str(tmp_path / "c"), "--color", "--frames", "2", "--size",
                        "96x72", "-q"], capsys)
    assert code == 0, err
    meta = json.loads((tmp_path / "c" / "meta.json").read_text())
    assert meta["color"] is True and meta["distractor"] is not None
    cap = cv2.VideoCapture(str(tmp_path / "c" / "video.mp4"))
    ok, frame = cap.read()
    hsv = cv2.cvtColor(frame, cv2.COLOR_BGR2HSV)
    d = meta["distractor"]
    assert hsv[int(d["cy"]), int(d["cx"]), 1] > 120  # saturated at the distractor's centre


def test_run_history_sampling_same_seed_same_track(colour_clip, tmp_path, capsys):
    tracks = []
    for k in range(2):
        path = tmp_path / f"t{k}.csv"
        code, out, err = run(["run", str(colour_clip), "--algo", "rb-ss-hs-sir", "-n", "60", "--init-gt", "--seed", "4",
                              "--track", str(path), "-q"], capsys)
        assert code == 0, err
        tracks.append(track_rows(path))
    assert tracks[0] == tracks[1] and len(tracks[0]) == 12
    code, _, err = run(["run", str(colour_clip), "--algo", "sir", "-n", "60", "--init-gt", "--max-frames", "3", "-q"],
                       capsys)
    assert code == 0, err


def test_run_history_sampling_on_a_model_without_the_split(colour_clip, capsys):
    code, _, err = run(["run", str(colour_clip), "--model", "plate", "--algo", "rb-ss-hs-sir"], capsys)
    assert code != 0
    assert err.strip().splitlines()[-1] == ("Error: --algo rb-ss-hs-sir does not run on the plate model; choose from "
                                            "lis, bootstrap, condensation, lls, avpf")


@pytest.mark.slow
def test_reproduce_hs_sir_json_and_plots(tmp_path, capsys):
    import matplotlib.image as mpimg

    js = tmp_path / "r.json"
    code, out, err = run(["reproduce", "hs-sir", "--clips", str(tmp_path / "clips"), "--make", "1", "--frames", "8",
                          "--size", "96x72", "--runs", "2", "--algos", "basic-sir:40,rb-ss-hs-sir:15,hs-sir:15",
                          "--in-process", "--workers", "1", "--out", str(tmp_path / "res"), "--json", str(js),
                          "--plots", str(tmp_path / "p"), "-q"], capsys)
    assert code == 0, err
    assert out.splitlines()[0] == "1 clips x 2 runs"
    assert out.splitlines()[1].split()[:5] == ["algo", "N", "P(lost)", "final", "P(lost)"]
    data = json.loads(js.read_text())
    assert [(r["algo"], r["particles"]) for r in data["results"]] == [("basic-sir", 40), ("rb-ss-hs-sir", 15),
                                                                      ("hs-sir", 15)]
    assert json.loads((tmp_path / "clips" / "contour-color-01" / "meta.json").read_text())["color"] is True
    for r in data["results"]:
        assert len(r["p_lost_per_frame"]) == 8 and r["runs"] == 2 and r["frames_per_s"] > 0
    for name in ("p_lost_vs_frame.png", "error_vs_frame.png"):
        assert mpimg.imread(tmp_path / "p" / name).ndim == 3


def test_equal_time_keeps_the_first_entry(colour_clip):
    from vistrack.reproduce.history_sampling import equal_time_entries

    entries, times = equal_time_entries(colour_clip, [("basic-sir", 60), ("rb-ss-hs-sir", 20)], frames=4)
    assert entries[0] == ("basic-sir", 60) and entries[1][0] == "rb-ss-hs-sir" and entries[1][1] >= 1
    assert set(times) == {"basic-sir:60", "rb-ss-hs-sir:20"} and all(np.isfinite(list(times.values())))


def test_likelihood_params_parse_and_reject():
    from vistrack.reproduce.history_sampling import likelihood_params

    assert likelihood_params("") == {}
    assert likelihood_params("sigma_edge=4, q_miss=0.5,measure_per_segment=1") == {
        "sigma_edge": 4.0, "q_miss": 0.5, "measure_per_segment": 1}
    with pytest.raises(ValueError, match="^unknown likelihood parameter 'sigma'; choose from sigma_edge, q_miss"):
        likelihood_params("sigma=4")
    with pytest.raises(ValueError, match="^measure_per_segment needs an integer, got '1.5'$"):
        likelihood_params("measure_per_segment=1.5")
    with pytest.raises(ValueError, match="^q_miss must be positive, got 0$"):
        likelihood_params("q_miss=0")


def test_likelihood_reaches_every_task_model(colour_clip, monkeypatch, tmp_path):
    import vistrack.evaluation.experiment as ev
    from vistrack.reproduce.history_sampling import HSConfig, hs_tasks

    assert all("model_params" not in t for t in hs_tasks(HSConfig(clips=[colour_clip], runs=1)))
    tasks = hs_tasks(HSConfig(clips=[colour_clip], runs=1, likelihood={"sigma_edge": 3.0}))
    assert [t["model_params"] for t in tasks] == [{"sigma_edge": 3.0}] * 2
    seen = []

    def spy(name, clip, **kw):
        seen.append(kw)
        raise KeyboardInterrupt  # stop before tracking

    monkeypatch.setattr(ev, "build_model", spy)
    with pytest.raises(KeyboardInterrupt):
        ev.run_task(tasks[0], tmp_path)
    assert seen == [{"init_gt": "", "sigma_edge": 3.0}]


def test_reproduce_hs_sir_rejects_an_unknown_likelihood_key(tmp_path, capsys):
    code, _, err = run(["reproduce", "hs-sir", "--clips", str(tmp_path), "--likelihood", "sigma=4"], capsys)
    assert code == 2
    assert err.strip().splitlines()[-1] == ("Error: Invalid value for '--likelihood': unknown likelihood parameter "
                                            "'sigma'; choose from sigma_edge, q_miss, clutter_density, "
                                            "measure_per_segment, edge_threshold")
