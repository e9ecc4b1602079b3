#!/usr/bin/env bash
# The hardware-GPU figures of BENCHMARKS.md in one command, for a machine with a GPU and many
# cores (what the project is lent for a few minutes at a time): the machine, GPU conformance,
# the GPU table (scripts/gpu-table.sh), issue 3's moonshot batches (a pop-1000 generation; 10 000
# particles per design), the cpu engine's ratio to the listing on each SIMD path this
# machine's CPU has (SAWTOOTH_SIMD; on 2 threads, as the 2-core development machine, and on
# all), a gpu-sweep over 0..40 degrees on the gpu and the cpu engine, and the GPU test
# target. Every step runs under its own time limit and writes into OUT, so a step that fails
# or times out leaves the others' files.
#
# Usage: SAWTOOTH_BIN=PATH [SAWTOOTH_GPU_TESTS=PATH] bash scripts/gpu-hardware.sh OUT [REPEATS]
#   SAWTOOTH_BIN: the sawtooth binary (default target/release/sawtooth)
#   SAWTOOTH_GPU_TESTS: the built integration-test binary (tests/suite.rs, `cargo test --release
#     --test suite --no-run` prints its path), whose gpu_conformance tests run with the full tier
#   SAWTOOTH_QUICK=1: small batches, to try the script on a software adapter first
set -uo pipefail
cd "$(dirname "$0")/.."
out=${1:?usage: bash scripts/gpu-hardware.sh OUT [REPEATS]}
repeats=${2:-3}
if ! [[ $repeats =~ ^[0-9]+$ ]] || ((repeats < 1)); then
    echo "gpu-hardware.sh: REPEATS must be a whole number of at least 1, got '$repeats'" >&2
    exit 2
fi
st=${SAWTOOTH_BIN:-target/release/sawtooth}
mkdir -p "$out"
: >"$out/steps.txt" # this run's steps only, also where OUT is used again
quick=${SAWTOOTH_QUICK:-0}
pop=1000 big=10000 gens=30 final=1000
if [[ $quick == 1 ]]; then pop=50 big=200 gens=3 final=100; fi

step() { # NAME LIMIT_S COMMAND...: run one step, its output to OUT/NAME.txt, its time to steps.txt
    local name=$1 limit=$2
    shift 2
    local t0=$EPOCHREALTIME rc
    timeout "$limit" "$@" >"$out/$name.txt" 2>&1
    rc=$?
    awk -v n="$name" -v rc="$rc" -v t0="$t0" -v t1="$EPOCHREALTIME" \
        'BEGIN { printf "%-28s rc %3d  %8.1f s\n", n, rc, t1 - t0 }' | tee -a "$out/steps.txt"
}

{
    nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv 2>&1 || true
    lscpu | grep -E '^(Model name|CPU\(s\)|Thread|Core|Socket)' || true
    echo "AVX-512F: $(grep -c -w avx512f /proc/cpuinfo) of $(grep -c ^processor /proc/cpuinfo) CPUs"
    echo "AVX2: $(grep -c -w avx2 /proc/cpuinfo) of $(grep -c ^processor /proc/cpuinfo) CPUs"
} >"$out/machine.txt" 2>&1

step conformance 120 "$st" conformance --designs 50
if [[ $quick == 1 ]]; then
    step gpu-table 200 bash -c "$st bench --env lunar --designs 64 --engines listing,cpu,gpu --repeats 1 --json"
else
    step gpu-table 240 env SAWTOOTH_BIN="$st" bash scripts/gpu-table.sh "$repeats"
fi
# Issue 3's moonshot: a pop-1000 generation, and 10 000 particles for each of its designs, on
# the gpu against the cpu engine on every core
for env in lunar earth; do
    step "pop-$env-${big}p" 150 "$st" bench --env "$env" --designs "$pop" --sample random \
        --particles "$big" --engines cpu,gpu --repeats "$repeats" --json
done
# The cpu engine against the listing on each SIMD path this CPU has (the binary refuses a
# path the CPU lacks, by name: such a path is left out), on 2 threads and on all of them
paths=(default)
for simd in scalar avx2 avx512 neon; do
    if SAWTOOTH_SIMD=$simd "$st" bench --designs 1 --particles 1 --repeats 1 --engines cpu >/dev/null 2>&1; then
        paths+=("$simd")
    fi
done
echo "SIMD paths: ${paths[*]}" >>"$out/machine.txt"
for threads in 2 all; do
    for simd in "${paths[@]}"; do
        for env in lunar earth; do
            vars=()
            [[ $threads == 2 ]] && vars+=(RAYON_NUM_THREADS=2)
            [[ $simd != default ]] && vars+=(SAWTOOTH_SIMD=$simd)
            step "simd-$threads-$simd-$env" 60 env "${vars[@]}" "$st" bench --env "$env" \
                --engines listing,cpu --repeats "$repeats" --json
        done
    done
done
# gpu-sweep, lunar, 0..40 degrees, the same seed and generations on both engines
for engine in gpu cpu; do
    rm -rf "$out/sweep-$engine.run"
    step "sweep-$engine" 150 "$st" gpu-sweep --env lunar --alpha 0..40 --pop "$pop" \
        --generations "$gens" --engine "$engine" --final-particles "$final" --out "$out/sweep-$engine.run"
    cp "$out/sweep-$engine.run/summary.csv" "$out/sweep-$engine-summary.csv" 2>/dev/null
done
if [[ -n ${SAWTOOTH_GPU_TESTS:-} ]]; then
    step gpu-tests 200 env SAWTOOTH_TEST_TIER=full "$SAWTOOTH_GPU_TESTS" gpu_conformance:: --skip the_gpu_table_script --skip the_hardware_gpu_script
fi
