#!/usr/bin/env bash
# The test command of the README: installs what the tests need, then runs them all.
# Usage: bash scripts/test.sh
set -euo pipefail
cd "$(dirname "$0")/.."
export CARGO_TERM_COLOR=never
cargo test --release --locked --all-targets
