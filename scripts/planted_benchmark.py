"""The planted-effect benchmark of `sawtooth diagnose` (issue 46, item 2).

Campaigns made by `sawtooth synth` on the practice campaigns' rig (data/campaign_rig: slow,
fast, shallow; 10 runs of 2000 grains each, 0.01 g scale): a control without any effect, each
candidate at three strengths around its detection limit (0.5, 1 and 2 times the limit the
diagnosis of the control reports), and data whose shape no candidate makes (the control's runs
reshaped as tests/diagnose_beyond.rs does), for several seeds; each diagnosed with every
candidate. The sled-motion cases leave the motion out of the setups (the experimenter did not
record it), with a control of their own for the limit. Nothing of it is committed as data:
this script makes it.

    python3 scripts/planted_benchmark.py run OUT [--seeds 1,2] [--heldout 3] [-- DIAGNOSE FLAGS]
    python3 scripts/planted_benchmark.py score OUT        # the table (OUT/table.md)

The detection rate at the limit itself (does the limit detect with the 90 % it claims?): every
candidate at 1 × its limit over many seeds, with each seed's controls (the false-alarm rate)
and without the reshapes:

    python3 scripts/planted_benchmark.py run OUT --seeds 1 --heldout 2,3,4,5 --factors 1 --no-reshapes
    python3 scripts/planted_benchmark.py run OUT ... --factors 1.5,2 --only speed_spread   # one effect further up

`run` is resumable: a campaign whose diagnosis.json exists is not made again. The limits are
those of the first seed's controls (OUT/limits.json), used for every seed. `score` grades
each campaign with the practice campaigns' rule (right: `best` is the planted effect, or the
effect is in the indistinguishable set with `best`, of at most three; a control is right when
`best` is null; a reshape when the verdict is `unexplained`) and reports, for the tuning seeds
and the held-out seeds apart: right above the limit (planted at 1 and 2 times it), false
`unexplained` where the planted effect is a candidate, and `no-gap` above the limit.
"""
import json
import os
import time

from diagnose_sweep import ROOT, binary, main as sweep_main, record_time, sh
RIG = ["slow", "fast", "shallow"]
FACTORS = [0.5, 1.0, 2.0]
# the effect's CLI form for a strength of one parameter, the others neutral (as the limits
# ladder them: src/diagnose/limits.rs)
FORMS = {
    ("impact-scatter", "sigma_deg"): "impact-scatter={s}",
    ("launch-spread", "speed_spread"): "launch-spread={s},0",
    ("launch-spread", "angle_sigma_deg"): "launch-spread=0,{s}",
    ("polydisperse", "sigma_ln"): "polydisperse={s}",
    ("quadratic-drag", "diameter_m"): "quadratic-drag={s},2500",
    ("fill-surface-loss", "speed_loss"): "fill-surface-loss={s},0.001",
    ("sled-motion", "return_speed_m_s"): "sled-motion=0,{s}",
}
# search boxes (src/model/effects.rs `search_bounds`): a planted strength stays inside
BOXES = {
    "sigma_deg": (0.0, 30.0),
    "speed_spread": (0.0, 0.9),
    "angle_sigma_deg": (0.0, 30.0),
    "sigma_ln": (0.0, 1.2),
    "diameter_m": (50e-6, 600e-6),
    "speed_loss": (0.0, 0.6),
    "return_speed_m_s": (0.01, 1.0),
}
# out of family: a share of every run's loaded mass moved from its modal tooth to tooth 1 and
# another share to the tooth after the mode
RESHAPES = {"reshape-12-8": (0.12, 0.08), "reshape-6-4": (0.06, 0.04)}




def setups(out, stated):
    """The rig's setups, or copies without their motion_* lines."""
    if stated:
        return [os.path.join(ROOT, "data", "campaign_rig", f"{c}.toml") for c in RIG]
    d = os.path.join(out, "unstated-setups")
    os.makedirs(d, exist_ok=True)
    paths = []
    for c in RIG:
        p = os.path.join(d, f"{c}.toml")
        src = open(os.path.join(ROOT, "data", "campaign_rig", f"{c}.toml")).read()
        open(p, "w").write("".join(line + "\n" for line in src.splitlines() if not line.startswith("motion_")))
        paths.append(p)
    return paths


def reshape(csv, share, tail):
    """tests/diagnose_beyond.rs `reshape`: `share` of each run's loaded mass from its modal
    tooth to tooth 1, `tail` to the tooth after the mode."""
    out, header = [], True
    for line in csv.splitlines():
        if line.startswith("#") or header:
            header &= line.startswith("#")
            out.append(line)
            continue
        cells = [float(c) for c in line.split(",")]
        run, teeth, mass = cells[0], cells[1:-1], cells[-1]
        k = max(range(len(teeth)), key=lambda j: (teeth[j], j))  # the last of equal modes, as Rust's max_by
        first = round(share * mass * 100) / 100
        nxt = round(tail * mass * 100) / 100 if k + 1 < len(teeth) else 0.0
        teeth[k] -= first + nxt
        teeth[0] += first
        if nxt > 0:
            teeth[k + 1] += nxt
        out.append(f"{int(run)}," + ",".join(f"{m:.2f}" for m in teeth) + f",{mass:.2f}")
    return "\n".join(out) + "\n"


def campaign(out, name, seed, effect, stated, flags, plain_from=None, shape=None, limits=False):
    """Make (synth) and diagnose one campaign in OUT/NAME unless done; returns its folder."""
    d = os.path.join(out, name)
    if os.path.exists(os.path.join(d, "out", "diagnosis.json")):
        return d
    os.makedirs(d, exist_ok=True)
    args = []
    for i, (c, setup) in enumerate(zip(RIG, setups(out, stated))):
        data = os.path.join(d, f"{c}.csv")
        if shape is not None:
            src = open(os.path.join(plain_from, f"{c}.csv")).read()
            open(data, "w").write(reshape(src, *shape))
        else:
            cmd = [binary(), "synth", "--setup", setup, "--runs", "10", "--seed", str(seed + i),
                   "--resolution-g", "0.01", "--out", data]
            if effect:
                cmd += ["--effect", effect]
            sh(cmd)
        args += ["--data", data, "--setup", setup]
    start = time.time()
    # only the controls' limits are read; the others leave them out (a few per cent of the time)
    extra = [] if limits else ["--no-detection-limits"]
    sh([binary(), "diagnose", *args, "--out", os.path.join(d, "out"), *extra, *flags], log=os.path.join(d, "diagnose.log"))
    record_time(out, name, start)
    return d


def strength(limit, factor, param):
    lo, hi = BOXES[param]
    return min(max(limit * factor, lo), hi)


def run(args):
    out = os.path.abspath(args.out)
    os.makedirs(out, exist_ok=True)
    flags = args.flags
    seeds = [int(s) for s in args.seeds.split(",") if s] + [int(s) for s in args.heldout.split(",") if s]
    plan = {"tuning": [int(s) for s in args.seeds.split(",") if s],
            "heldout": [int(s) for s in args.heldout.split(",") if s], "flags": flags, "cases": {}}
    # a second run into OUT (other factors, --only) adds its cases to the first's
    if os.path.exists(os.path.join(out, "plan.json")):
        plan["cases"] = json.load(open(os.path.join(out, "plan.json")))["cases"]
    # 1. the controls, stated and unstated motion; the first seed's give the limits
    for seed in seeds:
        for stated in (True, False):
            name = f"s{seed}/control-{'stated' if stated else 'unstated'}"
            campaign(out, name, 1000 * seed, None, stated, flags, limits=True)
            plan["cases"][name] = {"seed": seed, "effect": None, "kind": "control"}
    first = seeds[0]
    limits = {}
    for stated in (True, False):
        d = json.load(open(os.path.join(out, f"s{first}/control-{'stated' if stated else 'unstated'}", "out",
                                        "diagnosis.json")))
        for l in (d.get("detection_limits") or {}).get("limits", []):
            key = (l["effect"], l["param"])
            # sled motion from the unstated control (the stated setups state it), the rest stated
            if (key[0] == "sled-motion") != stated and key in FORMS and l["limit"] is not None:
                limits[f"{key[0]}|{key[1]}"] = l["limit"]
    json.dump(limits, open(os.path.join(out, "limits.json"), "w"), indent=1)
    # 2. every candidate at three strengths around its limit; 3. the reshapes
    for seed in seeds:
        for k, (key, limit) in enumerate(sorted(limits.items())):
            effect, param = key.split("|")
            if args.only and param not in args.only:
                continue
            for f in args.factors:
                # the campaign's seed keeps its place in FACTORS, so a subset remakes the same data
                j = FACTORS.index(f) if f in FACTORS else len(FACTORS) + args.factors.index(f)
                s = strength(limit, f, param)
                name = f"s{seed}/{effect}-{param}-x{f:g}"
                form = FORMS[(effect, param)].format(s=f"{s:.6g}")
                campaign(out, name, 1000 * seed + 100 * (k + 1) + 10 * j, form, effect != "sled-motion", flags)
                plan["cases"][name] = {"seed": seed, "effect": effect, "param": param, "factor": f,
                                       "strength": s, "kind": "planted"}
        for r, shape in ({} if args.no_reshapes else RESHAPES).items():
            name = f"s{seed}/{r}"
            campaign(out, name, 0, None, True, flags, plain_from=os.path.join(out, f"s{seed}/control-stated"),
                     shape=shape)
            plan["cases"][name] = {"seed": seed, "effect": None, "kind": "out-of-family"}
        json.dump(plan, open(os.path.join(out, "plan.json"), "w"), indent=1)
    json.dump(plan, open(os.path.join(out, "plan.json"), "w"), indent=1)


def right(d, effect):
    if effect is None:
        return d["best"] is None
    together = d["indistinguishable"]
    return d["best"] == effect or (d["best"] is not None and effect in together and len(together) <= 3)


def score(args):
    out = os.path.abspath(args.out)
    plan = json.load(open(os.path.join(out, "plan.json")))
    rows, summary = {}, {}
    for name, case in sorted(plan["cases"].items()):
        path = os.path.join(out, name, "out", "diagnosis.json")
        if not os.path.exists(path):
            continue
        d = json.load(open(path))
        part = "tuning" if case["seed"] in plan["tuning"] else "heldout"
        if case["kind"] == "planted":
            key = (case["effect"], case["param"], case["factor"])
            ok = right(d, case["effect"])
        elif case["kind"] == "control":
            key = ("control", name.split("/")[1].split("-")[1], 0)
            ok = right(d, None)
        else:
            key = ("out-of-family", name.split("/")[1], 0)
            ok = d["verdict"] == "unexplained"
        r = rows.setdefault((part,) + key, {"n": 0, "right": 0, "no-gap": 0, "unexplained": 0, "verdicts": []})
        r["n"] += 1
        r["right"] += ok
        r["no-gap"] += d["verdict"] == "no-gap"
        r["unexplained"] += d["verdict"] == "unexplained"
        r["verdicts"].append(f"{d['verdict']}/{d['best'] or '-'}")
        if case["kind"] == "planted" and case["factor"] >= 1.0:
            s = summary.setdefault(part, {"n": 0, "right": 0, "unexplained": 0, "no-gap": 0})
            s["n"] += 1
            s["right"] += ok
            s["unexplained"] += d["verdict"] == "unexplained"
            s["no-gap"] += d["verdict"] == "no-gap"
    limits = json.load(open(os.path.join(out, "limits.json")))
    lines = ["| seeds | case | strength (× limit) | campaigns | right | `no-gap` | `unexplained` | verdict/best |",
             "|---|---|---|---|---|---|---|---|"]
    for key, r in sorted(rows.items(), key=lambda kv: (kv[0][0] != "tuning",) + tuple(str(x) for x in kv[0][1:])):
        part, what, param, factor = key
        case = f"{what} {param}" if what not in ("control", "out-of-family") else f"{what} ({param})"
        lim = limits.get(f"{what}|{param}")
        strength_text = f"{factor:g} ({lim * factor:.3g})" if lim is not None else "–"
        lines.append(f"| {part} | {case} | {strength_text} | {r['n']} | {r['right']} | {r['no-gap']} | "
                     f"{r['unexplained']} | {', '.join(r['verdicts'])} |")
    lines.append("")
    for part, s in sorted(summary.items(), key=lambda kv: kv[0] != "tuning"):
        n = max(s["n"], 1)
        lines.append(f"{part} seeds, planted at 1 and 2 × the limit ({s['n']} campaigns): right "
                     f"{100 * s['right'] / n:.0f} %, false `unexplained` {100 * s['unexplained'] / n:.0f} %, "
                     f"`no-gap` {100 * s['no-gap'] / n:.0f} %")
    text = "\n".join(lines) + "\n"
    open(os.path.join(out, "table.md"), "w").write(text)
    print(text)


def factors(text):
    return [float(f) for f in text.split(",") if f]


def run_arguments(r):
    r.add_argument("--seeds", default="1,2")
    r.add_argument("--heldout", default="3")
    r.add_argument("--factors", type=factors, default=FACTORS,
                   help="strengths as multiples of each limit (default 0.5,1,2)")
    r.add_argument("--no-reshapes", action="store_true", help="leave out the out-of-family reshapes")
    r.add_argument("--only", type=lambda t: [p for p in t.split(",") if p], default=[],
                   help="plant only these parameters (e.g. speed_spread,return_speed_m_s)")


if __name__ == "__main__":
    sweep_main(__doc__, run, score, run_arguments)
