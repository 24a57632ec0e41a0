"""Several plates at once (issue 25 item 4): the overlap clips' per-plate ground truth, the
multi-plate model, the track CSV with ids, the CLEAR-MOT / identity scores, bad input."""

import csv

import numpy as np
import pytest

from cli_helpers import run
from vistrack.core.particles import ParticleSet
from vistrack.io.clips import load_clip, read_groundtruth_csv
from vistrack.models.plate.layout import plate_vertices
from vistrack.scoring.mot import FrameObjects, Identities, clear_mot, objects_by_frame

OBJECT_HEADER = "frame,visible,id,cx,cy,w,h,angle_deg,scale,x0,y0,x1,y1,x2,y2,x3,y3,hidden"
TRACK_HEADER = "frame,visible,id,cx,cy,w,h,angle_deg,scale,x0,y0,x1,y1,x2,y2,x3,y3,ess,ms,lost_reason"


@pytest.fixture(scope="module")
def road(synth_clip):
    return synth_clip("plate", frames=60, size=(320, 240), seed=4, cars=6, overlap=True)


@pytest.mark.slow
def test_overlap_objects_csv_format(road):
    """objects.csv: the exact header; every frame has a row; a frame without a plate has exactly one row
    ``t,0,-1,,...`` (empty geometry cells); plates in view have integer ids >= 0, at most three per frame, in
    order of id, and groundtruth.csv's row is the largest of them."""
    lines = (road / "objects.csv").read_text().splitlines()
    assert lines[0] == OBJECT_HEADER
    rows = [r.split(",") for r in lines[1:]]
    frames = [int(r[0]) for r in rows]
    assert sorted(set(frames)) == list(range(60)) and frames == sorted(frames)
    empty = [r for r in rows if r[1] == "0"]
    assert empty and all(r[2] == "-1" and set(r[3:]) == {""} and frames.count(int(r[0])) == 1 for r in empty)
    cols = read_groundtruth_csv(road / "objects.csv")
    gt = load_clip(road).truth
    counts = np.bincount(cols["frame"][cols["visible"] > 0].astype(int), minlength=60)
    assert counts.max() <= 3 and counts.max() >= 2  # several plates at once, never more than three
    for t in range(60):
        sel = (cols["frame"] == t) & (cols["visible"] > 0)
        ids = cols["id"][sel]
        assert np.all(ids >= 0) and np.all(np.diff(ids) > 0) and np.all(ids == np.round(ids))
        assert np.all(cols["hidden"][sel] <= 0.1)
        if sel.any():
            k = np.flatnonzero(sel)[np.argmax(cols["scale"][sel])]
            assert gt["id"][t] == cols["id"][k] and gt["cx"][t] == pytest.approx(cols["cx"][k], abs=1e-3)
        else:
            assert gt["visible"][t] == 0
    meta = load_clip(road).meta
    assert meta["overlap"] is True and meta["max_in_view"] == 3


def _plate(cx, cy, s=60.0):
    return plate_vertices(np.array([cx, cy, 0.0, s]), 2.0)[0]


def _frame(*objs):
    if not objs:
        return FrameObjects(np.zeros(0, int), np.zeros((0, 4, 2)), np.zeros(0))
    return FrameObjects(np.array([o[0] for o in objs]), np.stack([_plate(*o[1:]) for o in objs]),
                        np.full(len(objs), 60.0))


def test_mota_idf1_on_a_hand_made_case():
    """Two plates, four frames. Frame 0: both found (ids 10, 11); frame 1: plate A found, plate B
    missed and a report far from it; frame 2: plate A under a new id 12 (a switch); frame 3: no plate,
    id 12 reported. Misses 1, false positives 2, switches 1 over 5 true plates: MOTA = 1 - 4/5 = 0.2.
    IDF1: the best track-to-truth assignment A-10 (2 frames), B-11 (1) gives IDTP 3 of 6 reports and
    5 true plates: 2*3 / (6 + 5) = 6/11."""
    a, b = (0, 100, 100), (1, 300, 100)
    truth = [_frame(a, b), _frame(a, b), _frame(a), _frame()]
    hyp = [_frame((10, 100, 100), (11, 300, 100)), _frame((10, 101, 100), (11, 300, 200)), _frame((12, 100, 100)),
           _frame((12, 400, 300))]
    s = clear_mot(truth, hyp, 2.0)
    assert s["mota"] == pytest.approx(0.2) and s["idf1"] == pytest.approx(6 / 11)
    assert (s["misses"], s["false_positives"], s["switches"], s["objects"]) == (1, 2, 1, 5)
    assert (s["empty_frame_reports"], s["frames_without"]) == (1, 1)
    assert s["motp"] == pytest.approx(1.0)  # summed vertex errors 0, 0, 4, 0 px of the four matches


def test_objects_by_frame_reads_placeholder_rows():
    cols = {"frame": np.array([0, 1, 1, 2.0]), "visible": np.array([0, 1, 1, 0.0]), "id": np.array([-1, 3, 5, -1.0]),
            "scale": np.array([np.nan, 60, 50, np.nan])}
    for i in range(4):
        cols[f"x{i}"], cols[f"y{i}"] = np.arange(4.0) + i, np.arange(4.0) - i
    fr = objects_by_frame(cols)
    assert [len(f.ids) for f in fr] == [0, 2, 0] and fr[1].ids.tolist() == [3, 5]
    assert fr[1].vertices.shape == (2, 4, 2) and fr[1].vertices[1, 2].tolist() == [4.0, 0.0]


def test_identities_follow_moving_boxes_and_start_new_ones():
    ids = Identities(memory=3)

    def box(x):
        return [x, 100, 60, 30]

    assert ids.assign(0, [box(0), box(300)]).tolist() == [0, 1]
    assert ids.assign(1, [box(310), box(10)]).tolist() == [1, 0]  # by position, whatever the order
    assert ids.assign(2, [box(20)]).tolist() == [0]  # id 1 unseen, remembered
    assert ids.assign(4, [box(40), box(330)]).tolist() == [0, 1]  # predicted with its last velocity
    assert ids.assign(5, [box(200)]).tolist() == [2]  # nowhere near a track: a new id
    assert ids.assign(9, [box(40)]).tolist() == [3]  # past the memory: a new id


def _model(k=3):
    from vistrack.models.plate.plates import Plates

    return Plates((640, 480), k)


def test_plates_kernels_and_likelihood_factorise():
    """The joint K and p_0 are the slots' in turn: K's density is the sum of the partitions'; births,
    deaths and moves keep the presence flag consistent; log r = Σ_j log π_j; a second present slot
    on the first one's plate pays the exclusion."""
    from vistrack.appearance.features import FeatureMaps

    m = _model()
    rng = np.random.default_rng(3)
    x = m.sample_prior(400, rng)
    assert set(np.unique(x[:, 9::10])) <= {0.0, 1.0}
    y = m.predict(x, rng)
    born = (x[:, 9] == 0) & (y[:, 9] == 1)
    assert born.any() and np.all(y[born, 8] == 0) and np.all(y[born, 4:8] == y[born, 0:4])
    parts = sum(m.part_logpdf(y[:, c], x, j) for j, c in enumerate(m.partitions))
    np.testing.assert_allclose(m.transition_logpdf(y, x), parts)
    obs = m.observe(FeatureMaps(np.random.default_rng(0).integers(0, 255, (480, 640, 3)).astype(np.uint8)), None)
    np.testing.assert_allclose(m.loglik(obs, y), sum(m.loglik_part(obs, y, j) for j in range(3)))
    two = y[:2].copy()
    two[:, 9::10] = [[1, 1, 0], [1, 0, 0]]
    two[:, 10:19] = two[:, 0:9]  # slot 1 on slot 0's plate
    assert m.loglik_part(obs, two, 1)[0] == pytest.approx(
        m.gain * (m.plate.lik.loglik(obs, two[:1, :9])[0] - m.offset) + m.exclusion)
    assert m.loglik_part(obs, two, 1)[1] == 0.0  # absent: explains nothing


def test_estimate_is_the_same_whatever_slot_holds_a_plate():
    """The slots are exchangeable: particles that hold one plate in slot 0 or in slot 2 give one mode
    with their total weight, not two half modes."""
    m = _model()
    pose = np.array([200.0, 330, 0.0, 70])
    x = np.zeros((40, 30))
    x[:, 0:9] = x[:, 20:29] = np.concatenate([pose, pose, [5.0]])
    x[:20, 9], x[20:, 29] = 1, 1
    x[:, [0, 20]] += np.random.default_rng(0).normal(0, 1, (40, 1))
    est = m.estimate(ParticleSet(x))
    assert est[9] == pytest.approx(1.0) and est[19] == est[29] == 0.0
    assert est[0] == pytest.approx(x[:, 0].mean())


@pytest.mark.slow
def test_run_targets_track_csv_format_and_same_seed(road, tmp_path, capsys):
    """The track CSV of --targets: the exact header, every frame present, a frame without a reported
    plate one row with visible 0, id -1, NaN geometry and its lost reason; the same seed gives the
    same rows (all but the timing column)."""
    outs = []
    for k in range(2):
        track = tmp_path / f"t{k}.csv"
        code, out, err = run(["run", str(road), "--targets", "2", "-n", "20", "--max-frames", "12", "--seed", "5",
                              "--track", str(track), "-q"], capsys)
        assert code == 0, err
        with open(track) as f:
            rows = list(csv.reader(f))
        outs.append([r[:18] + r[19:] for r in rows])
    assert ",".join(outs[0][0][:18] + ["ms"] + outs[0][0][18:]) == TRACK_HEADER
    assert outs[0] == outs[1]
    body = outs[0][1:]
    assert sorted({int(r[0]) for r in body}) == list(range(12))
    for r in body:
        if r[1] == "0":
            assert r[2] == "-1" and set(r[3:17]) == {""} and r[-1] == "not found"
        else:
            assert int(r[2]) >= 0 and r[-1] == ""


def test_target_rows_of_a_frame_with_plates():
    """Rows of reported plates: frame, visible 1, the id, the plate's columns, ess, ms, empty reason."""
    from vistrack.loop import FrameResult
    from vistrack.session.recording import target_rows

    m = _model(2)
    states = np.array([[100.0, 300, 0.0, 60, 100, 300, 0, 60, 3], [400.0, 320, 0.1, 80, 400, 320, 0.1, 80, 7]])
    res = FrameResult(7, None, ParticleSet(np.zeros((4, 20))), np.zeros(20), 2.5, targets=(np.array([4, 9]), states))
    rows = target_rows(m, res)
    assert [list(r)[:3] for r in rows] == [["frame", "visible", "id"]] * 2
    assert [(r["frame"], r["visible"], r["id"]) for r in rows] == [(7, 1, 4), (7, 1, 9)]
    assert rows[1]["scale"] == 80 and rows[0]["x0"] == pytest.approx(70.0) and rows[0]["lost_reason"] == ""
    assert list(rows[0])[3:] == TRACK_HEADER.split(",")[3:]


@pytest.mark.parametrize("argv, msg", [
    (["--targets", "0"], "0 is not in the range x>=1"),
    (["--targets", "2", "--model", "box", "--init", "1,1,20,20"], "--targets is for the plate model"),
    (["--targets", "2", "--results", "r.txt"], "--results writes one box per frame"),
    (["--targets", "2", "--algo", "lls"], "--algo lls does not run on the plate model with --targets; choose from "
                                          "partitioned-lis, partitioned, branched-partitioned-lis"),
    (["--algo", "partitioned"], "partitioned sampling tracks several plates: add --targets K"),
    (["--targets", "2", "--init", "10,10,40,20"], "--targets finds the plates by itself"),
])
def test_bad_targets_input_is_one_error_line(road, tmp_path, capsys, monkeypatch, argv, msg):
    monkeypatch.chdir(tmp_path)
    code, out, err = run(["run", str(road), "-q", "--max-frames", "2"] + argv, capsys)
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert code != 0 and len(lines) == 1 and lines[0].startswith("Error:") and msg in lines[0], err


@pytest.mark.slow
def test_eval_targets_scores_mota_and_idf1(road, tmp_path, capsys, monkeypatch):
    """eval --targets: one row per task in results.csv with the MOT scores; the report's table; a clip
    without objects.csv or a non-plate model is one error line."""
    monkeypatch.chdir(tmp_path)
    code, out, err = run(["eval", str(road), "--model", "plate", "--targets", "2", "--algos",
                          "partitioned-lis,bootstrap", "--particles", "10", "--runs", "1", "--in-process", "--out",
                          "ev", "-q"], capsys)
    assert code == 0, err
    with open(tmp_path / "ev" / "results.csv") as f:
        rows = list(csv.DictReader(f))
    assert [r["algo"] for r in rows] == ["partitioned-lis", "bootstrap"]
    assert list(rows[0])[:6] == ["clip", "algo", "particles", "run", "mota", "idf1"]
    assert all(int(r["objects"]) > 0 and int(r["frames_without"]) > 0 for r in rows)
    assert "| algo | N | runs | MOTA | IDF1 |" in (tmp_path / "ev" / "report.md").read_text()
    code, out, err = run(["eval", str(road), "--targets", "2", "--out", "e2", "-q"], capsys)
    assert code != 0 and err.strip() == "Error: --targets is for --model plate"


def test_a_missing_scorer_is_one_error_line_before_any_tracking(road, tmp_path, capsys, monkeypatch):
    """eval --targets and reproduce plate --overlap score with motmetrics: without it (a stale
    environment), one line saying what to install, and no task run."""
    import sys

    monkeypatch.chdir(tmp_path)
    monkeypatch.setitem(sys.modules, "motmetrics", None)  # import motmetrics raises ImportError
    for argv in (["eval", str(road), "--model", "plate", "--targets", "2", "--particles", "10", "--runs", "1",
                  "--in-process", "--out", "ev", "-q"],
                 ["reproduce", "plate", "--overlap", "--clips", str(road.parent), "--runs", "1", "--in-process",
                  "--out", "rp", "-q"]):
        code, out, err = run(argv, capsys)
        assert code != 0 and err.strip().startswith("Error: the motmetrics library"), err
        assert "pip install motmetrics" in err and len(err.strip().splitlines()) == 1
    assert not list(tmp_path.glob("*/tasks/*")), "no task ran"


@pytest.fixture(scope="module")
def one_car(tmp_path_factory):
    """One car at the evaluation's frame size and about its speed; frame 36 has its plate mid-frame."""
    from vistrack.data_synth.plate_clip import make_plate_clip

    out = tmp_path_factory.mktemp("one_car")
    make_plate_clip(out, frames=100, size=(640, 480), seed=5, cars=1)
    return load_clip(out)


@pytest.mark.slow
def test_a_plate_covered_from_one_side_is_not_reported(one_car):
    """The report test sees partial occlusion: at a plate wholly in view each half scored alone is
    about the whole plate's log-odds, above ``report_half``, and the plate is reported; with a flat
    patch (a car in front) over the left 10 % of the plate, the whole plate still passes the
    whole-plate level, but the left half drops below ``report_half`` while the right stays above it,
    so the plate is reported only without the half test. The compiled and numpy paths agree."""
    from vistrack import kernels
    from vistrack.appearance.features import FeatureMaps
    from vistrack.models.plate.plates import Plates

    t, k = one_car.truth, 36
    assert t["visible"][k] > 0
    pose = np.array([t["cx"][k], t["cy"][k], np.deg2rad(t["angle_deg"][k]), t["scale"][k]])
    state = np.concatenate([pose, pose, [5.0]])[None]
    est = np.concatenate([state[0], [1.0], np.zeros(20)])  # slot 0 holds the plate, slots 1-2 absent
    m, plain = Plates((640, 480), 3), Plates((640, 480), 3, report_half=None)
    lik = m.plate.lik
    frame = dict(one_car.source)[k]
    obs = m.observe(FeatureMaps(frame), None)
    full, halves = lik.loglik(obs, state)[0], lik.half_loglik(obs, state)[0]
    assert np.all(np.abs(halves - full) < 1.0) and halves.min() > m.plate.visible_half
    assert len(m.targets(obs, est)) == 1
    v = m.plate.vertices(state)[0]
    covered = frame.copy()
    covered[int(v[:, 1].min()) - 20:int(v[:, 1].max()) + 20, :int(v[:, 0].min() + 0.1 * pose[3])] = 90
    obs = m.observe(FeatureMaps(covered), None)
    left, right = lik.half_loglik(obs, state)[0]
    assert lik.loglik(obs, state)[0] > m.plate.visible_loglik
    assert left < m.plate.visible_half < right
    assert len(m.targets(obs, est)) == 0 and len(plain.targets(obs, est)) == 1
    with kernels.numpy_paths(True):
        np.testing.assert_allclose(lik.half_loglik(obs, state)[0], [left, right], atol=1e-3)
