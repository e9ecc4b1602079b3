#!/usr/bin/env bash
# One figure of each kind the tool writes, as the PNGs shown in README.md (docs/figures/).
# Every figure is the tool's own PNG (each run folder holds NAME.svg and NAME.png); the runs
# are small so that this takes a few minutes on 2 cores, not the thesis's budgets.
# Usage: bash scripts/readme-figures.sh   (rewrites docs/figures/*.png)
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --locked --bin sawtooth
st=target/release/sawtooth
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
out=docs/figures
mkdir -p "$out"

# the flights of 12 grains on lunar solution C
$st simulate --config examples/lunar_solution_c.toml --particles 12 --plot "$out/flight.png"
# an optimisation's front (pareto.png): picks A/B/C, standard errors of the re-evaluation
$st optimize --env lunar --pop 100 --generations 40 --final-particles 500 --replicates 4 --seed 1 --quiet \
    --out "$work/opt"
cp "$work/opt/pareto.png" "$out/pareto.png"
# the picks over the slope (sweep.png)
$st gpu-sweep --env lunar --alpha 10..40 --step 10 --pop 60 --generations 25 --final-particles 300 --replicates 4 \
    --quiet --out "$work/sweep"
cp "$work/sweep/sweep.png" "$out/sweep.png"
# repeated runs at one setting (repeatability.png)
$st study repeatability --env lunar --runs 6 --pop 60 --generations 25 --final-particles 300 --replicates 2 \
    --quiet --out "$work/rep"
cp "$work/rep/repeatability.png" "$out/repeatability.png"
# a calibration against Test 3's measured tooth masses (fit.png)
$st fit --data data/validation/test3.csv --setup data/validation/test3.toml --out "$work/fit"
cp "$work/fit/fit.png" "$out/fit.png"
# the diagnosis of Test 3 (residuals, ranking and distributions)
$st diagnose --data data/validation/test3.csv --setup data/validation/test3.toml --out "$work/diag"
for f in residuals ranking distributions; do cp "$work/diag/$f.png" "$out/$f.png"; done
ls -l "$out"
