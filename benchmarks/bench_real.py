"""vistrack's defaults beside NanoTrack v3 and OpenCV's trackers on every real clip with ground truth: the table
of record (issues 34, 43 and 51).

    python benchmarks/bench_real.py --seeds 3 --sre --speed --entries box/lis:100   # the table of record
    python benchmarks/bench_real.py --seeds 1                           # user starts only, one seed
    python benchmarks/bench_real.py --seeds 3 --sre --speed --readme README.md --json real.json
    python benchmarks/bench_real.py --seeds 3 --stress ramp,blur        # also stressed copies (issue 34)

Clips: the corpus of ``real_corpus.py``: every folder under ``--data`` (``../shared/data/real``) holding
``groundtruth_rect.txt`` (globbed, so a clip added later is included), or those named by ``--clips``.

Starts (``real_corpus.py``)
    every tracker starts from the box a user types: the first line of the ground-truth file as written,
    in whole pixels (for OTB's 1-based files one pixel off the 0-based truth, the same box for all).
    ``--sre`` adds OTB's 12 spatial-robustness starts (the box shifted by 10 % of its size in 8
    directions and scaled by 0.8, 0.9, 1.1, 1.2): their mean AUC per clip (vistrack seed 1, NanoTrack, CSRT).
Trackers
    vistrack's defaults (``vistrack.Tracker(seed=s)``, what ``vistrack run VIDEO --init X,Y,W,H``
    runs) for seeds 1..``--seeds``; OpenCV's MIL, KCF, CSRT (KCF and CSRT need
    opencv-contrib-python-headless), NanoTrack v2 (``cv2.TrackerNano`` with the ONNX weights in
    ``../shared/data/baselines/nanotrack``) and NanoTrack v3 with its authors' tracker logic
    (:class:`vistrack.baselines.nanotrack.NanoTrackV3`, ``NanoV3``), each run once (they are deterministic); a
    tracker that is missing is skipped with a note. ``--entries [model/]algo:N,...`` adds vistrack
    configurations (``box/lis:100``: the box model, the hand-crafted one, beside the default).
Cross-validation (``--candidates FILE``)
    the default model's configurations tried (``benchmarks/siam_candidates.json``; the defaults first; the box
    model's are ``box_candidates.json``, ``tune_box.py --model box``) run on every clip and seed (as
    ``tune_box.py`` runs them); for each clip the configuration best on the *other* clips is scored on it: the
    leave-one-clip-out mean, printed beside the defaults' in-sample mean.
Speed (``--speed``)
    per clip, in this one process, single-threaded, from the same decoded frames held in memory:
    vistrack (seed 1) and NanoTrack alternately, ``--reps`` times each, the fastest of each;
    tracking-only frames/s and their ratio. End to end (decoding included, vistrack's reader) against
    KCF's on the median clip.
Scores (``vistrack.scoring.metrics.box_scores``)
    success AUC (IoU thresholds 0, 0.05, .., 1), precision at 20 px, mean centre error, over frames
    with a true box.

Printed: a row per clip and tracker, the means, and issue 43's acceptance checks. ``--readme FILE``
rewrites the block between ``<!-- BEGIN real-clips`` and ``<!-- END real-clips -->``; ``--json FILE``
keeps every number. Runs are cached (``~/.cache/vistrack/corpus_runs.jsonl``, keyed by vistrack's code and
OpenCV's version), so a second table after no change of code runs only ``--speed``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import cv2
import numpy as np
from real_corpus import (
    DATA,
    NANOTRACK_V3,
    OPENCV,
    SCORE_CACHE,
    cached_scores,
    find_clips,
    load_clip,
    opencv_tracker,
    run_nanotrack_v3,
    run_opencv,
    run_vistrack,
    sre_starts,
)
from tqdm import tqdm
from tune_box import cross_validate
from tune_box import evaluate as tune_evaluate

from vistrack.data_synth.perturb import STRESS_PRESETS, perturb_clip
from vistrack.io.video import open_video
from vistrack.system.resources import keep_freed_memory

STRESS_CACHE = Path.home() / ".cache" / "vistrack" / "bench_real"
#: the configurations of the default model tried (its defaults first), for the leave-one-clip-out mean
CANDIDATES = Path(__file__).with_name("siam_candidates.json")
DEFAULT = "vistrack"
#: the trackers run from the robustness starts (issues 43 and 51 compare vistrack with these)
SRE_TRACKERS = (DEFAULT, "Nano", "CSRT", NANOTRACK_V3)
#: ``--entries``: more vistrack configurations by name (``lis-100``: ``{"algo": "lis", "particles": 100}``)
ENTRIES = {}


def parse_entries(spec):
    """``[model/]algo:N,...`` -> ``{name: Tracker options}`` (``algo:N``: the default model's)."""
    out = {}
    for e in (e.strip() for e in spec.split(",") if e.strip()):
        name, n = e.split(":")
        opts = {"algo": name.split("/")[-1], "particles": int(n)}
        if "/" in name:
            model = name.split("/")[0]
            opts.update(model=model, **({"layout": "single-row"} if model == "plate" else {}))
        out[f"{name}-{n}"] = opts
    return out


def stressed_copy(clip, stress, cache=STRESS_CACHE):
    """The folder of ``clip``'s copy under the preset ``stress`` (``vistrack synth perturb``, seed 1), made once."""
    p = STRESS_PRESETS[stress]
    p = type(p)(**{**p.__dict__, "seed": 1})
    out = Path(cache) / f"{clip.name}-{stress}"
    meta = out / "perturb.json"
    if meta.is_file():
        m = json.loads(meta.read_text())
        same = all(m.get(k) == (list(v) if isinstance(v, tuple) else v) for k, v in p.__dict__.items())
        if same and m.get("source") == str(clip.folder.resolve()):
            return out
    perturb_clip(out, clip=clip.folder, p=p)
    return out


def accuracy(clips, trackers, seeds, *, sre=False, workers=2, cache=SCORE_CACHE):
    """Rows ``{"clip", "stress", "tracker", "auc", "auc_seeds", "precision", "error", "sre"}`` (runs cached:
    :func:`real_corpus.cached_scores`)."""
    jobs, where = [], []
    for clip, stress in clips:
        for tr in trackers:
            kind, options = ("vistrack", ENTRIES.get(tr)) if tr == DEFAULT or tr in ENTRIES else (tr, None)
            if options and options.get("model") == "plate" and not clip.name.startswith("plate"):
                continue
            for s in (seeds if kind == "vistrack" else [0]):
                jobs.append((clip.folder, kind, clip.user_box, s, options))
                where.append((clip.name, stress, tr, "user"))
            if sre and tr in SRE_TRACKERS:
                for start in sre_starts(clip.user_box):
                    jobs.append((clip.folder, kind, start, 1, options))
                    where.append((clip.name, stress, tr, "sre"))
    rows = {}
    for (clip, stress, tr, kind), sc in zip(where, cached_scores(jobs, cache=cache, workers=workers,
                                                                  desc="bench_real")):
        r = rows.setdefault((clip, stress, tr), {"clip": clip, "stress": stress, "tracker": tr, "scores": [],
                                                 "sre_auc": []})
        (r["scores"] if kind == "user" else r["sre_auc"]).append(sc)
    out = []
    for r in rows.values():
        sc = np.array(r.pop("scores"))
        sre_auc = [float(s[0]) for s in r.pop("sre_auc")]
        out.append({**r, "auc": float(sc[:, 0].mean()), "auc_seeds": sc[:, 0].tolist(),
                    "precision": float(sc[:, 1].mean()), "error": float(sc[:, 2].mean()),
                    "sre": float(np.mean(sre_auc)) if sre_auc else None})
    return out


def _tracking_seconds(frames, start, tracker):
    if tracker == DEFAULT:
        return run_vistrack(frames, start, 1).seconds
    if tracker in ENTRIES:
        return run_vistrack(frames, start, 1, ENTRIES[tracker]).seconds
    return (run_nanotrack_v3(frames, start) if tracker == NANOTRACK_V3 else run_opencv(frames, start, tracker)).seconds


def speed(clips, reps=3, kcf=True):
    """Per clip ``{"clip", "frames", "vistrack_fps", "nano_fps", "ratio", "v3_fps", "ratio_v3", "entries_fps",
    "decode_s", "vistrack_e2e", "kcf_e2e"}``: tracking-only frames/s in this process, the fastest of ``reps``
    alternating runs of each (vistrack's defaults, the ``--entries``, NanoTrack v2 and v3, KCF)."""
    cv2.setNumThreads(1)
    has_nano, has_kcf = opencv_tracker("Nano") is not None, kcf and opencv_tracker("KCF") is not None
    out = []
    for clip in tqdm(clips, desc="speed", unit="clip", file=sys.stderr):
        frames = np.ascontiguousarray(clip.frames())
        n = len(frames)
        trackers = [DEFAULT, *ENTRIES] + ["Nano"] * has_nano + [NANOTRACK_V3] + ["KCF"] * has_kcf
        for tr in trackers:  # compiled kernels and networks loaded before any clock
            _tracking_seconds(frames[:5], clip.user_box, tr)
        best = dict.fromkeys(trackers, np.inf)
        for _ in range(reps):
            for tr in trackers:
                best[tr] = min(best[tr], _tracking_seconds(frames, clip.user_box, tr))
        t0 = time.perf_counter()
        for k, _ in enumerate(open_video(clip.video)):
            if k + 1 == n:
                break
        decode = time.perf_counter() - t0
        out.append({"clip": clip.name, "frames": n, "vistrack_fps": n / best[DEFAULT],
                    "nano_fps": n / best["Nano"] if has_nano else None,
                    "ratio": best["Nano"] / best[DEFAULT] if has_nano else None,
                    "v3_fps": n / best[NANOTRACK_V3], "ratio_v3": best[NANOTRACK_V3] / best[DEFAULT],
                    "entries_fps": {e: n / best[e] for e in ENTRIES}, "decode_s": decode,
                    "vistrack_e2e": n / (best[DEFAULT] + decode),
                    "kcf_e2e": n / (best["KCF"] + decode) if has_kcf else None})
    return out


def cross_validated(clips, seeds, candidates_file, workers=2):
    """``(names, scores (C, K), chosen (K,), held_out (K,))`` over the candidates of ``candidates_file``."""
    configs = json.loads(Path(candidates_file).read_text())
    cands = [("defaults", {})] + [(k, v) for k, v in configs.items() if k != "defaults"]
    res = tune_evaluate(cands, clips, seeds, workers=workers)
    scores = np.array([[np.mean(res[(n, c.name, 0)]) for c in clips] for n, _ in cands])
    chosen, held = cross_validate(scores)
    return [n for n, _ in cands], scores, chosen, held


def means(rows, key="auc"):
    """``{stress: {tracker: mean over clips}}`` for trackers with ``key`` on every clip of that stress."""
    out = {}
    for stress in dict.fromkeys(r["stress"] for r in rows):
        sub = [r for r in rows if r["stress"] == stress]
        n_clips = len({r["clip"] for r in sub})
        by = {}
        for r in sub:
            if r.get(key) is not None:
                by.setdefault(r["tracker"], []).append(r[key])
        out[stress] = {k: float(np.mean(v)) for k, v in by.items() if len(v) == n_clips}
    return out


def checks(rows, cv=None, spd=None):
    """Issue 43's acceptance checks that these numbers can decide: ``[(text, passed)]``."""
    out = []
    m, s = means(rows).get("none", {}), means(rows, "sre").get("none", {})
    v = m.get(DEFAULT)
    if v is not None and "Nano" in m:
        out.append((f"mean AUC {v:.3f} >= NanoTrack's {m['Nano']:.3f}", v >= m["Nano"]))
    if v is not None and "CSRT" in m:
        out.append((f"mean AUC {v:.3f} >= CSRT's {m['CSRT']:.3f} + 0.08", v >= m["CSRT"] + 0.08))
        get = {(r["clip"], r["tracker"]): r["auc"] for r in rows if r["stress"] == "none"}
        worse = [f"{c} {a:.3f} vs {get[(c, 'CSRT')]:.3f}" for (c, t), a in get.items()
                 if t == DEFAULT and (c, "CSRT") in get and a < get[(c, "CSRT")] - 0.10]
        out.append(("every clip >= CSRT's - 0.10" + (f" (not: {'; '.join(worse)})" if worse else ""), not worse))
    if cv is not None:
        names, scores, _, held = cv
        gap = scores[0].mean() - held.mean()
        out.append((f"leave-one-clip-out mean {held.mean():.3f} within 0.03 of the defaults' in-sample "
                    f"{scores[0].mean():.3f}", abs(gap) <= 0.03))
    if s.get(DEFAULT) is not None:
        for other in ("Nano", "CSRT"):
            if other in s:
                out.append((f"robustness starts: mean AUC {s[DEFAULT]:.3f} >= {other}'s {s[other]:.3f}",
                            s[DEFAULT] >= s[other]))
    if spd:
        ratios = [(r["clip"], r["ratio"]) for r in spd if r["ratio"] is not None]
        if ratios:
            low = [f"{c} {x:.2f}x" for c, x in ratios if x < 2]
            out.append((f"tracking frames/s >= 2x NanoTrack's on every clip (lowest {min(x for _, x in ratios):.2f}x"
                        + (f"; below 2x: {', '.join(low)}" if low else "") + ")", not low))
        kcf = sorted(r["vistrack_e2e"] / r["kcf_e2e"] for r in spd if r["kcf_e2e"])
        if kcf:
            med = float(np.median(kcf))
            out.append((f"end-to-end frames/s, median clip: {med:.2f}x KCF's", med >= 1.0))
    return out


def checks_learned(rows, cv=None, spd=None, v3=NANOTRACK_V3):
    """Issue 51's acceptance checks of the default tracker against NanoTrack v3 (authors' logic): ``[(text, ok)]``."""
    out = []
    m, s = means(rows).get("none", {}), means(rows, "sre").get("none", {})
    v = m.get(DEFAULT)
    if v is None or v3 not in m:
        return out
    out.append((f"mean AUC {v:.3f} >= NanoTrack v3's {m[v3]:.3f} + 0.03", v >= m[v3] + 0.03))
    get = {(r["clip"], r["tracker"]): r["auc"] for r in rows if r["stress"] == "none"}
    worse = [f"{c} {a:.3f} vs {get[(c, v3)]:.3f}" for (c, t), a in get.items()
             if t == DEFAULT and (c, v3) in get and a < get[(c, v3)] - 0.05]
    out.append(("every clip >= v3's - 0.05" + (f" (not: {'; '.join(worse)})" if worse else ""), not worse))
    if cv is not None:
        held = cv[3].mean()
        out.append((f"leave-one-clip-out mean {held:.3f} within 0.02 of the in-sample {v:.3f}", abs(v - held) <= 0.02))
    if s.get(DEFAULT) is not None and v3 in s:
        out.append((f"robustness starts: mean AUC {s[DEFAULT]:.3f} >= v3's {s[v3]:.3f} + 0.03",
                    s[DEFAULT] >= s[v3] + 0.03))
    if spd:
        ratios = [(r["clip"], r["ratio_v3"]) for r in spd]
        med = float(np.median([x for _, x in ratios]))
        low = [f"{c} {x:.2f}x" for c, x in ratios if x < 0.8]
        out.append((f"tracking frames/s, median clip: {med:.2f}x v3's", med >= 1.0))
        out.append((f"every clip >= 0.8x v3's (lowest {min(x for _, x in ratios):.2f}x"
                    + (f"; below: {', '.join(low)}" if low else "") + ")", not low))
    return out


def markdown(rows, seeds, command, cv=None, spd=None):
    """README's table: a row per clip (AUC from user starts, robustness starts, frames/s) and the means."""
    trackers = list(dict.fromkeys(r["tracker"] for r in rows))
    others = [t for t in trackers if t != DEFAULT]
    get = {(r["clip"], r["tracker"]): r for r in rows if r["stress"] == "none"}
    fps = {r["clip"]: r for r in spd or []}
    clips = list(dict.fromkeys(r["clip"] for r in rows))
    has_sre = any(r["sre"] is not None for r in rows)
    cv_held = dict(zip(clips, cv[3])) if cv is not None else {}
    head = (["clip", "vistrack AUC (worst seed)"] + (["left-out AUC"] if cv else [])
            + (["vistrack SRE"] if has_sre else [])
            + [f"{t} AUC" + (" (SRE)" if has_sre and t in SRE_TRACKERS else "") for t in others]
            + (["frames/s: vistrack / v3 / v2"] if spd else []))
    lines = [f"Success AUC from the start box a user types (the first ground-truth line in whole pixels), vistrack "
             f"seeds {seeds[0]}–{seeds[-1]} (worst seed in brackets), OpenCV {cv2.__version__}'s trackers once"
             + ("; SRE: the mean over OTB's 12 robustness starts" if has_sre else "")
             + ("; left-out AUC: the configuration chosen on the other clips (leave-one-clip-out), scored on this one"
                if cv else "")
             + ("; tracking-only frames/s, one process, single-threaded" if spd else "") + f". From `{command}`.",
             "", "| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for c in clips:
        r = get.get((c, DEFAULT))
        if r is None:
            continue
        cells = [c, f"{r['auc']:.3f} ({min(r['auc_seeds']):.3f})"]
        cells += [f"{cv_held[c]:.3f}"] if cv else []
        cells += [f"{r['sre']:.3f}"] if has_sre else []
        for t in others:
            o = get.get((c, t))
            sre = f" ({o['sre']:.3f})" if o is not None and o["sre"] is not None else ""
            cells.append("–" if o is None else f"{o['auc']:.3f}{sre}")
        if spd:
            f = fps.get(c)
            cells.append(f"{f['vistrack_fps']:.0f} / {f['v3_fps']:.0f} / " + (f"{f['nano_fps']:.0f}" if f["nano_fps"]
                                                                                  else "–") if f else "–")
        lines.append("| " + " | ".join(cells) + " |")
    m, s = means(rows).get("none", {}), means(rows, "sre").get("none", {})
    cells = ["**mean**", f"**{m.get(DEFAULT, float('nan')):.3f}**"]
    cells += [f"{cv[3].mean():.3f}"] if cv else []
    cells += [f"{s.get(DEFAULT, float('nan')):.3f}"] if has_sre else []
    cells += [f"{m[t]:.3f}" + (f" ({s[t]:.3f})" if t in s else "") if t in m else "–" for t in others]
    cells += [""] if spd else []
    lines.append("| " + " | ".join(cells) + " |")
    stressed = [st for st in means(rows) if st != "none"]
    if stressed:
        ms = means(rows)
        lines += ["", "Mean success AUC over the same clips' stressed copies (`vistrack synth perturb`, seed 1):", "",
                  "| stress | " + " | ".join([DEFAULT, *others]) + " |", "|---|" + "---|" * (1 + len(others))]
        for st in ["none", *stressed]:
            lines.append(f"| {'original' if st == 'none' else st} | "
                         + " | ".join(f"{ms[st][t]:.3f}" if t in ms[st] else "–" for t in [DEFAULT, *others]) + " |")
    return "\n".join(lines) + "\n"


def update_readme(path, table, command):
    """Rewrite ``path``'s real-clips block with ``table``, its first line naming ``command``."""
    text = Path(path).read_text()
    begin = text.find("<!-- BEGIN real-clips")
    end = text.find("<!-- END real-clips -->")
    if begin < 0 or end < begin:
        sys.exit(f"{path} has no <!-- BEGIN real-clips ... --> ... <!-- END real-clips --> block")
    Path(path).write_text(text[:begin] + f"<!-- BEGIN real-clips: {command} -->\n" + table + text[end:])


def print_report(rows, cv, spd):
    print(f"{'clip':<26} {'stress':<7} {'tracker':<9} {'AUC':>6} {'worst':>6} {'P@20':>6} {'err px':>7} {'SRE':>6}")
    for r in rows:
        sre = f"{r['sre']:.3f}" if r["sre"] is not None else "–"
        print(f"{r['clip']:<26} {r['stress']:<7} {r['tracker']:<9} {r['auc']:>6.3f} {min(r['auc_seeds']):>6.3f} "
              f"{r['precision']:>6.3f} {r['error']:>7.1f} {sre:>6}")
    for stress, by in means(rows).items():
        print(f"mean AUC over clips, {stress}: " + ", ".join(f"{k} {v:.3f}" for k, v in by.items()))
    for stress, by in means(rows, "sre").items():
        if by:
            print(f"mean AUC over the robustness starts, {stress}: "
                  + ", ".join(f"{k} {v:.3f}" for k, v in by.items()))
    if cv is not None:
        names, scores, chosen, held = cv
        print(f"cross-validation over {len(names)} configurations ({', '.join(names)}): defaults in-sample "
              f"{scores[0].mean():.3f}, leave-one-clip-out {held.mean():.3f}; chosen per clip: "
              + ", ".join(f"{names[k]}" for k in chosen))
    for r in spd or []:
        nano = f"NanoTrack {r['nano_fps']:.0f}, ratio {r['ratio']:.2f}x" if r["nano_fps"] else "no NanoTrack"
        kcf = f", e2e {r['vistrack_e2e']:.0f} vs KCF {r['kcf_e2e']:.0f}" if r["kcf_e2e"] else ""
        print(f"speed {r['clip']:<26} vistrack {r['vistrack_fps']:.0f} frames/s, v3 {r['v3_fps']:.0f} "
              f"({r['ratio_v3']:.2f}x), {nano}{kcf}"
              + "".join(f", {e} {f:.0f}" for e, f in r["entries_fps"].items()))
    print("issue 43 checks:")
    for text, ok in checks(rows, cv, spd):
        print(f"  [{'ok' if ok else 'NO'}] {text}")
    print("issue 51 checks (against NanoTrack v3, authors' logic):")
    for text, ok in checks_learned(rows, cv, spd):
        print(f"  [{'ok' if ok else 'NO'}] {text}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    ap.add_argument("--seeds", type=int, default=3, help="vistrack seeds 1..SEEDS (default 3)")
    ap.add_argument("--sre", action="store_true", help="also OTB's 12 robustness starts (mean AUC per clip)")
    ap.add_argument("--speed", action="store_true", help="tracking frames/s against NanoTrack's, e2e against KCF's")
    ap.add_argument("--reps", type=int, default=3, help="--speed: runs of each tracker per clip, the fastest kept")
    ap.add_argument("--candidates", default=str(CANDIDATES),
                    help="the box configurations tried, for the leave-one-clip-out mean ('' none)")
    ap.add_argument("--entries", default="", help="more vistrack configurations beside the defaults: "
                    "[model/]algo:N, e.g. bootstrap:100,rb-ss-hs-sir:400")
    ap.add_argument("--opencv", default=",".join(OPENCV), help="OpenCV's trackers beside vistrack")
    ap.add_argument("--stress", default="",
                    help=f"stressed copies too, comma-separated, of {', '.join(STRESS_PRESETS)}")
    ap.add_argument("--clips", default="", help="clip folder names (default: every one with ground truth)")
    ap.add_argument("--data", default=str(DATA))
    ap.add_argument("--workers", type=int, default=2, help="processes for the accuracy runs")
    ap.add_argument("--reuse", default=None, help="take the accuracy rows and the cross-validation from this "
                    "earlier --json (the same code's tracks) and run only --speed")
    ap.add_argument("--json", default=None, help="write every number here")
    ap.add_argument("--readme", default=None, help="rewrite this file's real-clips block with the table")
    args = ap.parse_args()
    stresses = [s for s in args.stress.split(",") if s]
    bad = [s for s in stresses if s not in STRESS_PRESETS]
    if bad:
        sys.exit(f"unknown stress {', '.join(bad)}: choose from {', '.join(STRESS_PRESETS)}")
    clips = find_clips(args.data, [c for c in args.clips.split(",") if c] or None)
    if not clips:
        sys.exit(f"no clip with groundtruth_rect.txt under {args.data}")
    wanted = [c for c in args.opencv.split(",") if c]
    cvs = [c for c in wanted if opencv_tracker(c) is not None]
    if len(cvs) < len(wanted):
        print(f"skipped, not in this OpenCV ({cv2.__version__}) or without weights: "
              f"{', '.join(sorted(set(wanted) - set(cvs)))} (KCF, CSRT: opencv-contrib-python-headless; "
              "Nano: ../shared/data/baselines/nanotrack)")
    seeds = list(range(1, args.seeds + 1))
    variants = [(c, "none") for c in clips] + [(load_clip(stressed_copy(c, s)), s) for s in stresses for c in clips]
    ENTRIES.update(parse_entries(args.entries))
    if args.reuse:
        old = json.loads(Path(args.reuse).read_text())
        rows, c = old["rows"], old["cross_validation"]
        cv = None if c is None else (c["configurations"], np.array(c["scores"]),
                                     np.array([c["configurations"].index(n) for n in c["chosen"]]),
                                     np.array(c["held_out"]))
    else:
        rows = accuracy(variants, [DEFAULT, *ENTRIES, NANOTRACK_V3, *cvs], seeds, sre=args.sre, workers=args.workers)
        cv = cross_validated(clips, seeds, args.candidates, args.workers) if args.candidates else None
    spd = speed(clips, args.reps) if args.speed else None
    print_report(rows, cv, spd)
    command = "python benchmarks/bench_real.py " + " ".join(sys.argv[1:])
    if args.json:
        Path(args.json).write_text(json.dumps({
            "command": command, "seeds": seeds, "opencv": cv2.__version__, "rows": rows, "speed": spd,
            "cross_validation": None if cv is None else {
                "configurations": cv[0], "scores": cv[1].tolist(), "chosen": [cv[0][k] for k in cv[2]],
                "held_out": cv[3].tolist()}}, indent=1))
    if args.readme:
        flags = (f"--seeds {args.seeds}" + " --sre" * args.sre + " --speed" * args.speed
                 + (f" --entries {args.entries}" if args.entries else ""))
        command = f"python benchmarks/bench_real.py {flags}"
        update_readme(args.readme, markdown(rows, seeds, command, cv, spd), f"{command} --readme {args.readme}")


if __name__ == "__main__":
    keep_freed_memory()
    main()
