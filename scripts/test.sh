#!/usr/bin/env bash
# The test command of the README: installs what the tests need, then runs them all.
# The GPU tests need a Vulkan adapter; without a GPU driver, Mesa's software Vulkan
# (lavapipe) is installed from Debian's packages. Usage: bash scripts/test.sh
# Campaigns (issue 15): tests/campaign_slurm.rs itself runs scripts/slurm-local.sh, which
# installs slurm-wlm and munge when missing and starts/stops a private single-node Slurm
# (needs root or sudo; with CI=true a Slurm that cannot start fails that test).
set -euo pipefail
cd "$(dirname "$0")/.."
export CARGO_TERM_COLOR=never

have_vulkan_icd() {
    local f
    for f in /usr/share/vulkan/icd.d/*.json /etc/vulkan/icd.d/*.json; do
        [ -e "$f" ] && return 0
    done
    return 1
}
if ! have_vulkan_icd; then
    echo "test.sh: no Vulkan driver found; installing Mesa lavapipe (mesa-vulkan-drivers libvulkan1)"
    SUDO=""
    if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq mesa-vulkan-drivers libvulkan1 >/dev/null
fi
# lavapipe's WSI probing warns without a runtime dir; the tests draw nothing on screen.
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"

log=$(mktemp)
trap 'rm -f "$log"' EXIT
status=0
cargo test --release --locked --all-targets 2>&1 | tee "$log" || status=$?
# One closing line over every test binary (cargo's own last line belongs to whichever
# target ran last, possibly one without tests).
awk '/^test result:/ { for (i = 1; i <= NF; i++) { if ($(i+1) ~ /^passed/) p += $i; if ($(i+1) ~ /^failed/) f += $i } }
     END { printf "tests: %d passed, %d failed\n", p, f }' "$log"
exit $status
