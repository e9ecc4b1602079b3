#!/usr/bin/env python3
"""Peer comparison (issue 14): pymoo's algorithms driving the same evaluator as the built-in
`sawtooth optimize`, at equal numbers of evaluations, several seeds, lunar physical mode.

Every optimiser solves the same problem (sawtooth.pymoo.SawtoothProblem is the built-in
optimiser's problem: variables, bounds, objectives with their penalties, constraints with
MATLAB's tolerance, common random numbers refreshed per generation with the same seed rule)
with the same particles per design. Each run's final non-dominated designs (built-in: rank 0 of
the final population in checkpoint.json, exact values; pymoo: res.X) are re-evaluated with
--final-particles particles on --final-streams fresh streams that no optimiser saw; the
objectives are averaged over the streams and the hypervolume of the feasible non-dominated
re-evaluated points is taken w.r.t. (2 Hz, 20 000 J/kg), the reference of the built-in
optimiser's generations.csv. Wall time is the optimisation alone (built-in: the CLI process,
whose own final re-evaluation is cut to 1 x 100 particles).

Usage (from the repository root, the package installed as README's Python section says):
    python scripts/peer_pymoo.py --pop 100 --generations 30 --seeds 0,1,2,3,4 --out runs/peer
Writes OUT/results.json (every run) and OUT/summary.md (the table for BENCHMARKS.md).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from pymoo.algorithms.moo.nsga2 import NSGA2
from pymoo.algorithms.moo.sms import SMSEMOA
from pymoo.indicators.hv import HV
from pymoo.optimize import minimize
from pymoo.util.nds.non_dominated_sorting import NonDominatedSorting

import sawtooth
from sawtooth.pymoo import ChainRepair, SawtoothProblem

ROOT = Path(__file__).resolve().parents[1]
REF = np.array([2.0, 20000.0])  # (f_stroke Hz, W_spec J/kg), as generations.csv
# With REF the hypervolume is almost (2 - f) x (20000 - min W_spec): every front has f near
# 0.035 Hz. A reference just beyond the fronts' range tells their shapes apart, too.
REF_ZOOM = np.array([0.04, 2000.0])


def builtin(algorithm: str, a, seed: int, out: Path, selection: str = "deb"):
    d = out / f"builtin-{algorithm}-{selection}-s{seed}"
    if d.exists():
        for f in d.iterdir():
            f.unlink()
    cmd = [
        str(a.bin), "optimize", "--env", "lunar", "--algorithm", algorithm, "--pop", str(a.pop),
        "--generations", str(a.generations), "--particles", str(a.particles), "--seed", str(seed),
        "--final-particles", "100", "--replicates", "1", "--quiet", "--engine", a.engine, "--out", str(d),
    ]
    if selection != "deb":
        cmd += ["--selection", selection]
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    c = json.loads((d / "checkpoint.json").read_text())
    X = np.array([[float(v) for v in ind["x"]] for ind in c["population"] if ind["rank"] == 0])
    return X, wall, int(c["evaluations"])


class WithReplacementTournament:
    """The built-in optimiser's binary tournament: both contestants drawn with replacement;
    constraint violation, then rank, then crowding decide (pymoo draws from permutations and
    compares feasible pairs by dominance)."""

    @staticmethod
    def make():
        from pymoo.core.selection import Selection

        class _Sel(Selection):
            def _do(self, problem, pop, n_select, n_parents, random_state=None, **kwargs):
                rs = random_state if random_state is not None else np.random.default_rng()
                n = n_select * n_parents
                a = rs.integers(0, len(pop), n)
                b = rs.integers(0, len(pop), n)
                cv = pop.get("CV")[:, 0]
                # infeasible individuals carry no rank/crowding in pymoo: CV decides for them
                rank = np.array([np.inf if v is None else v for v in pop.get("rank")], dtype=float)
                cd = np.array([0.0 if v is None else v for v in pop.get("crowding")], dtype=float)
                win = np.where(cv[a] < cv[b], a, np.where(cv[b] < cv[a], b, -1))
                tie = win < 0
                key_a = np.stack([rank[a], -cd[a]], axis=1)
                key_b = np.stack([rank[b], -cd[b]], axis=1)
                a_better = (key_a[:, 0] < key_b[:, 0]) | ((key_a[:, 0] == key_b[:, 0]) & (key_a[:, 1] < key_b[:, 1]))
                b_better = (key_b[:, 0] < key_a[:, 0]) | ((key_a[:, 0] == key_b[:, 0]) & (key_b[:, 1] < key_a[:, 1]))
                coin = rs.random(n) < 0.5
                win = np.where(tie, np.where(a_better, a, np.where(b_better, b, np.where(coin, a, b))), win)
                return win.reshape(n_select, n_parents)

        return _Sel()


def pymoo_run(name: str, a, seed: int, repair: bool = True, crn: bool = True, dedup: bool = True,
              builtin_ops: bool = False, builtin_tournament: bool = False, builtin_mutation: bool = False):
    problem = SawtoothProblem(env="lunar", particles=a.particles, seed=seed, engine=a.engine, common_random_numbers=crn)
    repair = ChainRepair() if repair else None
    kw = dict(pop_size=a.pop, n_offsprings=a.pop, eliminate_duplicates=dedup)
    if builtin_ops:
        from pymoo.operators.mutation.pm import PM

        kw.update(selection=WithReplacementTournament.make(), mutation=PM(prob=1.0, eta=20), eliminate_duplicates=False)
    if builtin_tournament:
        kw.update(selection=WithReplacementTournament.make())
    if builtin_mutation:
        from pymoo.operators.mutation.pm import PM

        kw.update(mutation=PM(prob=1.0, eta=20))
    if repair is not None:
        kw["repair"] = repair
    algo = NSGA2(**kw) if name == "nsga2" else SMSEMOA(**kw)
    budget = a.pop * (a.generations + 1)  # the built-in optimiser's count: initial + G generations
    t0 = time.perf_counter()
    res = minimize(problem, algo, ("n_evals", budget), seed=seed, verbose=False)
    wall = time.perf_counter() - t0
    X = res.X if res.X is not None else np.empty((0, 8))
    return np.atleast_2d(X), wall, problem.evaluations


def reevaluate(X: np.ndarray, a):
    """Mean penalised objectives over fresh streams; feasible and valid in every stream."""
    if len(X) == 0:
        return np.empty((0, 2))
    s = sawtooth.Scenario(env="lunar", particles=a.final_particles)
    F = []
    ok = np.ones(len(X), dtype=bool)
    for k in range(a.final_streams):
        r = sawtooth.evaluate(s, X, seed=0xA5A5_0000 + k, engine=a.engine, feasible_only=True)
        ok &= r["simulated"] & r["valid"] & np.isfinite(r["w_spec_j_kg"])
        F.append(r["objectives"])
    F = np.mean(F, axis=0)[ok]
    if len(F) == 0:
        return F
    front = NonDominatedSorting().do(F, only_non_dominated_front=True)
    return F[front]


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--pop", type=int, default=100)
    p.add_argument("--generations", type=int, default=30)
    p.add_argument("--seeds", default="0,1,2,3,4")
    p.add_argument("--particles", type=int, default=100, help="particles per design while optimising (D.5: 100)")
    p.add_argument("--final-particles", type=int, default=2000)
    p.add_argument("--final-streams", type=int, default=4)
    p.add_argument("--engine", default="cpu")
    p.add_argument("--extras", action="store_true",
                   help="also pymoo NSGA2 without the chain repair, and with one frozen stream (no refresh per generation)")
    p.add_argument("--only", default="", help="run only these optimisers (names as in the table, ';'-separated)")
    p.add_argument("--bin", type=Path, default=ROOT / "target" / "release" / "sawtooth")
    p.add_argument("--out", type=Path, default=ROOT / "runs" / "peer")
    a = p.parse_args()
    a.out.mkdir(parents=True, exist_ok=True)
    seeds = [int(s) for s in a.seeds.split(",")]
    runners = {
        "built-in nsga2": lambda s: builtin("nsga2", a, s, a.out),
        "built-in matlab-like": lambda s: builtin("matlab-like", a, s, a.out),
        "built-in nsga2, permutation selection": lambda s: builtin("nsga2", a, s, a.out, "permutation"),
        "built-in matlab-like, permutation selection": lambda s: builtin("matlab-like", a, s, a.out, "permutation"),
        "pymoo NSGA2": lambda s: pymoo_run("nsga2", a, s),
        "pymoo SMS-EMOA": lambda s: pymoo_run("smsemoa", a, s),
    }
    if a.extras:
        runners["pymoo NSGA2, no repair"] = lambda s: pymoo_run("nsga2", a, s, repair=False)
        runners["pymoo NSGA2, frozen streams"] = lambda s: pymoo_run("nsga2", a, s, crn=False)
        runners["pymoo NSGA2, duplicates kept"] = lambda s: pymoo_run("nsga2", a, s, dedup=False)
        runners["pymoo NSGA2, built-in's tournament and mutation"] = lambda s: pymoo_run("nsga2", a, s, builtin_ops=True)
        runners["pymoo NSGA2, built-in's tournament"] = lambda s: pymoo_run("nsga2", a, s, builtin_tournament=True)
        runners["pymoo NSGA2, built-in's mutation"] = lambda s: pymoo_run("nsga2", a, s, builtin_mutation=True)
    if a.only:
        runners = {k: v for k, v in runners.items() if k in a.only.split(";")}
    hv = HV(ref_point=REF)
    hv_zoom = HV(ref_point=REF_ZOOM)
    results = []
    for seed in seeds:
        for name, run in runners.items():
            X, wall, evals = run(seed)
            F = reevaluate(X, a)
            v = float(hv(F)) if len(F) else 0.0
            vz = float(hv_zoom(F)) if len(F) else 0.0
            wmin = float(F[:, 1].min()) if len(F) else float("nan")
            results.append(dict(optimiser=name, seed=seed, evaluations=evals, wall_s=wall, hv=v, hv_zoom=vz,
                                front_size=len(F), min_w_spec_j_kg=wmin, front=F.tolist()))
            print(f"seed {seed} {name:22s} evals {evals:6d} wall {wall:7.2f} s  HV {v:10.1f}  HV_zoom {vz:7.3f}  "
                  f"front {len(F):3d}  min W_spec {wmin:7.1f} J/kg", flush=True)
    (a.out / "results.json").write_text(json.dumps(dict(settings={k: str(v) for k, v in vars(a).items()}, runs=results), indent=1))
    lines = [
        f"pop {a.pop}, {a.generations} generations ({a.pop * (a.generations + 1)} evaluations), "
        f"{a.particles} particles per design, seeds {a.seeds}, engine {a.engine}; pymoo with the chain repair unless said; "
        f"fronts re-evaluated with {a.final_particles} particles x {a.final_streams} fresh streams; HV w.r.t. (2 Hz, 20000 J/kg), HV_zoom w.r.t. (0.04 Hz, 2000 J/kg), both in Hz·J/kg.",
        "",
        "| optimiser | HV mean ± sd | HV per seed | HV_zoom mean ± sd | HV_zoom per seed | min W_spec mean (J/kg) | front size mean | wall mean (s) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for name in runners:
        rs = [r for r in results if r["optimiser"] == name]
        h = np.array([r["hv"] for r in rs])
        z = np.array([r["hv_zoom"] for r in rs])
        sd = lambda v: v.std(ddof=1) if len(v) > 1 else 0.0
        lines.append(
            f"| {name} | {h.mean():.1f} ± {sd(h):.1f} | {', '.join(f'{x:.0f}' for x in h)} | "
            f"{z.mean():.3f} ± {sd(z):.3f} | {', '.join(f'{x:.3f}' for x in z)} | "
            f"{np.nanmean([r['min_w_spec_j_kg'] for r in rs]):.1f} | {np.mean([r['front_size'] for r in rs]):.1f} | "
            f"{np.mean([r['wall_s'] for r in rs]):.2f} |"
        )
    (a.out / "summary.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    sys.exit(main())
