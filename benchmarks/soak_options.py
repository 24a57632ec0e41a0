"""The soak's option scenarios (:mod:`soak`): numbers, boxes, sizes, names and files given to an option that
do not make sense. What they may break: the one-line error (a traceback, a vague or late message) or an
input taken as something it is not."""

from __future__ import annotations

from soak_harness import BE, EV, INIT, SY, R, Scenario, all_of, fast, says, sub, warns


def scenarios():
    """The option scenarios."""
    return _numbers() + _commands() + _strict()


def _numbers():
    base = R("{fx}/v.avi", init=False)
    init = [("nan,1,2,3", "--init"), ("10,10,inf,20", "--init"), ("10,10,-5,20", "--init"), ("10,10,0,0", "--init"),
            ("1e300,1,2,3", "--init"), ("1,2,3", "--init"), ("a,b,c,d", "--init"), ("500,500,20,20", "--init")]
    out = [Scenario(f"run --init {v}", base + ["--init", v], mention=m) for v, m in init]
    opts = [("-n", "0"), ("-n", "-5"), ("-n", "100000000"), ("-n", "nan"), ("--ess-threshold", "nan"),
            ("--ess-threshold", "-0.5"), ("--ess-threshold", "2"), ("--ess-threshold", "inf"), ("--seed", "-1"),
            ("--seed", "nan"), ("--max-frames", "0"), ("--max-frames", "-3"),
            ("--show-particles", "-1")]
    out += [Scenario(f"run {o} {v}", sub(base + ["--init", INIT], o, v), mention=o.lstrip("-")[:4] if o != "-n"
                     else "partic") for o, v in opts]
    out += [Scenario("run --seed 2**64 (any non-negative integer seeds numpy)",
                     sub(base + ["--init", INIT], "--seed", str(2**64)), "either")]
    out += [
        Scenario("run --show-particles 1000000 (more than N)", R("{fx}/v.avi", "--show-particles", "1000000",
                                                                  "--out", "{w}/a.mp4"), "either"),
        Scenario("run --template with NaN", R("{fx}/v.avi", "--model", "contour", "--template",
                                              "{fx}/template_nan.txt"), mention="template"),
        Scenario("run --template garbage", R("{fx}/v.avi", "--model", "contour", "--template", "{fx}/garbage.txt"),
                 mention="garbage.txt"),
        Scenario("run --template missing", R("{fx}/v.avi", "--model", "contour", "--template", "{fx}/none.txt"),
                 mention="none.txt"),
        Scenario("run --init-gt missing file", R("{fx}/v.avi", "--init-gt", "{fx}/none.txt", init=False),
                 mention="none.txt"),
        Scenario("run --init-gt garbage file", R("{fx}/v.avi", "--init-gt", "{fx}/garbage.txt", init=False),
                 mention="garbage.txt"),
        Scenario("run --init-gt on a bare video", R("{fx}/v.avi", "--init-gt", init=False), mention="ground"),
        Scenario("run --model landmarks on a plain video", R("{fx}/v.avi", "--model", "landmarks", init=False),
                 mention="landmark"),
        Scenario("run --algo pf-eis with the box model", R("{fx}/v.avi", "--algo", "pf-eis"), mention="pf-eis"),
        Scenario("run --init and --init-gt together", R("{fx}/clip", "--init-gt"), "either"),
        Scenario("run --model box without a box", R("{fx}/v.avi", "--model", "box", init=False), mention="init"),
    ]
    return out


def _commands():
    suite = "{fx}/suite"
    v = "{fx}/v.avi"
    P = ["synth", "perturb", "{fx}/otb", "--out", "{w}/o", "-q"]
    out = [
        *[Scenario(f"eval {o} {v}", sub(EV(suite), o, v), mention=m) for o, v, m in [
            ("--particles", "0", "particles"), ("--particles", "-5", "particles"), ("--particles", "nan", "particles"),
            ("--runs", "0", "runs"), ("--runs", "-1", "runs"), ("--seed", "-1", "seed"), ("--workers", "-1", "workers"),
            ("--timeout", "0", "timeout"), ("--algos", "nope", "nope"), ("--model", "nope", "nope")]],
        Scenario("eval --particles 100000000", sub(EV(suite), "--particles", "100000000"), mention="partic"),
        Scenario("eval --algos '' without --results-dir", sub(EV(suite), "--algos", ""), mention="algos"),
        Scenario("synth contour", SY, "ok"),
        *[Scenario(f"synth {o} {v}", sub(SY, o, v), mention=m) for o, v, m in [
            ("--frames", "0", "frames"), ("--frames", "-1", "frames"), ("--size", "8x8", "8x8"),
            ("--size", "100000x100000", "100000"), ("--size", "nanxnan", "size"), ("--seed", "-1", "seed")]],
        Scenario("synth --size 3840x2160", sub(sub(SY, "--size", "3840x2160"), "--frames", "2"), "ok"),
        Scenario("synth plate --cars 0", ["synth", "plate", "--out", "{w}/p", "--frames", "3", "--cars", "0"],
                 mention="cars"),
        Scenario("synth plate --size 100x80", ["synth", "plate", "--out", "{w}/p", "--frames", "3", "--size", "100x80"],
                 mention="100x80"),
        Scenario("synth plate small", ["synth", "plate", "--out", "{w}/p", "--frames", "3", "--size", "160x120", "-q"],
                 "ok"),
        Scenario("synth landmarks --k 2", ["synth", "landmarks", "--out", "{w}/l", "--frames", "3", "--k", "2"],
                 mention="k"),
        *[Scenario(f"synth landmarks --occlusion {v}", ["synth", "landmarks", "--out", "{w}/l", "--frames", "3",
                                                        "--size", "128x96", "--occlusion", v], mention="occlusion")
          for v in ("nan", "2", "-1")],
        Scenario("synth landmarks --clutter-blobs -1", ["synth", "landmarks", "--out", "{w}/l", "--frames", "3",
                                                        "--clutter-blobs", "-1"], mention="clutter"),
        Scenario("synth-suite --clips 0", ["synth-suite", "--kind", "contour", "--clips", "0", "--out", "{w}/s"],
                 mention="clips"),
        Scenario("synth-suite plate 64x48", ["synth-suite", "--kind", "plate", "--clips", "1", "--frames", "2",
                                             "--size", "64x48", "--out", "{w}/s"], mention="64x48"),
        Scenario("synth-suite contour", ["synth-suite", "--kind", "contour", "--clips", "2", "--frames", "2",
                                         "--size", "96x72", "--out", "{w}/s", "-q"], "ok"),
        Scenario("run --init 0,0,1e12,1e12 (box)", R(v, init=False) + ["--init", "0,0,1e12,1e12"], mention="larger"),
        Scenario("run --init 0,0,1e12,1e12 (contour)", R(v, "--model", "contour", init=False)
                 + ["--init", "0,0,1e12,1e12"], mention="larger"),
        Scenario("eval --results-dir a/mt --results-dir b/mt", EV("{fx}/suite/c1", "--results-dir", "{fx}/rd_a/mt",
                                                                     "--results-dir", "{fx}/rd_b/mt"),
                 mention="same name"),
        Scenario("eval --results-dir named lis", EV("{fx}/suite/c1", "--results-dir", "{fx}/rd_lis/lis"),
                 mention="named like"),
        Scenario("eval --equal-time on a 1-frame clip", EV("{fx}/one_frame", "--equal-time", model="box")
                 + ["--algos", "lis,bootstrap"], mention="at least 3"),
        Scenario("eval --particles 100,100", sub(EV("{fx}/suite"), "--particles", "100,100"), mention="twice"),
        Scenario("eval --algos lis,lis", sub(EV("{fx}/suite"), "--algos", "lis,lis"), mention="twice"),
        Scenario("synth --size 321x241", sub(SY, "--size", "321x241"), mention="even"),
        Scenario("synth plate --frames 3 --size 160x120", ["synth", "plate", "--out", "{w}/p", "--frames", "3",
                                                               "--size", "160x120", "-q"], "ok",
                 check=warns("no plate")),
        Scenario("demo --real-frames 60 on a 12-frame clip", ["demo", "--out", "{w}/d", "--frames", "10", "--runs",
                                                                  "1", "--real-clip", "{fx}/otb", "--real-frames",
                                                                  "60"], "ok", check=says("all 12 frames")),
        Scenario("run --init with 1 px inside the frame", R(v, init=False) + ["--init", "159,119,30,30"],
                 mention="outside"),
        Scenario("run --template of 4 points, one NaN", R(v, "--model", "contour", "--template",
                                                              "{fx}/template_nan4.txt"),
                 mention="finite"),
        Scenario("synth --size 8192x2048", sub(SY, "--size", "8192x2048"), mention="8190"),
        Scenario("eval --out E where E/tasks is a file", sub(EV("{fx}/suite"), "--out", "{w}/E"), mention="tasks",
                 check=fast(20), prepare=lambda w: ((w / "E").mkdir(), (w / "E" / "tasks").write_text("x"))),
        Scenario("synth perturb --gain without --light", [*P, "--gain", "0.5:1"], mention="--light"),
        Scenario("synth perturb --shake 1000", [*P, "--shake", "1000"], "ok",
                   check=all_of(_absent_truth, warns("out of the frame"))),
        Scenario("run --init-gt EXISTING_FOLDER", R("{fx}/otb", "--init-gt", "{fx}/otb", init=False),
                   mention="is a folder"),
    ]
    out += [Scenario("reproduce bearings", BE + ["--json", "{w}/b.json"], "ok")]
    out += [Scenario(f"reproduce bearings {o} {v}", sub(BE, o, v), mention=m) for o, v, m in [
        ("--runs", "0", "runs"), ("--runs", "-1", "runs"), ("--particles", "0", "particles"), ("--ships", "0", "ships"),
        ("--ships", "-1", "ships"), ("--steps", "0", "steps"), ("--sequences", "-1", "sequences"),
        ("--ess-threshold", "nan", "ess"), ("--algos", "nope", "nope"), ("--seed", "-1", "seed")]]
    out += [
        Scenario("reproduce contour --clips missing: made there",
                 ["reproduce", "contour", "--clips", "{w}/made", "--make", "1", "--frames", "3", "--size", "96x72",
                  "--algos", "lis:10", "--runs", "1", "--in-process", "--out", "{w}/C", "-q"], "ok"),
        Scenario("reproduce contour on two small clips", ["reproduce", "contour", "--clips", "{fx}/suite", "--algos",
                                                          "lis:20,bootstrap:40", "--runs", "1", "--in-process", "--out",
                                                          "{w}/C", "--json", "{w}/c.json", "-q"], "ok"),
        Scenario("reproduce contour --algos lis:0",
                 ["reproduce", "contour", "--clips", "{fx}/suite", "--algos", "lis:0", "--runs", "1", "--in-process",
                  "--out", "{w}/C", "-q"],
                 mention="lis:0"),
        Scenario("reproduce contour --frames 1", ["reproduce", "contour", "--clips", "{w}/none", "--frames", "1",
                                                  "--in-process", "--out", "{w}/C", "-q"], mention="frames"),
        Scenario("fit-plate a missing folder", ["fit-plate", "{fx}/nothere"], mention="nothere"),
        Scenario("fit-plate contour clips", ["fit-plate", "{fx}/suite"], mention="plate"),
        Scenario("unknown command", ["frobnicate"], mention="frobnicate"),
    ]
    return out


def _absent_truth(w, res):
    import numpy as np

    if res.code != 0:
        return None
    gt = np.loadtxt(w / "o" / "groundtruth_rect.txt", delimiter=",")
    if np.any(gt[:, 2] > 0):
        return "silent wrong", f"{int(np.sum(gt[:, 2] > 0))} boxes marked present, all out of the frame"
    return None


def _strict():
    """Issue 55's option cases: numbers read strictly, NaN refused by every float option, URLs as outputs."""
    base = R("{fx}/v.avi", init=False)
    poc = ["synth", "plate-on-car", "{fx}/otb", "--out", "{w}/o"]
    return [
        *[Scenario(f"run --init {v}", base + ["--init", v], mention="init") for v in ("4_1,48,25,19", "٣,48,25,19")],
        *[Scenario(f"synth plate-on-car {o} nan", [*poc, o, "nan"], mention=o.lstrip("-"))
          for o in ("--upscale", "--noise", "--width", "--blur")],
        Scenario("synth perturb --shake nan", ["synth", "perturb", "{fx}/otb", "--out", "{w}/o", "--shake", "nan"],
                 mention="shake"),
        Scenario("run --out a URL", R("{fx}/v.avi", "--out", "http://127.0.0.1:9/a.mp4"), mention="a URL"),
        Scenario("eval --out a URL", sub(EV("{fx}/suite"), "--out", "http://127.0.0.1:9/R"), mention="a URL"),
    ]
