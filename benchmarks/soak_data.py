"""The soak's data scenarios (:mod:`soak`): videos and image folders damaged, cut, odd or empty; ground
truth, meta.json and result files that are not what their layout says; clips given as URLs and their
cache; run's summary against eval's. What they may break: a frame or a box read wrong, a score over the
wrong frames, a cached copy used when it should not be."""

from __future__ import annotations

import functools
import http.server
import json
import os
import shutil
import threading
import time

import soak_harness as S
from soak_harness import (
    EV,
    FRAMES,
    R,
    Scenario,
    all_of,
    consistent_absent,
    copy,
    natural_order,
    results_follow_track,
    results_lines,
    says,
    short_error,
    track_accounts,
    track_decodable,
    track_has,
    warns,
)


def scenarios():
    """The data scenarios."""
    return _videos() + _truth() + _urls() + _summary() + _conventions() + _caches()


def _videos():
    E = "either"

    def fifo(w):
        os.mkfifo(w / "fifo")

    return [

        Scenario("run avi", R("{fx}/v.avi"), "ok", check=track_has(FRAMES, FRAMES)),
        Scenario("run mp4, moov at the end", R("{fx}/moov_end.mp4"), "ok", check=track_has(FRAMES, FRAMES)),
        Scenario("run mp4, moov at the front", R("{fx}/moov_front.mp4"), "ok", check=track_has(FRAMES, FRAMES)),
        Scenario("run mp4 cut at 60 %, moov at the end", R("{fx}/trunc_end.mp4"), E),
        Scenario("run mp4 cut at 60 %, moov at the front", R("{fx}/trunc_front.mp4"), E,
                 check=track_decodable("trunc_front.mp4")),
        Scenario("run avi cut at 60 %", R("{fx}/trunc.avi"), E, check=track_decodable("trunc.avi")),
        Scenario("run mp4, 1500 bytes overwritten mid-stream", R("{fx}/corrupt.mp4"), "ok",
                 check=track_decodable("corrupt.mp4")),
        Scenario("run avi, 1500 bytes overwritten mid-stream", R("{fx}/corrupt.avi"), "ok",
                 check=track_decodable("corrupt.avi")),
        Scenario("run zero-byte video", R("{fx}/empty.mp4"), mention="empty.mp4"),
        Scenario("run 1-frame video", R("{fx}/one.mp4"), "ok", check=track_has(1, 1)),
        Scenario("run 8x8 frames, box inside", R("{fx}/tiny.avi", init=False) + ["--init", "1,1,5,5"], E),
        Scenario("run 8x8 frames, plates (no box)", R("{fx}/tiny.avi", init=False), E),
        Scenario("run 3840x2160 frames", R("{fx}/uhd.mp4", init=False) + ["--init", "1400,1000,300,200"], "ok",
                 check=track_has(3, 3)),
        Scenario("run grey video", R("{fx}/grey.avi"), "ok", check=track_has(FRAMES, FRAMES)),
        Scenario("run grey image folder", R("{fx}/grey"), "ok", check=track_has(8, 8)),
        Scenario("run 4-channel image folder", R("{fx}/bgra"), "ok", check=track_has(8, 8)),
        Scenario("run 16-bit image folder", R("{fx}/u16"), "ok", check=track_has(8, 8)),
        Scenario("run image folder with one bad image", R("{fx}/badimg"), "ok", check=track_accounts(8, 1)),
        Scenario("run image folder of bad images only", R("{fx}/allbad"), mention="allbad"),
        Scenario("run empty folder", R("{fx}/emptydir"), mention="emptydir"),
        Scenario("run a text file", R("{fx}/notes.txt"), mention="notes.txt"),
        Scenario("run a missing path", R("{fx}/nothere.mp4"), mention="nothere"),
        Scenario("run synthetic clip --init-gt", R("{fx}/clip", "--init-gt", init=False), "ok",
                 check=track_has(20, 20)),
        Scenario("run clip, contour LS-N-IPS", R("{fx}/clip", "--init-gt", "--model", "contour", "--algo", "ls-n-ips",
                                                  init=False), "ok"),
        Scenario("run plate clip, no box", R("{fx}/plate", init=False), "ok", check=track_has(10, 10)),
        Scenario("run landmark clip", ["run", "{fx}/lm", "-n", "50", "--track", "{w}/t.csv", "-q"], "ok",
                 check=track_has(10, 10)),
        Scenario("run OTB folder --init-gt", R("{fx}/otb", "--init-gt", init=False), "ok", check=track_has(12, 12)),
        Scenario("run OTB folder whose ground truth is all absent, --init-gt", R("{fx}/otb_absent", "--init-gt",
                                                                                 init=False), mention="ground"),
        Scenario("run --max-frames 5", R("{fx}/v.avi", "--max-frames", "5"), "ok", check=track_has(5, 5)),
        Scenario("run --out annotated video", R("{fx}/v.avi", "--out", "{w}/a.mp4"), "ok"),
        Scenario("run --results OTB format", R("{fx}/v.avi", "--results", "{w}/r.txt"), "ok"),
        Scenario("run image folder whose frames change size, --out", R("{fx}/sizes", "--out", "{w}/a.mp4"),
                 mention="0004.png"),
        Scenario("run image folder whose frames change size", R("{fx}/sizes"), mention="0004.png"),
        Scenario("run 12 undecodable frames of 40, --results", R("{fx}/bad12", "--results", "{w}/r.txt"), "ok",
                 check=all_of(track_accounts(40, 12), results_follow_track(40))),
        Scenario("run frames frame1..frame12", R("{fx}/natural", "--out", "{w}/a.mp4", "--show-particles", "0",
                                                     init=False) + ["--init", "60,50,21,17"], "ok",
                 check=natural_order),
        Scenario("run avi cut at 60 % says it ended early", R("{fx}/trunc.avi"), "ok", check=warns("ended early")),
        Scenario("run /dev/zero", R("/dev/zero"), mention="not a regular file"),
        Scenario("run a FIFO", R("{w}/fifo"), mention="not a regular file", prepare=fifo),
    ]


def _truth():
    def tiny(w):
        shutil.copytree(S.FX / "otb", w / "tiny")
        (w / "tiny" / "groundtruth_rect.txt").write_text("1,1,0.5,0.5\n" * 12)

    return [
        Scenario("eval a clip without ground truth", EV("{fx}/v.avi"), mention="ground truth"),
        Scenario("eval a missing path", EV("{fx}/nothere"), mention="nothere"),
        Scenario("eval an empty folder", EV("{fx}/emptydir"), mention="emptydir"),
        Scenario("eval OTB clip", EV("{fx}/otb", model="box"), "ok", check=consistent_absent),
        Scenario("eval OTB clip, grey images", EV("{fx}/otb_grey", model="box"), "ok"),
        Scenario("eval OTB absent frames as NaN", EV("{fx}/otb_nan", model="box"), "ok", check=consistent_absent),
        Scenario("eval OTB absent frames as 0,0,0,0", EV("{fx}/otb_zero", model="box"), "ok", check=consistent_absent),
        Scenario("eval ground truth shorter than the video", EV("{fx}/otb_short", model="box"), "ok",
                 check=warns("ground truth")),
        Scenario("eval ground truth longer than the video", EV("{fx}/otb_long", model="box"), "ok",
                 check=warns("ground truth")),
        Scenario("eval ground truth with negative sizes (absent)", EV("{fx}/otb_negative", model="box"), "ok",
                 check=consistent_absent),
        Scenario("eval malformed ground-truth line", EV("{fx}/otb_bad", model="box"), mention="line 6"),
        Scenario("eval ground truth all absent", EV("{fx}/otb_absent", model="box"), mention="ground truth"),
        Scenario("eval empty ground-truth file", EV("{fx}/otb_empty", model="box"), mention="ground truth"),
        Scenario("eval one undecodable image", EV("{fx}/otb_badimg", model="box"), "ok"),
        Scenario("eval --results-dir", EV("{w}/suite/c1", "--results-dir", "{w}/results"), "ok",
                 prepare=copy("suite", "results")),
        Scenario("eval --results-dir without a clip's file", EV("{fx}/suite", "--results-dir", "{fx}/results"),
                 mention="c2.txt"),
        Scenario("eval --results-dir with a garbage file", EV("{w}/suite/c1", "--results-dir", "{w}/badresults"),
                 mention="c1.txt", prepare=copy("suite", "badresults")),
        Scenario("run meta.json [1,2,3]", R("{fx}/meta_list"), mention="meta.json"),
        Scenario("run meta.json \"hello\"", R("{fx}/meta_str"), mention="meta.json"),
        Scenario("eval meta.json [1,2,3]", EV("{fx}/meta_list", model="box"), mention="meta.json"),
        Scenario("eval --results-dir shorter than the ground truth", EV("{fx}/suite/c1", "--results-dir",
                                                                           "{fx}/rd_short/mt"), "ok",
                 check=warns("6 lines for the 10")),
        Scenario("run --init-gt, ground truth absent in frames 0-3", R("{fx}/otb_late", "--init-gt", "--results",
                                                                          "{w}/r.txt", init=False), "ok",
                 check=all_of(says("tracking starts there"), results_lines(12, first_zero=4))),
        Scenario("run ground-truth box 1e300", R("{fx}/otb_huge", "--init-gt", init=False), mention="line 2",
                 check=short_error()),
        Scenario("run binary ground truth", R("{fx}/otb_binary", "--init-gt", init=False),
                 mention="groundtruth_rect.txt"),
        Scenario("run ground truth with a UTF-8 BOM", R("{fx}/otb_bom", "--init-gt", init=False), "ok",
                 check=track_has(12, 12)),
        Scenario("run --init-gt, first boxes missing: the redetected column",
                   R("{fx}/otb_late", "--init-gt", init=False), "ok", check=_has_column("redetected")),
        Scenario("run a 0.5x0.5 ground-truth box", R("{w}/tiny", "--init-gt", init=False),
                   mention="smaller than 2 px", prepare=tiny),
    ]


def _served(steps):
    """A driver: ``w/www`` served over HTTP on a free port (``{url}``) while the steps run, with
    ``$VISTRACK_CACHE`` in ``w``; ``then(w)`` between steps. The result is the last step's; every
    step's is in ``res.steps``."""

    def driver(w, argv, timeout):
        handler = functools.partial(http.server.SimpleHTTPRequestHandler, directory=str(w / "www"))
        handler.log_message = lambda *a: None
        server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
        threading.Thread(target=server.serve_forever, daemon=True).start()
        url = f"http://127.0.0.1:{server.server_address[1]}"
        env = {**os.environ, "VISTRACK_CACHE": str(w / "cache")}
        t0, results = time.time(), []
        try:
            for step in steps:
                if callable(step):
                    step(w)
                    continue
                args = [a.format(w=w, fx=S.FX, url=url) for a in step]
                r = S.vistrack(args, w, timeout, env=env)
                results.append(r)
        finally:
            server.shutdown()
        res = results[-1]
        res.steps = results
        res.seconds = time.time() - t0
        return res

    return driver


def _shift_truth(w):
    """The server's ground truth changes: every box 30 px to the right."""
    import csv

    p = w / "www" / "c1" / "groundtruth.csv"
    with open(p, newline="") as f:
        rows = list(csv.DictReader(f))
    for r in rows:
        r["cx"] = f"{float(r['cx']) + 30:.3f}"
    with open(p, "w", newline="") as f:
        wr = csv.DictWriter(f, fieldnames=list(rows[0]))
        wr.writeheader()
        wr.writerows(rows)


def _fresh_scores(w, res):
    a, b = (json.loads((w / d / "results.json").read_text())["results"][0]["success_auc"] for d in ("R1", "R2"))
    if a == b and "cache" not in res.err.lower():
        return "silent wrong", f"the changed clip scored as the old one (AUC {a:.3f}), no word of a cache"
    return None


def _urls():
    ev = ["eval", "{url}/c1", "--model", "contour", "--algos", "bootstrap", "--particles", "20", "--runs", "1",
          "--in-process", "-q", "--out"]
    shown = [a.replace("{url}", "URL") for a in ev] + ["W/R2"]
    return [
        S.Scenario("eval a URL clip whose ground truth changed on the server", shown, "ok",
                   prepare=lambda w: shutil.copytree(S.FX / "suite" / "c1", w / "www" / "c1"),
                   check=_fresh_scores,
                   driver=_served([[*ev, "{w}/R1"], _shift_truth, [*ev, "{w}/R2"]])),
        S.Scenario("eval an unreachable URL names it", S.EV("http://127.0.0.1:9/c1"), mention="127.0.0.1:9/c1"),
        S.Scenario("run 0 beside a file 0 reads the file", ["run", "0", "--init", S.INIT, "-n", "20", "-q",
                                                                  "--track", "{w}/t.csv"], "ok",
                   prepare=lambda w: shutil.copy(S.FX / "v.avi", w / "0"), check=S.track_has(S.FRAMES, S.FRAMES)),
    ]


def _summary_agrees(w, res):
    """run's summary and eval --results-dir over the same results agree. The results file holds 0,0,0,0 on
    the frames the tracker reported lost (issue 44), so eval scores them as run's summary does "with the
    frames reported lost as empty": that AUC, the frames lost, and the mean error over the frames reported
    tracked (run's precision counts a reported-lost frame's estimate, the file cannot)."""
    import re

    if res.code != 0:
        return None
    line = next((ln for ln in res.steps[0].out.splitlines() if ln.startswith("vs ground truth")), "")
    r = json.loads((w / "E" / "results.json").read_text())["results"][0]
    m = re.search(r"\(([0-9.]+) with the frames reported lost as empty\).*\(([0-9.]+) px over the frames reported "
                  r"tracked\).*lost by the ground truth \([^)]*\) in (\d+)", line)
    if not m:
        return "silent wrong", f"no summary line: {line[:80]!r}"
    auc, err, lost = float(m.group(1)), float(m.group(2)), int(m.group(3))
    n = sum(1 for _ in open(w / "mt" / "bad12.txt"))
    if abs(auc - r["success_auc"]) > 1e-3 or abs(err - r["mean_error"]) > 0.01 or abs(lost / n - r["p_lost"]) > 1e-6:
        return "silent wrong", f"run: AUC {auc}, error {err} px, {lost} lost; eval: {r['success_auc']:.3f}, " \
                               f"{r['mean_error']:.2f} px, P(lost) {r['p_lost']:.3f}"
    res.note = f"AUC {auc}, error {err} px, {lost} lost in both"
    return None


def _summary():
    first = ["run", "{fx}/bad12", "--init-gt", "-n", "50", "--results", "{w}/mt/bad12.txt"]
    then = ["eval", "{fx}/bad12", "--algos", "", "--results-dir", "{w}/mt", "--out", "{w}/E", "-q"]
    return [S.Scenario("run's summary and eval score 12 undecodable frames alike", then, "ok",
                       prepare=lambda w: (w / "mt").mkdir(), driver=S.two_steps(first, then), check=_summary_agrees)]


def _has_column(name):
    def check(w, res):
        if res.code != 0:
            return None
        head = (w / "t.csv").read_text().splitlines()[0].split(",")
        return None if name in head else ("silent wrong", f"the track has no {name} column: {head}")

    return check


def _conventions():
    """Issue 55's data cases: flag files of another length, WebP frames, a perfect results file's score, a
    --targets track's frames without a plate, URLs never taken for paths."""
    def short_flags(w):
        shutil.copytree(S.FX / "otb", w / "lasot")
        (w / "lasot" / "full_occlusion.txt").write_text("0,0,1,0")

    def webp(w):
        import cv2

        (w / "wp" / "img").mkdir(parents=True)
        for k, f in enumerate(S._frames(8)):
            cv2.imwrite(str(w / "wp" / "img" / f"{k + 1:04d}.webp"), f)
        (w / "wp" / "groundtruth_rect.txt").write_text("\n".join(S._otb_rows(8)) + "\n")

    def perfect(w):
        shutil.copytree(S.FX / "otb", w / "otb")
        (w / "mt").mkdir()
        shutil.copy(w / "otb" / "groundtruth_rect.txt", w / "mt" / "otb.txt")

    def at_most_20_of_21(w, res):
        if res.code != 0:
            return None
        auc = json.loads((w / "R" / "results.json").read_text())["results"][0]["success_auc"]
        return None if auc <= 20 / 21 + 1e-12 else ("silent wrong", f"success AUC {auc:.4f} above 20/21")

    return [
        Scenario("eval an OTB clip whose full_occlusion.txt is short", EV("{w}/lasot", model="box"), "ok",
                 prepare=short_flags, check=warns("4 flags for the 12 rows")),
        Scenario("run an OTB folder of .webp frames", R("{w}/wp", "--init-gt", init=False), "ok", prepare=webp,
                 check=track_has(8, 8)),
        Scenario("eval a results file equal to the ground truth", EV("{w}/otb", "--results-dir", "{w}/mt",
                                                                     model="box") + ["--algos", ""], "ok",
                 prepare=perfect, check=at_most_20_of_21),
        Scenario("run --targets 3 on a plate clip: empty cells, never nan", R("{fx}/plate", "--targets", "3",
                                                                            init=False), "ok"),
        Scenario("run --init-gt a URL", R("{fx}/v.avi", "--init-gt", "http://127.0.0.1:9/gt.txt", init=False),
                 mention="a URL"),
        Scenario("run a URL that redirects in a loop", ["run", "URL/v.mp4", "--init", S.INIT, "-q"],
                 mention="in a loop", driver=_looping(["run", "{url}/v.mp4", "--init", S.INIT, "-q"])),
        Scenario("run an ftp:// URL nobody answers", ["run", "ftp://127.0.0.1:9/v.mp4", "--init", S.INIT, "-q"],
                 mention="ftp://127.0.0.1:9/v.mp4"),
    ]


def _looping(steps):
    """A driver: the command ``steps`` with ``{url}`` a server that redirects every path to itself."""

    def driver(w, argv, timeout):
        with S.looping_server() as url:
            return S.vistrack([a.format(url=url) for a in steps], w, timeout)

    return driver


def _caches():
    """Issue 55's caches: a cached copy cut short, changed or replaced by a folder is downloaded again; a
    cache that cannot be written names itself and VISTRACK_CACHE."""
    run_url = ["run", "{url}/v.mp4", "--init", S.INIT, "-n", "20", "--track", "{w}/t.csv"]
    shown = [a.replace("{url}", "URL") for a in run_url]

    def serve_video(w):
        (w / "www").mkdir()
        shutil.copy(S.FX / "moov_front.mp4", w / "www" / "v.mp4")

    def damage(how):
        def then(w):
            (copy,) = (w / "cache").rglob("v.mp4")
            S.damage_copy(copy, how)

        return then

    def fetched_again(w, res):
        return None if res.code != 0 or "again into" in res.err else \
            ("silent wrong", f"the damaged copy was used: {res.err.strip()[-100:]!r}")

    def cache_a_file(w):
        serve_video(w)
        (w / "cache").write_text("not a folder")

    return [
        *[Scenario(f"run a URL whose cached copy was {how}", shown, "ok", prepare=serve_video, check=fetched_again,
                   driver=_served([run_url, damage(how), run_url])) for how in ("cut", "changed", "a folder")],
        Scenario("run a URL with the download cache a file", shown, mention="download cache", prepare=cache_a_file,
                 driver=_served([run_url])),
    ]
