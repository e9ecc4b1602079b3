#!/usr/bin/env bash
# The fidelity map of docs/dem.md (issue 31): DEM campaigns of the validation rig (Test 3's
# setup) in several regimes, each compared with the model. Every campaign resumes where it
# stopped when the script is run again. Usage: bash scripts/dem-fidelity.sh [OUT] [SEEDS] [OVERLAP]
# (default runs/dem/fidelity, 3 seeds, the [dem] default overlap; OVERLAP sets
# `[dem] max_overlap_fraction` for every regime, and the overlap regime halves it; one LIGGGHTS
# process at a time; SAWTOOTH_BIN picks the executable, default target/release/sawtooth;
# REGIMES="earth-deep earth-v0-0.8 ..." runs only those, in the script's order).
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-runs/dem/fidelity}
seeds=${2:-3}
overlap=${3:-}
bin=${SAWTOOTH_BIN:-target/release/sawtooth}
rig=data/validation/test3.toml
mkdir -p "$out"
if [ -n "$overlap" ]; then
    { cat "$rig"; printf '\n[dem]\nmax_overlap_fraction = %s\n' "$overlap"; } >"$out/rig-overlap-$overlap.toml"
    rig="$out/rig-overlap-$overlap.toml"
fi
half=$(python3 -c "print(${overlap:-0.025} / 2)")
campaign() { # NAME ARGS...
    local name=$1
    shift
    if [ -n "${REGIMES:-}" ] && [[ " $REGIMES " != *" $name "* ]]; then return 0; fi
    "$bin" dem run --config "${config:-$rig}" --runs "$seeds" --jobs 1 --out "$out/$name" "$@" >"$out/$name.txt" 2>"$out/$name.log"
    "$bin" dem compare "$out/$name" --json >"$out/$name.json"
    echo "$name: done"
}
# deep fill: 150 grains carrying the model's fill mass (Earth, drag, the rig's 35 deg)
campaign earth-deep --particles 150
# lunar vacuum: the same rig under lunar gravity, no drag (early: the slowest regime, 5-30 min
# a run here, so that it finishes when time is short)
campaign lunar-deep --particles 150 --env lunar --k-drag 0
# monolayer: 40 grains of the deep fill's size lining the catch (about a quarter of the mass)
d_um=$(python3 -c "import json; c=json.load(open('$out/earth-deep/run-001/case.json')); print(c['placement']['diameter_m']*1e6)")
campaign earth-monolayer --particles 40 --grain-diameter-um "$d_um"
# v0 across the optimiser's range (0.8-2.0 m/s), and a shallower slope
campaign earth-v0-0.8 --particles 150 --design 20,15,5,5,60,0,0.8,60
campaign earth-v0-1.4 --particles 150 --design 20,15,5,5,60,0,1.4,60
campaign earth-v0-2.0 --particles 150 --design 20,15,5,5,60,0,2.0,60
campaign earth-alpha-20 --particles 150 --alpha 20
# the softened modulus: the deep fill again with half the peak overlap (a stiffer contact,
# about half the time step), to measure how much the softening itself moves the results
stiff="$out/rig-overlap-$half.toml"
{ cat data/validation/test3.toml; printf '\n[dem]\nmax_overlap_fraction = %s\n' "$half"; } >"$stiff"
config=$stiff
campaign "earth-deep-overlap-$half" --particles 150
config=$rig
# the map's table (docs/dem.md), markdown, from every regime's `dem compare --json`
python3 - "$out" <<'PY'
import json, sys, glob, os
print("| regime | seeds | per-tooth error mean / max (pp) | d_avg model (mm) | model from the DEM's bed | model, DEM's law | d_avg DEM (mm, mean ± sd) | d_avg error | centre model / DEM | dispersion model / DEM | lost DEM % | s per run DEM (wall) | model per design |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
opt = lambda v: '—' if v is None else f"{v:.1f}"
for f in sorted(glob.glob(os.path.join(sys.argv[1], '*.json'))):
    c = json.load(open(f))
    name = os.path.basename(f)[:-5]
    e = c['d_avg_error_pct']
    sp = lambda k, fmt: f"{c[k]['mean']:{fmt}} ± {c[k]['sd']:{fmt}}"
    print(f"| {name} | {c['runs']} | {c['mean_abs_tooth_error_pp']:.1f} / {c['max_abs_tooth_error_pp']:.1f} "
          f"| {c['model_d_avg_mm']:.1f} | {opt(c.get('model_from_bed_d_avg_mm'))} | {opt(c.get('model_dem_law_d_avg_mm'))} | {sp('dem_d_avg_mm', '.1f')} | {'—' if e is None else f'{e:+.1f} %'} "
          f"| {c['model_centre']:.2f} / {sp('dem_centre', '.2f')} | {c['model_dispersion']:.2f} / {sp('dem_dispersion', '.2f')} "
          f"| {c['dem_lost_pct']['mean']:.1f} | {sp('dem_s', '.0f')} | {1e3 * c['model_s']:.0f} ms ({c['model_particles']} particles) |")
PY
