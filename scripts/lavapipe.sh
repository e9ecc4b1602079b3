#!/usr/bin/env bash
# Installs Mesa's software Vulkan (lavapipe) from Debian's packages: the adapter the GPU
# tests run on where there is no GPU, and the one BENCHMARKS.md's lavapipe proxy is measured
# on. On Debian 12 (bookworm) it comes from bookworm-backports (Mesa 25), whose lavapipe
# skips a block of a shader that none of a group's eight lanes enters, as a GPU skips one no
# thread of a warp enters; Debian 12's own Mesa 22.3 runs every block whatever its lanes
# decide (BENCHMARKS.md, "The lavapipe proxy on Mesa 25"). Elsewhere (Debian 13 ships Mesa
# 25) the distribution's own package. Needs root or sudo.
# Usage: bash scripts/lavapipe.sh
set -euo pipefail
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
codename=$(. /etc/os-release && echo "${VERSION_CODENAME:-}")
packages=(mesa-vulkan-drivers libvulkan1)
if [ "$codename" = bookworm ]; then
    list=/etc/apt/sources.list.d/sawtooth-bookworm-backports.list
    echo "deb http://deb.debian.org/debian bookworm-backports main" | $SUDO tee "$list" >/dev/null
    if $SUDO apt-get update -qq &&
        DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq -t bookworm-backports "${packages[@]}" >/dev/null; then
        exit 0
    fi
    # the tests run on either; only BENCHMARKS.md's proxy figures are Mesa 25's
    echo "lavapipe.sh: bookworm-backports' Mesa did not install; taking Debian 12's own (Mesa 22.3)" >&2
    $SUDO rm -f "$list"
fi
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${packages[@]}" >/dev/null
