#!/usr/bin/env bash
# Where the WGSL kernel's time goes on lavapipe, which keeps no symbols for the code LLVM
# compiles: perf samples a pop-1000 gpu generation running over and over, the process's
# anonymous executable mappings (that code) are read from /proc/PID/mem and disassembled,
# and the samples are counted per instruction. Printed: the share of the run in that code,
# then the kernel's loops (backward jumps over more than 512 bytes, outermost first) with the
# share of the kernel's samples inside each, and its hottest instructions. Which loop is
# which WGSL loop is read from the nesting (BENCHMARKS.md has the lunar one on 5930f44: the
# bounce loop, the teeth loop, the scan past the teeth a flight clears, the root loops).
# lavapipe runs both sides of every branch its eight lanes disagree on and a loop until its
# last lane leaves, so these shares are what a change to the kernel's shape can move.
# Needs perf (Debian: linux-perf), objdump (binutils), a Vulkan lavapipe (mesa-vulkan-drivers)
# and permission to record and read another process (root, or perf_event_paranoid <= 1 and
# ptrace allowed).
# Usage: bash scripts/lavapipe-profile.sh [lunar|earth] [SECONDS]   (defaults: lunar 4)
set -euo pipefail
cd "$(dirname "$0")/.."
env=${1:-lunar}
secs=${2:-4}
if [[ $env != lunar && $env != earth ]]; then
    echo "lavapipe-profile.sh: the environment must be lunar or earth, got '$env'" >&2
    exit 2
fi
if ! [[ $secs =~ ^[0-9]+$ ]] || ((secs < 1)); then
    echo "lavapipe-profile.sh: SECONDS must be a whole number of at least 1, got '$secs'" >&2
    exit 2
fi
for tool in perf objdump python3; do
    command -v "$tool" >/dev/null || { echo "lavapipe-profile.sh: needs $tool" >&2; exit 2; }
done
cargo build --release --locked --bin sawtooth >&2
work=$(mktemp -d)
pid=
trap '[[ -n $pid ]] && kill "$pid" 2>/dev/null; rm -rf "$work"' EXIT
# more repeats than the sampling needs (bench times the preparation as often first);
# killed once the samples and the code are taken. SAWTOOTH_PROFILE=1 prints a line per gpu
# run: the first one means the kernels are compiled, so the samples are of the steady state.
SAWTOOTH_PROFILE=1 target/release/sawtooth bench --env "$env" --designs 1000 --sample random \
    --engines gpu --repeats 2000 >"$work/bench.out" 2>&1 &
pid=$!
until grep -q "profile gpu" "$work/bench.out"; do
    kill -0 "$pid" 2>/dev/null || { cat "$work/bench.out" >&2; echo "lavapipe-profile.sh: bench stopped" >&2; exit 1; }
    sleep 1
done
perf record -q -o "$work/perf.data" -F 4000 -p "$pid" -- sleep "$secs" >&2
# the JIT code: executable mappings with no file behind them
python3 - "$pid" "$work" <<'PY'
import pathlib, sys
pid, work = sys.argv[1], pathlib.Path(sys.argv[2])
with open(f"/proc/{pid}/mem", "rb") as mem:
    for line in pathlib.Path(f"/proc/{pid}/maps").read_text().splitlines():
        fields = line.split()
        if "x" in fields[1] and len(fields) < 6:
            lo, hi = (int(a, 16) for a in fields[0].split("-"))
            mem.seek(lo)
            (work / f"jit_{lo:x}.bin").write_bytes(mem.read(hi - lo))
PY
kill "$pid"
wait "$pid" 2>/dev/null || true
pid=
perf script -i "$work/perf.data" -F ip 2>/dev/null >"$work/ips"
for bin in "$work"/jit_*.bin; do
    lo=${bin##*/jit_}
    lo=${lo%.bin}
    objdump -D -b binary -m i386:x86-64 --adjust-vma="0x$lo" "$bin" >"${bin%.bin}.s"
done
python3 - "$work" "$env" <<'PY'
import collections, pathlib, re, sys
work, env = pathlib.Path(sys.argv[1]), sys.argv[2]
samples = collections.Counter(int(l, 16) for l in (work / "ips").read_text().split())
total = sum(samples.values())
regions = []
for s in sorted(work.glob("jit_*.s")):
    insns = []
    for line in s.read_text().splitlines():
        m = re.match(r"\s*([0-9a-f]+):\t[0-9a-f ]+\t(.*)", line)
        if m:
            insns.append((int(m.group(1), 16), m.group(2).strip()))
    if insns:
        regions.append(insns)
if not regions or total == 0:
    # on a hardware GPU the kernel runs on the card, not in this process's JIT code
    sys.exit("lavapipe-profile.sh: no JIT code or no samples (is the gpu engine on lavapipe?)")
jit = sum(samples[a] for r in regions for a, _ in r)
kernel = max(regions, key=lambda r: sum(samples[a] for a, _ in r))
in_kernel = sum(samples[a] for a, _ in kernel)
print(f"lavapipe, {env} pop-1000 generation: {total} samples; {100 * jit / total:.1f} % in JIT code, "
      f"{100 * in_kernel / total:.1f} % in the kernel ({kernel[-1][0] - kernel[0][0] + 1} bytes)\n")
loops = []
for addr, text in kernel:
    m = re.match(r"j\w+\s+0x([0-9a-f]+)", text)
    if m and addr - int(m.group(1), 16) > 512:
        loops.append((int(m.group(1), 16), addr))
loops.sort(key=lambda l: (l[0], -l[1]))
print("| loop (addresses) | bytes | depth | share of the kernel's samples |")
print("|---|---|---|---|")
for lo, hi in loops:
    depth = sum(1 for a, b in loops if a <= lo and hi <= b and (a, b) != (lo, hi))
    share = sum(samples[a] for a, _ in kernel if lo <= a <= hi) / in_kernel
    print(f"| {'  ' * depth}{lo:x}-{hi:x} | {hi - lo} | {depth} | {100 * share:.1f} % |")
print("\nhottest instructions (share of the kernel's samples):")
for addr, text in sorted(kernel, key=lambda i: -samples[i[0]])[:12]:
    print(f"  {100 * samples[addr] / in_kernel:5.1f} %  {addr:x}  {text}")
PY
