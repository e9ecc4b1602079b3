#!/usr/bin/env bash
# The DEM campaigns of data/dem/ (issue 32, item 1): LIGGGHTS campaigns of the campaign rig
# (data/campaign_rig/{slow,fast,shallow}.toml: glass beads, Earth with Stokes drag), and the
# same rig on the Moon at slower strokes (data/dem/configs/lunar-*.toml: lunar gravity in
# vacuum), that `diagnose` reads as it reads a rig's. Each campaign runs in OUT/NAME (dumps and logs stay
# there); its measured-data CSV and setup TOML are copied to data/dem/NAME/. A campaign that
# was killed resumes where it stopped when the script is run again; a finished one is skipped.
#
# Usage: bash scripts/dem-campaigns.sh [OUT] [SEEDS] [NAME...]
# (default runs/dem/campaigns, 3 seeds, every campaign; LIGGGHTS under `nice -n 10`, two at
# a time: the machine is shared).
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-runs/dem/campaigns}
seeds=${2:-3}
shift $(($# < 2 ? $# : 2))
only=("$@")
bin=${SAWTOOTH_BIN:-target/release/sawtooth}
mkdir -p "$out" data/dem
wanted() { # NAME: run it when no names were given, or it is among them
    [ ${#only[@]} -eq 0 ] && return 0
    local n
    for n in "${only[@]}"; do [ "$n" = "$1" ] && return 0; done
    return 1
}
campaign() { # NAME CONFIG ARGS...
    local name=$1 config=$2
    shift 2
    wanted "$name" || return 0
    local t0=$SECONDS
    nice -n 10 "$bin" dem run --config "$config" --runs "$seeds" --jobs 2 --out "$out/$name" "$@" \
        >"$out/$name.txt" 2>"$out/$name.log"
    mkdir -p "data/dem/$name"
    cp "$out/$name/dem.csv" "$out/$name/setup.toml" "data/dem/$name/"
    echo "$name: done in $((SECONDS - t0)) s"
}
diameter_um() { # NAME: the grain diameter of a finished campaign's first run, um
    python3 -c "import json; c=json.load(open('$out/$1/run-001/case.json')); print(round(c['placement']['diameter_m']*1e6, 3))"
}
rig=data/campaign_rig
# deep fill: 150 grains carrying the model's fill mass, at each of the rig's three conditions
for c in slow fast shallow; do
    campaign "earth-deep-$c" "$rig/$c.toml" --particles 150
done
# the slow condition with a sled that returns at once at 0.3 m/s while the grains fly (stated
# in the setup's [measurement]); diagnosed beside earth-deep-fast and earth-deep-shallow
campaign earth-deep-slow-return data/dem/configs/slow-return.toml --particles 150
# monolayer: 40 grains of the deep fill's size lining the catch (about a quarter of the mass)
for c in slow fast shallow; do
    wanted "earth-mono-$c" || continue
    campaign "earth-mono-$c" "$rig/$c.toml" --particles 40 --grain-diameter-um "$(diameter_um "earth-deep-$c")"
done
# the deep fill with the polydisperse size law (log-normal, sd 0.3 of ln d; LIGGGHTS size
# classes), at each condition
for c in slow fast shallow; do
    campaign "earth-poly-$c" "$rig/$c.toml" --particles 150 --effect polydisperse=0.3
done
# lunar gravity in vacuum (no drag): the rig's design at strokes the DEM carries in minutes
# (data/dem/configs/lunar-*.toml: v0 0.5 m/s at 30 deg, 0.65 m/s at 30 deg, 0.5 m/s at 15 deg;
# at the rig's own 1.1 m/s the grains fly for seconds over ~20 teeth); deep fill, then the
# monolayer of the deep fill's grain size
for c in slow fast shallow; do
    campaign "lunar-deep-$c" "data/dem/configs/lunar-$c.toml" --particles 150
done
for c in slow fast shallow; do
    wanted "lunar-mono-$c" || continue
    campaign "lunar-mono-$c" "data/dem/configs/lunar-$c.toml" --particles 40 --grain-diameter-um "$(diameter_um "lunar-deep-$c")"
done
