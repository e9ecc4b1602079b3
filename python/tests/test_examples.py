"""The user programs in examples/ run as their docstrings say and print what they promise."""

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_design_grid_prints_every_design_and_the_lowest_specific_work():
    out = subprocess.run(
        [sys.executable, str(ROOT / "examples" / "design_grid.py"), "--particles", "100", "--seed", "3"],
        capture_output=True, text=True, check=True,
    ).stdout
    lines = out.splitlines()
    assert lines[0] == "lunar, 100 particles per design, seed 3, cpu engine", out
    rows = [l for l in lines[2:] if not l.startswith("lowest")]
    assert len(rows) == 16, out  # the 4 x 4 grid, one row per design, valid or not
    best = lines[-1]
    assert best.startswith("lowest specific work: v0 "), out
    # the best row is one of the grid's rows: its W_spec is the smallest printed
    w = [float(r.split()[3]) for r in rows if "invalid" not in r and r.split()[3] != "nan"]
    assert w and f"{min(w):.0f} J/kg" in best, out
