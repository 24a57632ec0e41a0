"""Diagnostics of the history-sampling experiment (issue 23, thesis §3.2.5) on colour contour clips.

    python benchmarks/hs_sir_diag.py proposal CLIP             # blob proposal: draws vs its density
    python benchmarks/hs_sir_diag.py onestep CLIP              # one step of the family + bootstrap
    python benchmarks/hs_sir_diag.py edges CLIP [CLIP ...]     # edge features at the true pose
    python benchmarks/hs_sir_diag.py frames CLIP ALGO:N,... [--seeds 2] [--frames 60] [--likelihood K=V,..]

``CLIP``: a clip of ``vistrack reproduce hs-sir`` (``hs-sir-clips/contour-color-01``). ``frames``
prints, per run, over the frames not lost (error <= 50 px): the mean and median error of the
weighted mean, the distance of the particle nearest to the truth, the share of particles
within 3 px of it, the mean ESS, the distinct histories in the set, and how far the likelihood
at the best particle lies under the best pose within 4 px of the truth (negative: the
likelihood prefers a pose away from the truth).
"""

import argparse

import numpy as np

from vistrack.appearance.features import FeatureMaps
from vistrack.core.particles import ParticleSet
from vistrack.io.clips import load_clip
from vistrack.loop import Stepper
from vistrack.models.contour.spline import edge_peaks, pose_from
from vistrack.registry import make_filter
from vistrack.registry.builders import build_model
from vistrack.reproduce.history_sampling import likelihood_params


def true_pose(t, i):
    return np.asarray(pose_from(t["cx"][i], t["cy"][i], t["scale"][i], t["angle_deg"][i]), float)


def frame_obs(clip, model, k):
    frame = next(f for i, f in clip.source if i == k)
    return model.observe(FeatureMaps(frame), None)


def proposal(args):
    """2e6 draws of the blob proposal on frame 20, binned at 1 px, against its density."""
    clip = load_clip(args.clip[0])
    model = build_model("contour", clip, init_gt="")
    obs, prop = frame_obs(clip, model, 20), model.innovation_proposal()
    x = prop.sample(2_000_000, obs, np.random.default_rng(0))
    w, h = clip.source.size
    ex, ey = np.arange(-6, w + 7), np.arange(-6, h + 7)
    hist = np.histogram2d(x[:, 0], x[:, 1], bins=[ex, ey])[0] / len(x)
    sub = (np.arange(4) + 0.5) / 4
    gx, gy = np.meshgrid((ex[:-1, None] + sub).ravel(), (ey[:-1, None] + sub).ravel(), indexing="ij")
    dens = np.exp(prop.logpdf(np.stack([gx.ravel(), gy.ravel()], 1), obs))
    dens = dens.reshape(len(ex) - 1, 4, len(ey) - 1, 4).mean(axis=(1, 3))
    big = dens > 1e-5
    z = (hist[big] - dens[big]) / np.sqrt(dens[big] / len(x))
    print(f"integral {dens.sum():.6f}; bins {big.sum()}: chi2/dof {np.mean(z ** 2):.3f}, max |z| {np.abs(z).max():.2f}")


def onestep(args):
    """One step from the same diverse weighted set (frame 19 -> 20): weighted E[pose] per filter."""
    clip = load_clip(args.clip[0])
    t, model = clip.truth, build_model("contour", clip, init_gt="")
    obs, rng, n = frame_obs(clip, model, 20), np.random.default_rng(1), 3000
    s = np.array([3, 3, .02, .02])
    z1 = true_pose(t, 19) + s * rng.standard_normal((n, 4))
    z2 = z1 - (true_pose(t, 19) - true_pose(t, 18)) + s * rng.standard_normal((n, 4))
    prev = ParticleSet(np.concatenate([z1, z2], 1), rng.standard_normal(n))
    print("truth", np.round(true_pose(t, 20), 4))
    for algo in ["basic-sir", "rb-ss-hs-sir", "rb-hs-sir", "hs-sir", "bootstrap"]:
        est = []
        for rep in range(12):
            r = np.random.default_rng(100 + rep)
            if algo == "bootstrap":  # ten draws of K per particle, w = w_prev r
                new = model.predict(np.repeat(prev.states, 10, axis=0), r)
                lw = np.repeat(prev.log_weights, 10) + model.loglik(obs, new)
            else:
                f = make_filter(algo, model)
                new, lw, _ = f.sample(f.histories(prev, r, f.kernel), obs, r, f.kernel)
            w = np.exp(lw - lw.max())
            est.append(w @ new[:, :4] / w.sum())
        m, se = np.mean(est, 0), np.std(est, 0, ddof=1) / np.sqrt(len(est))
        print(f"{algo:13s}", " ".join(f"{a:9.4f}±{b:.4f}" for a, b in zip(m, se)))


def edges(args):
    """Edge features along the measurement lines of the true contour, every third frame."""
    off = np.arange(-20, 20.01, 0.5)
    res, missing, far, lines = [], 0, 0, 0
    for c in args.clip:
        clip = load_clip(c)
        model = build_model("contour", clip, init_gt="")
        for i, fr in clip.source:
            if i % 3:
                continue
            obs = model.observe(FeatureMaps(fr), None)
            peaks = edge_peaks(model.edge_profiles(obs, true_pose(clip.truth, i)[None], off)[0],
                               model.feature_threshold(obs))
            for p in peaks:
                pos = off[p]
                near = pos[np.abs(pos) <= 6]
                lines += 1
                missing += not len(near)
                res += [near[np.argmin(np.abs(near))]] if len(near) else []
                far += np.sum(pos >= 8)
    r = np.abs(res)
    print(f"lines {lines}: no edge within 6 px {missing / lines:.3f}; nearest edge within 1 px {np.mean(r <= 1):.3f}, "
          f"residual std {np.std(res):.2f} px; features per px 8-20 px outside {far / lines / 12:.4f}")


def frames(args):
    """Per-frame diagnostics of tracking runs (module docstring)."""
    clip = load_clip(args.clip[0])
    t, params = clip.truth, likelihood_params(args.likelihood)
    fr = list(clip.source)[:args.frames]
    gx, gy = np.meshgrid(np.arange(-4, 4.01, 0.5), np.arange(-4, 4.01, 0.5))
    for entry in args.entries.split(","):
        algo, n = entry.split(":")
        for seed in range(args.seeds):
            model = build_model("contour", clip, init_gt="", **params)
            rows = []
            for r in Stepper(make_filter(algo, model), int(n), np.random.default_rng(seed)).steps(fr):
                z, p = true_pose(t, r.index), r.particles
                d = np.hypot(p.states[:, 0] - z[0], p.states[:, 1] - z[1])
                grid = np.tile(np.concatenate([z, z]), (gx.size, 1))
                grid[:, 0] += gx.ravel()
                grid[:, 1] += gy.ravel()
                best = p.states[np.argmax(p.log_weights)][None]
                gap = model.loglik(r.obs, grid).max() - model.loglik(r.obs, best)[0]
                rows.append([np.hypot(*(r.estimate[:2] - z[:2])), d.min(), np.mean(d < 3), r.ess,
                             len(np.unique(p.states[:, 4])), gap])
            a = np.array(rows)
            ok = a[:, 0] <= 50
            print(f"{algo:13s} N={n:5s} seed {seed}: lost {1 - ok.mean():.2f}; error {a[ok, 0].mean():5.2f} "
                  f"(median {np.median(a[ok, 0]):5.2f}), nearest {a[ok, 1].mean():4.2f} px, within 3 px "
                  f"{a[ok, 2].mean():.3f}, ESS {a[ok, 3].mean():4.1f}, histories {a[ok, 4].mean():5.1f}, "
                  f"log r gap {np.median(a[ok, 5]):5.1f}", flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("what", choices=["proposal", "onestep", "edges", "frames"])
    ap.add_argument("clip", nargs="+")
    ap.add_argument("--entries", default="basic-sir:3000,rb-ss-hs-sir:3000,basic-sir:400,rb-ss-hs-sir:400")
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument("--frames", type=int, default=60)
    ap.add_argument("--likelihood", default="")
    args = ap.parse_args()
    if args.what == "frames" and len(args.clip) > 1:  # "frames CLIP ALGO:N,..." positional form
        args.clip, args.entries = args.clip[:1], args.clip[1]
    globals()[args.what](args)


if __name__ == "__main__":
    main()
