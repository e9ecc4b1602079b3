#!/usr/bin/env bash
# The GPU tables of BENCHMARKS.md in one command, for a machine with a GPU: conformance
# first (GPU against the CPU twin; stops here when a tolerance fails), then the pop-1000
# generations and issue 2's 64-design batches, each engine side by side in one process,
# printed as one Markdown table with the devices the engines ran on.
# Usage: bash scripts/gpu-table.sh [REPEATS]   (default 3; prints Markdown on stdout)
set -euo pipefail
cd "$(dirname "$0")/.."
repeats=${1:-3}
# the best of the repeats is taken (bench runs the gpu engine once untimed first: that run
# compiles the kernels); checked here so that a typo fails before conformance has run
if ! [[ $repeats =~ ^[0-9]+$ ]] || ((repeats < 1)); then
    echo "gpu-table.sh: REPEATS must be a whole number of at least 1, got '$repeats'" >&2
    exit 2
fi
# SAWTOOTH_BIN: a sawtooth binary to use instead of building one (the test suite's)
if [[ -n ${SAWTOOTH_BIN:-} ]]; then
    st=$SAWTOOTH_BIN
else
    cargo build --release --locked --bin sawtooth >&2
    st=target/release/sawtooth
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

$st conformance --designs 50 >&2

n=0
for env in lunar earth; do
    for batch in "--designs 1000 --sample random" "" "--compat-listing"; do
        n=$((n + 1))
        # shellcheck disable=SC2086 # the batch's flags are words
        $st bench --env $env $batch --engines listing,cpu,gpu --repeats "$repeats" --json > "$work/$n.json"
    done
done

# The pop-1000 generations again with the host preparing a slice of designs while the device
# runs the slice before (SAWTOOTH_GPU_SLICE_DESIGNS; 0, the default, is the whole generation
# at once, the rows above): whether that takes the preparation off a hardware GPU's critical
# path. On lavapipe the device is the host's own cores, so there slices only cost.
mkdir "$work/slices"
for env in lunar earth; do
    for slice in 500 250; do
        n=$((n + 1))
        SAWTOOTH_GPU_SLICE_DESIGNS=$slice $st bench --env $env --designs 1000 --sample random \
            --engines cpu,gpu --repeats "$repeats" --json > "$work/slices/$n-$slice.json"
    done
done

python3 - "$work" "$repeats" <<'EOF'
import json, pathlib, sys
work, repeats = pathlib.Path(sys.argv[1]), sys.argv[2]
runs = [json.loads(p.read_text()) for p in sorted(work.glob("*.json"), key=lambda p: int(p.stem))]
print(f"best of {repeats} repeats per engine; seconds per batch, preparation included; ratios of")
print("particle-bounces per second, as `bench` prints them")
print()
print("| batch | listing | cpu | gpu | cpu / listing | gpu / cpu |")
print("|---|---|---|---|---|---|")
for r in runs:
    s, rate = r["seconds_per_batch"], r["particle_bounces_per_s"]
    mode = "" if r["mode"] == "physical" else ", listing mode"
    size = "pop 1000" if r["designs"] == 1000 and r["sample"] == "random" else f'{r["designs"]} designs'
    print(f'| {r["env"]}, {size}{mode} | {s["listing"]:.4g} s | {s["cpu"] * 1e3:.4g} ms '
          f'| {s["gpu"] * 1e3:.4g} ms | {rate["cpu"] / rate["listing"]:.1f}× | **{rate["gpu"] / rate["cpu"]:.2f}×** |')
print()
for engine, device in runs[0]["devices"].items():
    print(f"- {engine}: {device}")
print()
print("pop-1000 generations in slices, the next prepared while one runs (SAWTOOTH_GPU_SLICE_DESIGNS;")
print("the whole generation at once is the table above)")
print()
print("| generation | designs per slice | cpu | gpu | gpu / cpu |")
print("|---|---|---|---|---|")
for p in sorted((work / "slices").glob("*.json"), key=lambda p: int(p.stem.split("-")[0])):
    r = json.loads(p.read_text())
    s, rate = r["seconds_per_batch"], r["particle_bounces_per_s"]
    print(f'| {r["env"]}, pop 1000 | {p.stem.split("-")[1]} | {s["cpu"] * 1e3:.4g} ms | {s["gpu"] * 1e3:.4g} ms '
          f'| **{rate["gpu"] / rate["cpu"]:.2f}×** |')
EOF
