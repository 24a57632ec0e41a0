"""Bearings-only, one ship: vistrack's filters beside the `particles` library's (N. Chopin) on the
same sequences, in one process.

`particles` is an optional benchmark dependency (``pip install "vistrack[peers]"``, or
``pip install --no-deps particles`` where its ``numpy<2`` pin would downgrade numpy). The model
(thesis §4.5.5: the dynamics, the wrapped-Cauchy bearing, the prior) is written once for
`particles` below, with the same numpy expressions as vistrack's; `particles` draws from
``np.random``, seeded per run.

Filters: vistrack's ``lis`` (the ξ proposal with its first stage, the default), its §4.5.5
position move, its bootstrap; `particles`' ``Bootstrap`` and ``GuidedPF`` with two proposals:
``lin``, the textbook guided proposal (the bearing linearised at the predicted position, the
wrapped Cauchy replaced by its L2 Gaussian fit: a Gaussian proposal in closed form), and ``xi``,
vistrack's ξ move without the first stage. `particles` resamples when ESS < N/2 (its
default), vistrack every step. Each `particles` filter runs at the N that makes its time per run
match vistrack's ``lis`` (a short interleaved calibration, then checked on the full run: the ratio
is printed); ``--fixed`` adds `particles`' filters at N = 3000.

    python benchmarks/bench_bearings_peers.py [--seeds 0,1,2,3,4] [--sequences 10] [--runs 20]

The sequences and run streams are ``vistrack reproduce bearings --seed S``'s. Errors are the
final-step position errors of the weighted mean; ms per 10-step run are CPU time of this process
(``time.process_time``: on a shared machine, wall time also counts the other processes' turns).
"""

import argparse
import time
import warnings

import numpy as np

from vistrack.core.gaussian import diag_logpdf
from vistrack.core.transition import PriorKernel
from vistrack.filters import filter_steps
from vistrack.models.bearings.model import Bearings, simulate, wrapped_cauchy_logpdf
from vistrack.models.bearings.xi import XiProposal
from vistrack.registry import make_filter

try:
    import particles
    from particles import distributions as dists
    from particles import state_space_models as ssms
except ImportError:  # pragma: no cover - the benchmark says what to install
    particles = None

MODEL = Bearings(1)
SIG = MODEL.sigma_eta


def _np_rng():
    """A Generator drawn from ``np.random`` (`particles`' seeded global state)."""
    return np.random.default_rng(np.random.randint(2**62))


class _Prior(dists.ProbDist if particles else object):
    dim = 4

    def rvs(self, size=None):
        return MODEL.prior_mean + MODEL.prior_std * np.random.standard_normal((size, 4))

    def logpdf(self, x):
        return MODEL.prior_logpdf(x)


class _Kernel(dists.ProbDist if particles else object):
    """``K(.|xp)``; ``logpdf`` is the density of the noise ξ (on the support of K)."""

    dim = 4

    def __init__(self, xp):
        self.xp = xp

    def rvs(self, size=None):
        xi = SIG * np.random.standard_normal((len(self.xp), 2))
        return MODEL.predict_mean(self.xp) + xi @ np.array([[0.5, 1, 0, 0], [0, 0, 0.5, 1]])

    def logpdf(self, x):
        return MODEL.transition_logpdf(x, self.xp)


class _Bearing(dists.ProbDist if particles else object):
    """The wrapped-Cauchy bearing of the states ``x``."""

    def __init__(self, x):
        self.x = x

    def logpdf(self, y):
        return wrapped_cauchy_logpdf(y[0] - np.arctan2(self.x[:, 2], self.x[:, 0]), MODEL.one_minus_rho)


class _Linearised(dists.ProbDist if particles else object):
    """Guided proposal: the position's Gaussian posterior with the bearing linearised at the
    prior position mean ``p`` (``(K, 2)``, ``K`` 1 or N; variances ``s2 (2,)``), the wrapped Cauchy
    replaced by its L2 Gaussian fit. Velocities follow the position (``xp`` given: ``Δv = 2 Δp``,
    on the support of K) or are prior draws (first step)."""

    dim = 4

    def __init__(self, p, s2, y, xp=None):
        self.p, self.xp = p, xp
        r2 = np.sum(p * p, axis=1)
        h0, h1 = -p[:, 1] / r2, p[:, 0] / r2  # d bearing / d (x1, x3)
        e = np.angle(np.exp(1j * (y[0] - np.arctan2(p[:, 1], p[:, 0]))))
        sh0, sh1 = s2[0] * h0, s2[1] * h1
        den = h0 * sh0 + h1 * sh1 + MODEL.sigma_angle**2
        k0, k1 = sh0 / den, sh1 / den
        self.m0, self.m1 = p[:, 0] + k0 * e, p[:, 1] + k1 * e
        self.c00, self.c01, self.c11 = s2[0] - k0 * sh0, -k0 * sh1, s2[1] - k1 * sh1
        self.det = self.c00 * self.c11 - self.c01**2

    def rvs(self, size=None):
        z = np.random.standard_normal((2, size))
        l00 = np.sqrt(self.c00)
        l10 = self.c01 / l00
        pos0, pos1 = self.m0 + l00 * z[0], self.m1 + l10 * z[0] + np.sqrt(self.c11 - l10**2) * z[1]
        x = _Prior().rvs(size) if self.xp is None else MODEL.predict_mean(self.xp)
        if self.xp is not None:
            x[:, 1] += 2 * (pos0 - x[:, 0])
            x[:, 3] += 2 * (pos1 - x[:, 2])
        x[:, 0], x[:, 2] = pos0, pos1
        return x

    def logpdf(self, x):
        d0, d1 = x[:, 0] - self.m0, x[:, 2] - self.m1
        quad = (self.c11 * d0 * d0 - 2 * self.c01 * d0 * d1 + self.c00 * d1 * d1) / self.det
        log_pos = -0.5 * quad - 0.5 * np.log(self.det) - np.log(2 * np.pi)
        if self.xp is None:  # times the prior of the velocities
            return log_pos + diag_logpdf(x[:, [1, 3]], MODEL.prior_mean[[1, 3]], MODEL.prior_std[[1, 3]])
        return log_pos - np.log(4.0)  # the density of ξ = 2 (pos - p)


class _Xi(dists.ProbDist if particles else object):
    """vistrack's ξ move (:class:`~vistrack.models.bearings.xi.XiProposal`) as a `particles` proposal;
    ``logpdf`` on the measure of ``PX`` (the noise ξ under K, the state under ``p_0``)."""

    dim = 4

    def __init__(self, y, xp=None):
        self.y, self.xp = y, xp
        self.prop = XiProposal(MODEL, PriorKernel(MODEL) if xp is None else None)

    def rvs(self, size=None):
        rng = _np_rng()
        x = MODEL.sample_prior(size, rng) if self.xp is None else MODEL.predict(self.xp, rng)
        return self.prop.sample(x, self.y, rng, self.xp)[0]

    def logpdf(self, x):
        _, _, a, u, m, s = self.prop.frame(x, self.y, self.xp)
        log_pi = self.prop.logpdf(x, x, self.y, self.xp)
        cond = -0.5 * ((u - m) / s) ** 2 - np.log(s) - 0.5 * np.log(2 * np.pi)
        if self.xp is None:  # p_0 with its across-ray conditional replaced by π
            return MODEL.prior_logpdf(x) - cond[:, 0] + log_pi
        xi = (x - MODEL.predict_mean(self.xp))[:, [1, 3]]
        along = xi @ np.array([np.cos(self.y[0]), np.sin(self.y[0])])
        return -0.5 * (along / SIG) ** 2 - np.log(SIG) - 0.5 * np.log(2 * np.pi) + log_pi - np.log(2.0)


if particles:

    class PeerBearings(ssms.StateSpaceModel):
        """The one-ship bearings model for `particles`, with the two guided proposals."""

        default_params = {"guide": "lin"}

        def PX0(self):
            return _Prior()

        def PX(self, t, xp):
            return _Kernel(xp)

        def PY(self, t, xp, x):
            return _Bearing(x)

        def proposal0(self, data):
            if self.guide == "xi":
                return _Xi(data[0])
            return _Linearised(MODEL.prior_mean[None, [0, 2]], MODEL.prior_std[[0, 2]] ** 2, data[0])

        def proposal(self, t, xp, data):
            if self.guide == "xi":
                return _Xi(data[t], xp)
            return _Linearised(MODEL.predict_mean(xp)[:, [0, 2]], np.full(2, (0.5 * SIG) ** 2), data[t], xp)


def run_peer(kind, obs, n, seed):
    """One `particles` run (``np.random`` seeded from the SeedSequence ``seed``): the final-step
    weighted mean ``(4,)``."""
    np.random.seed(seed.generate_state(1)[0])
    if kind == "bootstrap":
        fk = ssms.Bootstrap(ssm=PeerBearings(), data=obs)
    else:
        fk = ssms.GuidedPF(ssm=PeerBearings(guide=kind), data=obs)
    pf = particles.SMC(fk=fk, N=n, collect="off")
    pf.run()
    return pf.W @ pf.X


def run_ours(filt, obs, n, seed):
    """One vistrack run: final-step weighted mean ``(4,)``."""
    for p in filter_steps(filt, obs, n, np.random.default_rng(seed)):
        pass
    return p.mean()


def sequences(seeds, n_seq, runs, steps=10):
    """``(truth, obs, run seeds)`` per sequence, as ``vistrack reproduce bearings --seed S``."""
    out = []
    for seed in seeds:
        seq_ss, run_ss = np.random.SeedSequence(seed).spawn(2)
        seqs, run_seeds = seq_ss.spawn(n_seq), run_ss.spawn(n_seq * runs)
        for s in range(n_seq):
            truth, obs = simulate(MODEL, steps, np.random.default_rng(seqs[s]))
            out.append((seed, truth, obs, run_seeds[s * runs:(s + 1) * runs]))
    return out


def configs(n_ours):
    """vistrack's filters: ``name -> run(obs, seed)`` with their N."""
    lis, pos = make_filter("lis", MODEL), make_filter("lis", Bearings(1, proposal="position"))
    boot = make_filter("bootstrap", MODEL)
    return {
        ("vistrack", "lis (xi)", n_ours): lambda obs, sd: run_ours(lis, obs, n_ours, sd),
        ("vistrack", "lis (position)", n_ours): lambda obs, sd: run_ours(pos, obs, n_ours, sd),
        ("vistrack", "bootstrap", 3000): lambda obs, sd: run_ours(boot, obs, 3000, sd),
    }


def peer(kind, n):
    """`particles`' filter ``kind`` at ``n``: ``key -> run(obs, seed)``."""
    name = {"bootstrap": "Bootstrap", "lin": "GuidedPF (linearised)", "xi": "GuidedPF (xi)"}[kind]
    return {("particles", name, n): lambda obs, sd: run_peer(kind, obs, n, sd)}


def timed(runs, data, reps):
    """Interleaved over ``data`` (at most ``reps`` runs per sequence): ``key -> (final errors, ms/run)``."""
    err = {k: [] for k in runs}
    sec = dict.fromkeys(runs, 0.0)
    for _, truth, obs, seeds in data:
        for sd in seeds[:reps]:
            for k, run in runs.items():  # interleaved: machine noise hits every filter alike
                t0 = time.process_time()
                mean = run(obs, sd)
                sec[k] += time.process_time() - t0
                err[k].append(float(MODEL.position_error(mean, truth[-1])[0]))
    return {k: (np.array(err[k]), 1e3 * sec[k] / len(err[k])) for k in runs}


def matched_n(kind, lis, data, rounds=4):
    """The N at which `particles`' ``kind`` takes as long per run as vistrack's ``lis`` (``key ->
    run``): time ratios measured interleaved with it, a line through the two latest (N, ratio)
    points solved for ratio 1, ``rounds`` times; at least 10."""
    def ratio(n):
        res = timed({**lis, **peer(kind, n)}, data[:3], 6)
        t = [v[1] for v in res.values()]
        return t[1] / t[0]

    pts = [(300, ratio(300)), (3000, ratio(3000))]
    for _ in range(rounds):
        (n1, r1), (n2, r2) = pts[-2:]
        n = max(10, int(round(n1 + (1.0 - r1) * (n2 - n1) / (r2 - r1), -1)))
        if n == pts[-1][0]:
            break
        pts.append((n, ratio(n)))
    return min(pts, key=lambda p: abs(p[1] - 1.0))[0]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="0,1,2,3,4")
    ap.add_argument("--sequences", type=int, default=10)
    ap.add_argument("--runs", type=int, default=20)
    ap.add_argument("--n", type=int, default=100, help="vistrack's lis particles (the time to match)")
    ap.add_argument("--peer-n", default=None, help="N for particles' bootstrap,lin,xi (default: matched)")
    ap.add_argument("--fixed", action="store_true", help="also particles' filters at N = 3000")
    args = ap.parse_args()
    if particles is None:
        raise SystemExit("Error: this benchmark needs the particles library: pip install --no-deps particles "
                         "(or 'vistrack[peers]', which pins numpy<2)")
    warnings.simplefilter("ignore")
    data = sequences([int(s) for s in args.seeds.split(",")], args.sequences, args.runs)
    ours = configs(args.n)
    timed({**ours, **peer("bootstrap", 100), **peer("lin", 100), **peer("xi", 100)}, data[:1], 2)  # warm up
    kinds = ("bootstrap", "lin", "xi")
    if args.peer_n:
        ns = [int(v) for v in args.peer_n.split(",")]
    else:
        lis = {k: v for k, v in ours.items() if k[1] == "lis (xi)"}
        ns = [matched_n(kind, lis, data) for kind in kinds]
        print("matched N (bootstrap, lin, xi):", ",".join(map(str, ns)), flush=True)
    runs = dict(ours)
    for kind, n in zip(kinds, ns):
        runs.update(peer(kind, n))
        if args.fixed and n != 3000:
            runs.update(peer(kind, 3000))
    res = timed(runs, data, args.runs)
    report(res, data, args)


def report(res, data, args):
    """The table: final-step error overall (± its standard error) and per seed, ms per run, and the
    time per run relative to vistrack's lis."""
    seeds = [d[0] for d in data for _ in d[3][:args.runs]]
    ref = next(v[1] for k, v in res.items() if k[1] == "lis (xi)")
    useeds = sorted(set(seeds))
    print(f"bearings-only, 1 ship: seeds {args.seeds}, {args.sequences} sequences x {args.runs} runs each")
    head = f"{'library':<9} {'filter':<22} {'N':>5} {'final err':>9} {'± se':>7} {'ms/run':>7} {'time/lis':>8}"
    print(head + "".join(f" {'seed ' + str(s):>8}" for s in useeds))
    for (lib, name, n), (e, ms) in res.items():
        per = [e[np.array(seeds) == s].mean() for s in useeds]
        print(f"{lib:<9} {name:<22} {n:>5} {e.mean():>9.5f} {e.std(ddof=1) / np.sqrt(len(e)):>7.5f} {ms:>7.2f} "
              f"{ms / ref:>8.2f}" + "".join(f" {p:>8.5f}" for p in per))


if __name__ == "__main__":
    main()
