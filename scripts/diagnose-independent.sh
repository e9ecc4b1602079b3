#!/usr/bin/env bash
# Diagnose the independent practice campaigns (data/practice_campaigns, made by a
# simulator that is not this project's) and grade them against answers.json with the rule of
# that folder's README. Usage:
#   bash scripts/diagnose-independent.sh [OUT_DIR] [extra diagnose flags...]
# Writes OUT_DIR/campaign_N/ (diagnosis.json, report.md, figures) and OUT_DIR/grades.txt;
# exits 1 when fewer than 5 of 6 are right. About 2-3 min a campaign on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
root="${CAMPAIGNS:-data/practice_campaigns}"
out="${1:-runs/independent}"
shift || true
cargo build --release --locked --quiet
mkdir -p "$out"
for dir in "$root"/campaign_*; do
    name=$(basename "$dir")
    args=()
    for c in "$dir"/c*.csv; do
        args+=(--data "$c" --setup "${c%.csv}.toml")
    done
    start=$(date +%s)
    ./target/release/sawtooth diagnose "${args[@]}" --out "$out/$name" "$@" > /dev/null 2> "$out/$name.log"
    echo "$name: $(( $(date +%s) - start )) s" >&2
done
python3 scripts/grade_independent.py "$root/answers.json" "$out" | tee "$out/grades.txt"
