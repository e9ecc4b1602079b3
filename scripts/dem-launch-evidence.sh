#!/bin/bash
# The DEM evidence behind the fill-surface-loss effect (docs/physics.md, issue 32 item 3):
# a `sawtooth dem write` case of the validation rig with a trajectory dump (every 0.5 ms for
# 0.17 s from the stroke's start) inserted, run by LIGGGHTS, then each grain's speed and end
# position against its depth below the fill's free surface, beside the model's own particles.
#
#   bash scripts/dem-launch-evidence.sh [OUT_DIR] [extra `dem write` flags, e.g. --env lunar --k-drag 0]
#
# Needs liggghts, a release build and python3 with numpy. Earth: about a minute of CPU.
set -euo pipefail
out=${1:-runs/dem-launch-evidence}
shift || true
bin=${SAWTOOTH_BIN:-target/release/sawtooth}
"$bin" dem write --config data/validation/test3.toml --particles 150 "$@" --out "$out"
python3 - "$out/in.sawtooth" <<'PY'
import re, sys
p = sys.argv[1]; s = open(p).read()
dt = float(re.search(r"timestep (\S+)", s).group(1))
m = re.search(r"# the stroke \(and the return\)\nrun (\d+)\n", s)
every, more = int(round(0.0005 / dt)), int(round(0.15 / dt))
s = s.replace(m.group(0), f"# the stroke (and the return)\ndump traj all custom {every} traj.dump id x y z vx vy vz omegaz\n"
              f"run {m.group(1)}\nrun {more}\nundump traj\n", 1)
open(p, "w").write(s)
PY
(cd "$out" && nice -n 10 liggghts -in in.sawtooth > screen.out 2>&1)
"$bin" simulate --config data/validation/test3.toml --particles 600 "$@" --trajectories "$out/model-trajectories.csv" > /dev/null
python3 scripts/dem_launch_evidence.py "$out"
