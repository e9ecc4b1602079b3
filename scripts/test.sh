#!/usr/bin/env bash
# The test command of the README, the full tier: installs what the tests need, then runs them
# all. Plain `cargo test` is the fast tier (no apt, no network, a few minutes): it skips the
# heavy tests, each saying so on stderr; SAWTOOTH_TEST_TIER=full (set below) or CI=true runs
# them (tests/common/mod.rs, `full_tier`; docs/testing.md lists them).
# The GPU tests need a Vulkan adapter; without a GPU driver, Mesa's software Vulkan
# (lavapipe) is installed from Debian's packages (scripts/lavapipe.sh). Usage: bash scripts/test.sh
# Campaigns (issue 15): tests/campaign_slurm.rs itself runs scripts/slurm-local.sh, which
# installs slurm-wlm and munge when missing and starts/stops a private single-node Slurm
# (needs root or sudo; with CI=true a Slurm that cannot start fails that test).
set -euo pipefail
cd "$(dirname "$0")/.."
export CARGO_TERM_COLOR=never
# the heavy tests: the withheld-effect diagnoses, the big lavapipe conformance, the Slurm campaign
export SAWTOOTH_TEST_TIER=full

have_vulkan_icd() {
    local f
    for f in /usr/share/vulkan/icd.d/*.json /etc/vulkan/icd.d/*.json; do
        [ -e "$f" ] && return 0
    done
    return 1
}
# On Debian 12 lavapipe comes from bookworm-backports (Mesa 25; scripts/lavapipe.sh says why).
if ! have_vulkan_icd; then
    echo "test.sh: no Vulkan driver found; installing Mesa lavapipe (scripts/lavapipe.sh)"
    bash scripts/lavapipe.sh
fi
# The DEM tests (tests/dem.rs, issue 31) run the real engine: Debian's LIGGGHTS package.
if ! command -v liggghts >/dev/null 2>&1; then
    echo "test.sh: no liggghts found; installing the Debian package liggghts"
    SUDO=""
    if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
    $SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq liggghts >/dev/null
fi
# lavapipe's WSI probing warns without a runtime dir; the tests draw nothing on screen.
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"

# --- style gates (issue 16): formatting and lints are part of the test, not advice --------
# rustup's default profile ships both; a minimal toolchain gets them added here.
if ! cargo fmt --version >/dev/null 2>&1 || ! cargo clippy --version >/dev/null 2>&1; then
    rustup component add rustfmt clippy
fi
lint_status=0
cargo fmt --all --check || { echo "test.sh: cargo fmt --check failed (run: cargo fmt)"; lint_status=1; }
cargo clippy --release --locked --workspace --all-targets -- -D warnings || {
    echo "test.sh: cargo clippy found warnings"
    lint_status=1
}

# --- the aarch64 build: the NEON lanes compile and lint (nothing aarch64 runs here) -------
if ! rustup target list --installed 2>/dev/null | grep -qx aarch64-unknown-linux-gnu; then
    rustup target add aarch64-unknown-linux-gnu >/dev/null 2>&1 || true
fi
if rustup target list --installed 2>/dev/null | grep -qx aarch64-unknown-linux-gnu; then
    cargo clippy --locked --target aarch64-unknown-linux-gnu --lib --tests -- -D warnings || {
        echo "test.sh: the aarch64 build failed (cargo clippy --target aarch64-unknown-linux-gnu)"
        lint_status=1
    }
else
    echo "test.sh: SKIPPED the aarch64 build: the target aarch64-unknown-linux-gnu is not installed and rustup could not add it"
fi

log=$(mktemp)
trap 'rm -f "$log"' EXIT
status=0
# --workspace: the benchmarks too (benches/, their own package so that plain `cargo test` does
# not compile criterion); the Python package is built and tested by pip and pytest below.
cargo test --release --locked --workspace --exclude sawtooth-py --all-targets --no-fail-fast 2>&1 | tee "$log" || status=$?
# One closing line over every test binary (cargo's own last line belongs to whichever
# target ran last, possibly one without tests).
awk '/^test result:/ { for (i = 1; i <= NF; i++) { if ($(i+1) ~ /^passed/) p += $i; if ($(i+1) ~ /^failed/) f += $i } }
     END { printf "tests: %d passed, %d failed\n", p, f }' "$log"

# --- Python package (issue 14) ---------------------------------------------------------
# A virtual environment in .venv (git-ignored), the package installed from the repository
# exactly as the README says (`pip install ./python`, maturin builds the abi3 wheel against
# the locked Cargo.lock and the shared target/), then pytest. PYTHON picks the interpreter.
PYTHON="${PYTHON:-python3}"
py_status=0
pylog=$(mktemp)
trap 'rm -f "$log" "$pylog"' EXIT
if ! .venv/bin/python -m pip --version >/dev/null 2>&1; then
    rm -rf .venv
    if ! "$PYTHON" -m venv .venv >/dev/null 2>&1; then
        # Debian's system python needs python3-venv (ensurepip) for `-m venv`
        echo "test.sh: $PYTHON -m venv failed; installing python3-venv"
        rm -rf .venv
        SUDO=""
        if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
        $SUDO apt-get update -qq
        DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq python3-venv python3-pip >/dev/null
        "$PYTHON" -m venv .venv
    fi
fi
{
    .venv/bin/python -m pip install -q maturin pytest numpy pymoo pandas matplotlib &&
        # the CLI the tests compare with: built by `cargo test ... --all-targets` above; a separate
        # `cargo build` would resolve without the dev-dependencies' features and recompile wgpu
        { [ -x target/release/sawtooth ] || cargo build --release --locked --bin sawtooth; } &&
        MATURIN_PEP517_ARGS="--locked" .venv/bin/python -m pip install -q ./python &&
        .venv/bin/python -m pytest -q -p no:cacheprovider python/tests
} 2>&1 | tee "$pylog" || py_status=$?
# pytest's last line, e.g. "23 passed in 9.1s" or "1 failed, 22 passed in 9.3s"
awk '/ (passed|failed|error)/ && / in [0-9.]+s/ { p = 0; f = 0; for (i = 1; i <= NF; i++) { if ($(i+1) ~ /^passed/) p = $i; if ($(i+1) ~ /^(failed|errors?)/) f += $i } }
     END { printf "python tests: %d passed, %d failed\n", p, f }' "$pylog"
if [ "$py_status" -ne 0 ] && [ "$status" -eq 0 ]; then status=$py_status; fi
if [ "$lint_status" -ne 0 ] && [ "$status" -eq 0 ]; then status=$lint_status; fi
exit $status
