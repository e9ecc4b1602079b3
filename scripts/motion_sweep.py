"""The motion screen checked on a sweep of unstated sled motions (issue 46, item 4).

Campaigns of three conditions on the practice rig's geometry (data/campaign_rig/slow.toml)
with v0, a and the slope drawn over the optimiser's ranges (v0 0.8-2.0 m/s, a 20-80 m/s²,
α 0-40°), each made by `sawtooth synth` with a sled that rests DELAY after the launch and
returns at SPEED, down the slope or back along the launch direction; delays from 0 to past
the flights (0.3 s), speeds 0.05-1 m/s. Each campaign is diagnosed twice: with the setups
stating the true delay and speed (`--effects sled-motion`: does the candidate, told the
motion, explain the data?) and with the motion left out of every setup (every candidate, the
motion screen searching it). The screen does not miss when the unstated diagnosis names
sled-motion `best` in the campaigns the stated one explains.

    python3 scripts/motion_sweep.py run OUT [--campaigns 24] [--seed 1] [-- DIAGNOSE FLAGS]
    python3 scripts/motion_sweep.py score OUT        # OUT/table.md

Resumable: a diagnosis whose diagnosis.json exists is not run again. Nothing is committed as
data; this script makes it.
"""
import json
import os
import random
import subprocess
import sys
import time

from diagnose_sweep import ROOT, binary, main as sweep_main, record_time, sh
DELAYS = [0.0, 0.01, 0.02, 0.05, 0.1, 0.3]
SPEEDS = [0.05, 0.1, 0.2, 0.3, 0.5, 1.0]
DIRECTIONS = ["slope", "launch"]
V0 = (0.8, 2.0)
A = (20.0, 80.0)
SLOPE = (0.0, 40.0)
# the top of the sled-motion candidate's delay box: a motion this late is past the flights
PAST_THE_FLIGHTS_S = 0.3




def setup_text(v0, a, alpha, motion):
    """The rig's slow setup at (v0, a, alpha); `motion` None leaves the motion out, else
    (delay, speed, direction) is stated."""
    lines = []
    for line in open(os.path.join(ROOT, "data", "campaign_rig", "slow.toml")).read().splitlines():
        if line.startswith("motion_"):
            continue
        if line.startswith("v0_m_s"):
            line = f"v0_m_s = {v0}"
        elif line.startswith("a_m_s2"):
            line = f"a_m_s2 = {a}"
        elif line.startswith("alpha_deg"):
            line = f"alpha_deg = {alpha}"
        lines.append(line)
        if line.startswith("particle_mass_g") and motion is not None:
            lines.append(f"motion_delay_s = {motion[0]}")
            lines.append(f"motion_return_speed_m_s = {motion[1]}")
            lines.append(f"motion_direction = \"{motion[2]}\"")
    return "\n".join(lines) + "\n"


def plan(n, seed):
    """`n` campaigns: delay, speed and direction cycled over their grids in a shuffled order
    (every value about equally often), three conditions each with v0, a, α drawn uniformly."""
    rng = random.Random(seed)
    combos = [(d, s, r) for d in DELAYS for s in SPEEDS for r in DIRECTIONS]
    rng.shuffle(combos)
    out = []
    for i in range(n):
        d, s, r = combos[i % len(combos)]
        conds = [(round(rng.uniform(*V0), 2), round(rng.uniform(*A)), round(rng.uniform(*SLOPE))) for _ in range(3)]
        out.append({"name": f"m{i:02d}", "delay_s": d, "speed_m_s": s, "direction": r, "conditions": conds,
                    "seed": 1000 * seed + 10 * i})
    return out


def diagnose(d, pairs, flags, name, out):
    target = os.path.join(d, "diagnosis.json")
    if os.path.exists(target):
        return
    args = []
    for data, setup in pairs:
        args += ["--data", data, "--setup", setup]
    start = time.time()
    sh([binary(), "diagnose", *args, "--out", d, *flags], log=d + ".log")
    record_time(out, name, start)


def run(args):
    out = os.path.abspath(args.out)
    os.makedirs(out, exist_ok=True)
    campaigns = plan(args.campaigns, args.seed)
    json.dump({"campaigns": campaigns, "flags": args.flags}, open(os.path.join(out, "plan.json"), "w"), indent=1)
    for c in campaigns:
        try:
            run_one(c, out, args.flags)
        except subprocess.CalledProcessError as e:
            # a design the model refuses at this (v0, a, slope): said, and left out of the score
            print(f"{c['name']}: skipped ({e})", file=sys.stderr, flush=True)
            with open(os.path.join(out, "times.txt"), "a") as t:
                t.write(f"{c['name']} skipped: {e}\n")


def run_one(c, out, flags):
    d = os.path.join(out, c["name"])
    os.makedirs(d, exist_ok=True)
    stated, unstated = [], []
    for k, (v0, a, alpha) in enumerate(c["conditions"]):
        motion = (c["delay_s"], c["speed_m_s"], c["direction"])
        maker = os.path.join(d, f"c{k}-maker.toml")
        text = setup_text(v0, a, alpha, None) + (
            f"\n[effects.sled_motion]\ndelay_s = {motion[0]}\nreturn_speed_m_s = {motion[1]}\n"
            f"direction = \"{c['direction']}\"\n")
        open(maker, "w").write(text)
        data = os.path.join(d, f"c{k}.csv")
        if not os.path.exists(data):
            sh([binary(), "synth", "--setup", maker, "--runs", "10", "--seed", str(c["seed"] + k),
                "--resolution-g", "0.01", "--out", data])
        told = os.path.join(d, f"c{k}-stated.toml")
        open(told, "w").write(setup_text(v0, a, alpha, motion))
        left = os.path.join(d, f"c{k}-unstated.toml")
        open(left, "w").write(setup_text(v0, a, alpha, None))
        stated.append((data, told))
        unstated.append((data, left))
    # a motion that sets in past the flights is no motion: the stated candidate is the
    # baseline (the diagnosis leaves it out), so only the unstated diagnosis runs
    if c["delay_s"] < PAST_THE_FLIGHTS_S:
        diagnose(os.path.join(d, "stated"), stated, ["--effects", "sled-motion", "--no-detection-limits", *flags],
                 c["name"] + "/stated", out)
    diagnose(os.path.join(d, "unstated"), unstated, flags, c["name"] + "/unstated", out)


def score(args):
    out = os.path.abspath(args.out)
    campaigns = json.load(open(os.path.join(out, "plan.json")))["campaigns"]
    lines = ["| campaign | delay (s) | speed (m/s) | direction | conditions (v0, a, α) | stated: verdict | unstated: best, "
             "verdict | fitted motion (delay, speed) | found |", "|---|---|---|---|---|---|---|---|---|"]
    explained = found = 0
    misses, false_motion = [], []
    for c in campaigns:
        ps, pu = (os.path.join(out, c["name"], k, "diagnosis.json") for k in ("stated", "unstated"))
        past = c["delay_s"] >= PAST_THE_FLIGHTS_S
        if not (os.path.exists(pu) and (past or os.path.exists(ps))):
            continue
        u = json.load(open(pu))
        s = {"verdict": "(past the flights)"} if past else json.load(open(ps))
        sm = next((m for m in u["ranking"] if m["effect"] == "sled-motion"), None)
        fitted = f"{sm['params'].get('delay_s', float('nan')):.3f}, {sm['params'].get('return_speed_m_s', float('nan')):.3f}" if sm else "–"
        counts = s["verdict"] == "explained"
        ok = u["best"] == "sled-motion"
        explained += counts
        found += counts and ok
        if counts and not ok:
            misses.append(c["name"])
        if past and ok:
            false_motion.append(c["name"])
        conds = "; ".join(f"{v0}, {a}, {al}" for v0, a, al in c["conditions"])
        lines.append(f"| {c['name']} | {c['delay_s']} | {c['speed_m_s']} | {c['direction']} | {conds} | {s['verdict']} | "
                     f"{u['best']}, {u['verdict']} | {fitted} | {'yes' if ok else 'no'}{'' if counts else ' (not counted)'} |")
    lines.append("")
    lines.append(f"explained when stated: {explained}; of those, sled-motion `best` when unstated: {found} "
                 f"({100 * found / max(explained, 1):.0f} %); misses: {', '.join(misses) or 'none'}; motions past the "
                 f"flights with sled-motion named `best` anyway: {', '.join(false_motion) or 'none'}")
    text = "\n".join(lines) + "\n"
    open(os.path.join(out, "table.md"), "w").write(text)
    print(text)


def run_arguments(r):
    r.add_argument("--campaigns", type=int, default=24)
    r.add_argument("--seed", type=int, default=1)


if __name__ == "__main__":
    sweep_main(__doc__, run, score, run_arguments)
