#!/usr/bin/env bash
# The harder synthetic campaigns of issue 32 (docs/diagnosis-report.md, "Harder synthetic
# campaigns") at the full budget: each made by `sawtooth synth` on the practice campaigns'
# rig (data/campaign_rig/{slow,fast,shallow}.toml, 10 runs, 0.01 g scale; the generator that
# tests/diagnose_beyond.rs uses, with the seeds of the report's table, not the tests'), then
# diagnosed with every candidate at the defaults, one campaign at a time. Usage:
#   bash scripts/diagnose-harder.sh [OUT_DIR] [extra diagnose flags...]
#   HARDER="uA qd300" bash scripts/diagnose-harder.sh runs/harder   # some campaigns only
# Writes OUT_DIR/NAME/{slow,fast,shallow}.csv (and the setups it used), OUT_DIR/NAME/out/
# (diagnosis.json, report.md, figures), OUT_DIR/NAME.log, OUT_DIR/times.txt and
# OUT_DIR/table.md: baseline gap, the top three, best, the indistinguishable set, verdict,
# wall time, and whether the truth is named (best) or narrowed (best non-null, the truth in
# an indistinguishable set of at most three: the practice campaigns' rule).
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-runs/harder}"
shift || true
cargo build --release --locked --quiet
bin=./target/release/sawtooth
mkdir -p "$out"

# name | effect withheld from the model | first seed (+0, +1, +2 for slow, fast, shallow) |
# whether the setups state the sled's motion
campaigns=(
    "uA|sled-motion=0,0.3|201|unstated"
    "uB|sled-motion=0.05,0.5|211|unstated"
    "uC|sled-motion=0.02,0.15|221|unstated"
    "is11|impact-scatter=11|301|stated"
    "qd300|quadratic-drag=300e-6,2500|311|stated"
    "poly08|polydisperse=0.08|331|stated"
)
wanted="${HARDER:-uA uB uC is11 qd300 poly08}"

: > "$out/times.txt"
for spec in "${campaigns[@]}"; do
    IFS='|' read -r name effect seed motion <<< "$spec"
    [[ " $wanted " == *" $name "* ]] || continue
    dir="$out/$name"
    rm -rf "$dir"
    mkdir -p "$dir"
    args=()
    i=0
    for cond in slow fast shallow; do
        setup="data/campaign_rig/$cond.toml"
        if [[ $motion == unstated ]]; then
            # the experimenter did not record how the sled moved after the stroke
            grep -v '^motion_' "$setup" > "$dir/$cond.toml"
            setup="$dir/$cond.toml"
        fi
        "$bin" synth --setup "$setup" --effect "$effect" --runs 10 --seed $((seed + i)) \
            --resolution-g 0.01 --out "$dir/$cond.csv" > /dev/null
        args+=(--data "$dir/$cond.csv" --setup "$setup")
        i=$((i + 1))
    done
    start=$(date +%s)
    "$bin" diagnose "${args[@]}" --out "$dir/out" "$@" > /dev/null 2> "$out/$name.log"
    echo "$name ${effect%%=*} $(( $(date +%s) - start )) s (load $(cut -d' ' -f1-3 /proc/loadavg))" | tee -a "$out/times.txt"
done

python3 - "$out" <<'EOF' | tee "$out/table.md"
import json, os, sys
out = sys.argv[1]
times = {l.split()[0]: l.strip().split(maxsplit=2) for l in open(os.path.join(out, "times.txt"))}
print("| campaign | withheld | baseline gap | top three: gap (reduction) | best | indistinguishable | verdict | named / narrowed | wall time |")
print("|---|---|---|---|---|---|---|---|---|")
for name, (_, truth, wall) in times.items():
    d = json.load(open(os.path.join(out, name, "out", "diagnosis.json")))
    top = ", ".join(f"{m['effect']} {m['gap']:.1f} ({100 * m['reduction']:.0f} %)" for m in d["ranking"][:3])
    together = d["indistinguishable"]
    if d["best"] == truth:
        grade = "named"
    elif d["best"] is not None and truth in together and len(together) <= 3:
        grade = "narrowed"
    else:
        grade = "NOT FOUND"
    left = d["verdict_detail"]["remaining"]
    print(f"| {name} | {truth} | {d['baseline']['gap']:.1f} | {top} | {d['best']} | {', '.join(together) or '–'} "
          f"| {d['verdict']} ({left['model']} leaves {left['gap']:.1f}, {left['gap_over_floor']:.1f}× its floor) "
          f"| {grade} | {wall} |")
EOF
