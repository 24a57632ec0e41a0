"""Landmark shape tracking speed (seed 000), side by side in one process.

Part 1, simulation (§4): ms per step of each algorithm at the paper's K and N,
rounds interleaved so that machine noise hits all alike; ratio to PF-Gordon.
Part 2, video: one 640x480 synthetic landmark clip, decoded once; ms per frame
split into feature maps + blob detection + association (``observe``) and the
filter step.

    python benchmarks/bench_landmarks.py [--rounds 5]
"""

import argparse
import tempfile
import time
import warnings

import numpy as np

from vistrack.appearance.features import FeatureMaps
from vistrack.core.particles import ParticleSet
from vistrack.data_synth.landmark_clip import make_landmark_clip, simulate
from vistrack.io.clips import load_clip
from vistrack.registry import make_filter
from vistrack.registry.builders import build_model
from vistrack.reproduce.landmarks import LandmarksConfig
from vistrack.system.resources import keep_freed_memory


def sim_part(rounds):
    print(f"{'K':>2} {'algo':<10} {'N':>4} {'ms/step':>8} {'x pf-gordon':>11}")
    for k in (5, 8):
        cfg = LandmarksConfig(k=k)
        model = cfg.model()
        _, obs = simulate(model, 40, np.random.default_rng(0))
        algos = ["pf-gordon", "pf-doucet", "pf-eis", "pf-eis-mt"]
        times = {a: [] for a in algos}
        for r in range(rounds):
            for a in algos:
                filt = make_filter(a, model, **({"mt_dims": cfg.mt_dims} if a == "pf-eis-mt" else {}))
                p = ParticleSet(model.sample_prior(cfg.particles, None))
                rng = np.random.default_rng(r)
                t0 = time.perf_counter()
                for y in obs:
                    p = filt.step(p, y, rng)
                times[a].append((time.perf_counter() - t0) * 1e3 / len(obs))
        base = np.median(times["pf-gordon"])
        for a in algos:
            m = float(np.median(times[a]))
            print(f"{k:>2} {a:<10} {cfg.particles:>4} {m:>8.3f} {m / base:>11.1f}")


def video_part(rounds):
    with tempfile.TemporaryDirectory() as d:
        make_landmark_clip(d, frames=100, seed=1)
        clip = load_clip(d)
        frames = [f for _, f in clip.source]
        model = build_model("landmarks", clip)
    print(f"\n640x480 clip, {len(frames)} frames: ms per frame")
    print(f"{'algo':<10} {'N':>4} {'observe':>8} {'filter':>8} {'total':>8} {'frames/s':>9}")
    for algo, n in [("pf-eis-mt", 100), ("pf-eis", 100), ("pf-doucet", 100), ("pf-gordon", 100)]:
        obs_t, filt_t = [], []
        for r in range(rounds):
            filt = make_filter(algo, model)
            rng = np.random.default_rng(r)
            p, buffers, t_obs, t_filt = None, {}, 0.0, 0.0
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                for f in frames:
                    t0 = time.perf_counter()
                    y = model.observe(FeatureMaps(f, buffers=buffers), p)
                    t1 = time.perf_counter()
                    p = filt.first_step(y, n, rng) if p is None else filt.step(p, y, rng)
                    t2 = time.perf_counter()
                    t_obs += t1 - t0
                    t_filt += t2 - t1
            obs_t.append(t_obs * 1e3 / len(frames))
            filt_t.append(t_filt * 1e3 / len(frames))
        o, fl = float(np.median(obs_t)), float(np.median(filt_t))
        print(f"{algo:<10} {n:>4} {o:>8.2f} {fl:>8.2f} {o + fl:>8.2f} {1e3 / (o + fl):>9.0f}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=5)
    args = ap.parse_args()
    sim_part(args.rounds)
    video_part(max(1, args.rounds // 2))


if __name__ == "__main__":
    keep_freed_memory()  # as the CLI does
    main()
