#!/usr/bin/env bash
# Where the cpu engine's time goes on issue 2's 64-design batches, by what could change it:
# perf samples (with DWARF call stacks) sorted into the particle kernel's own arithmetic, the
# libm calls it makes, and the preparation every engine shares; then the bound this puts on
# any speed-up that keeps the arithmetic (and so every result) as it is: the kernel's own
# arithmetic can run on SIMD lanes to the same bits (IEEE +, -, *, /, sqrt are the same in
# every lane), and so can the project's own expm1, sincos and atan2 (src/lane_math.rs, one
# code for one f64 or eight lanes; they count as the kernel's arithmetic here, while what is
# still called in libm.so, such as ln, counts as libm).
# Needs `perf` (Debian: linux-perf) and permission to record (root, or perf_event_paranoid <= 1).
# Usage: bash scripts/cpu-shares.sh [REPEATS]   (default 100 batches per environment)
set -euo pipefail
cd "$(dirname "$0")/.."
repeats=${1:-100}
if ! [[ $repeats =~ ^[0-9]+$ ]] || ((repeats < 1)); then
    echo "cpu-shares.sh: REPEATS must be a whole number of at least 1, got '$repeats'" >&2
    exit 2
fi
command -v perf >/dev/null || { echo "cpu-shares.sh: needs perf (apt-get install linux-perf)" >&2; exit 2; }
cargo build --release --locked --bin sawtooth >&2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for env in lunar earth; do
    perf record -q -o "$work/$env.data" -F 2000 --call-graph dwarf,16384 \
        target/release/sawtooth bench --env "$env" --engines cpu --repeats "$repeats" >&2
    perf script -i "$work/$env.data" 2>/dev/null > "$work/$env.txt"
done
python3 - "$work" <<'PY'
import pathlib, re, sys
work = pathlib.Path(sys.argv[1])
kinds = ["kernel arithmetic", "kernel libm", "preparation arithmetic", "preparation libm", "other"]
print("| batch | kernel arithmetic (flight search, bounce, draws) | kernel libm (sincos, atan2; expm1, log) "
      "| preparation arithmetic (fill, launch points) | preparation libm (fill arc) | other (threads, allocation) "
      "| samples | most speed-up, arithmetic 4× faster | most speed-up, arithmetic free |")
print("|---|" + "---|" * (len(kinds) + 3))
for env in ["lunar", "earth"]:
    counts = dict.fromkeys(kinds, 0)
    for sample in (work / f"{env}.txt").read_text().split("\n\n"):
        frames = [l.strip() for l in sample.splitlines()[1:] if l.strip()]
        if not frames:
            continue
        stack = "\n".join(frames)
        # a libm function's own frames come first (inlined ones share its address)
        in_libm = any("libm.so" in f for f in frames[:2])
        if "model::prepare::prepare" in stack:
            kind = kinds[3] if in_libm else kinds[2]
        elif re.search(r"CpuEngine|run_design|run_particles", stack):
            kind = kinds[1] if in_libm else kinds[0]
        else:
            kind = kinds[4]
        counts[kind] += 1
    total = sum(counts.values())
    share = {k: v / total for k, v in counts.items()}
    arith = share[kinds[0]] + share[kinds[2]]
    # Amdahl: only the arithmetic (kernel and preparation) gets faster; libm and the rest stay
    bound = lambda s: 1.0 / (1.0 - arith + arith / s)
    cells = " | ".join(f"{100 * share[k]:.1f} %" for k in kinds)
    print(f"| {env}, 64 designs | {cells} | {total} | {bound(4):.2f}× | {bound(float('inf')):.2f}× |")
PY
