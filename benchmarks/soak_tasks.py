"""The soak's batch scenarios (:mod:`soak`): eval's grid and its task files, ``--resume``, the ``--out`` lock,
a worker killed, a scheduler away, two evals into one folder. What they may break: task files lost or
reused where they should not be, results that mix runs."""

from __future__ import annotations

from soak_harness import EV, Scenario, damage, equals_fresh, evald, lost_if_flagged, resynth, sub, tasks_kept, two_evals


def scenarios():
    """The batch scenarios."""
    suite = "{fx}/suite"
    seed1 = EV("{w}/suite", "--seed", "1")
    unreported = EV("{w}/suite", "--resume")
    return [
        Scenario("eval --resume with a task file that lost a key under its fingerprint", unreported, "ok",
                 prepare=evald(["suite"], then=_drop_key("reported")),
                 check=equals_fresh(sub(EV("{w}/suite"), "--out", "{w}/F"))),
        Scenario("eval --resume with a task file whose lists were cut short", unreported, "ok",
                 prepare=evald(["suite"], then=_cut_lists), check=equals_fresh(sub(EV("{w}/suite"), "--out", "{w}/F"))),
        Scenario("eval suite", EV(suite), "ok"),
        Scenario("eval suite, 2 worker processes", [a for a in EV(suite) if a != "--in-process"] + ["--workers", "2"],
                 "ok"),
        Scenario("eval --scheduler notaurl", EV(suite, "--scheduler", "notaurl"), mention="notaurl"),
        Scenario("eval unreachable scheduler keeps the old task files",
                 EV("{w}/suite", "--scheduler", "tcp://127.0.0.1:9", "--timeout", "2"), prepare=evald(["suite"]),
                 mention="scheduler", check=tasks_kept(2)),
        Scenario("eval two evals into one --out", EV(suite, "--seed", "2"), mention="in use", check=lost_if_flagged,
                 driver=two_evals(sub(sub(EV(suite, "--seed", "1"), "--particles", "300"), "--runs", "4"),
                                  EV(suite, "--seed", "2"))),
        Scenario("eval --resume after a seed change", sub(EV("{w}/suite", "--resume"), "--seed", "2"), "ok",
                 prepare=evald(["suite"], "--seed", "1"), check=equals_fresh(sub(sub(seed1, "--seed", "2"),
                                                                                  "--out", "{w}/F"))),
        Scenario("eval --resume with a {} task file", EV("{w}/suite", "--resume"), "ok", prepare=evald(
            ["suite"], then=damage("{}")), check=equals_fresh(sub(EV("{w}/suite"), "--out", "{w}/F"))),
        Scenario("eval --resume with a cut task file", EV("{w}/suite", "--resume"), "ok", prepare=evald(
            ["suite"], then=damage('{"clip": "c')), check=equals_fresh(sub(EV("{w}/suite"), "--out", "{w}/F"))),
        Scenario("eval --resume with a binary task file", EV("{w}/suite", "--resume"), "ok", prepare=evald(
            ["suite"], then=damage(b"\\xff\\xfe\\x00")), check=equals_fresh(sub(EV("{w}/suite"), "--out", "{w}/F"))),
        Scenario("eval --resume after the clip changed", EV("{w}/suite", "--resume"), "ok", prepare=evald(
            ["suite"], then=resynth), check=equals_fresh(sub(EV("{w}/suite"), "--out", "{w}/F"))),
        Scenario("eval --model plate on contour clips", EV(suite, model="plate"), "either"),
        Scenario("eval --model landmarks on contour clips", EV(suite, model="landmarks"), "either"),
        Scenario("eval --algos opencv-mil", sub(EV(suite), "--algos", "opencv-mil"), "ok"),
        Scenario("eval --equal-time", EV(suite, "--equal-time") + ["--algos", "bootstrap,lis"], "ok"),
    ]


def _edit_task(edit):
    """``then(w)``: the first task file of ``w/R`` edited by ``edit(dict)``, its fingerprint kept."""
    import json

    def then(w):
        p = sorted((w / "R" / "tasks").glob("*.json"))[0]
        data = json.loads(p.read_text())
        edit(data)
        p.write_text(json.dumps(data))

    return then


def _drop_key(key):
    return _edit_task(lambda d: d.pop(key, None))


_cut_lists = _edit_task(lambda d: d.update({k: v[: len(v) // 2] for k, v in d.items() if isinstance(v, list)}))
