#!/usr/bin/env bash
# The loss-adjusted gap (%²) of fixed models against a synthetic campaign of the practice rig,
# simulated with many particles (`sawtooth simulate`, one stream per seed), so that a model's
# gap is known without the diagnosis's Monte-Carlo budget: what a fitted candidate really
# leaves, against what the true model leaves (docs/diagnosis-report.md, "What limits 300 µm
# quadratic drag at the defaults"). Usage:
#   bash scripts/precise-gaps.sh CAMPAIGN_DIR PARTICLES SEED 'NAME|simulate flags' ...
# CAMPAIGN_DIR holds slow.csv, fast.csv, shallow.csv (scripts/diagnose-harder.sh writes them);
# the setups are data/campaign_rig/{slow,fast,shallow}.toml. Prints each model's gap per
# condition and in all, the handling loss allowed as in `verdict::loss_adjusted_sse`
# (a share s of the loaded mass, least squares in [0, the measured not-recovered share]).
set -euo pipefail
cd "$(dirname "$0")/.."
dir="$1"; particles="$2"; seed="$3"; shift 3
cargo build --release --locked --quiet
bin=./target/release/sawtooth
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for spec in "$@"; do
    name="${spec%%|*}"; flags="${spec#*|}"
    for c in slow fast shallow; do
        # shellcheck disable=SC2086
        "$bin" simulate --config "data/campaign_rig/$c.toml" --particles "$particles" --seed "$seed" --json $flags \
            > "$tmp/$name-$c.json"
    done
done
python3 - "$dir" "$tmp" "$@" <<'PY'
import csv, json, os, sys
campaign, tmp, specs = sys.argv[1], sys.argv[2], sys.argv[3:]

def measured(path, bins):
    rows = [r for r in csv.reader(l for l in open(path) if not l.startswith("#"))][1:]
    runs = [[float(x) for x in r[1:]] for r in rows]
    m = [0.0] * bins
    for r in runs:
        teeth, loaded = r[:-1], r[-1]
        for j, t in enumerate(teeth):
            m[j] += t / loaded / len(runs)
        m[-1] += (1 - sum(teeth) / loaded) / len(runs)
    return m

def loss_adjusted_sse(sim, meas):
    last = len(sim) - 1
    d = [-p for p in sim]
    d[last] = 1 - sim[last]
    a = [p - q for p, q in zip(sim, meas)]
    dd = sum(x * x for x in d)
    s = min(max(-sum(x * y for x, y in zip(a, d)) / dd, 0.0), max(meas[last], 0.0)) if dd > 0 else 0.0
    adj = [(1 - s) * p + (s if j == last else 0.0) for j, p in enumerate(sim)]
    return sum((1e2 * (p - q)) ** 2 for p, q in zip(adj, meas))

for spec in specs:
    name = spec.split("|")[0]
    parts = []
    for c in ["slow", "fast", "shallow"]:
        dist = json.load(open(os.path.join(tmp, f"{name}-{c}.json")))["distribution"]
        sim = list(dist) + [1 - sum(dist)]
        parts.append(loss_adjusted_sse(sim, measured(os.path.join(campaign, f"{c}.csv"), len(sim))))
    print(f"{name}: gap {sum(parts):.2f} %² (slow {parts[0]:.2f}, fast {parts[1]:.2f}, shallow {parts[2]:.2f})")
PY
