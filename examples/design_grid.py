"""A user program on the Python package: how launch speed and acceleration trade mass flow
against specific work around the thesis's lunar solution C.

    pip install ./python            # once, from the repository's root (docs/python.md)
    python examples/design_grid.py [--particles N] [--seed S]

Every design of the grid runs in one engine batch on the same particle streams (common random
numbers), so neighbouring cells differ by the design, not by the noise.
"""

import argparse

import numpy as np

import sawtooth

# lunar solution C in sawtooth.VARIABLES' units: l_c, l_a, l_b, r (mm), omega, delta (deg),
# v0 (m/s), a (m/s^2)
SOLUTION_C = [47.346, 46.898, 32.183, 43.687, 94.42, 11.964, 0.840, 32.051]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--particles", type=int, default=400)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()

    scenario = sawtooth.Scenario(env="lunar", particles=args.particles, seed=args.seed)
    v0 = np.linspace(0.7, 1.3, 4)  # m/s
    a = np.linspace(25.0, 55.0, 4)  # m/s^2
    grid = np.array([[*SOLUTION_C[:6], v, acc] for v in v0 for acc in a])
    r = sawtooth.evaluate(scenario, grid)

    print(f"lunar, {r['particles']} particles per design, seed {r['seed']}, {r['engine']} engine")
    print(f"{'v0 [m/s]':>9} {'a [m/s^2]':>10} {'m_dot [kg/h]':>13} {'W_spec [J/kg]':>14}  note")
    for x, valid, m_dot, w_spec, rule in zip(grid, r["valid"], r["m_dot_kg_s"], r["w_spec_j_kg"], r["invalid_rule"]):
        # an invalid design is a row with the rule it breaks, not an exception
        note = "" if valid else f"invalid: {rule}"
        print(f"{x[6]:9.2f} {x[7]:10.1f} {3600 * m_dot:13.1f} {w_spec:14.0f}  {note}")
    best = int(np.nanargmin(r["w_spec_j_kg"]))
    print(f"lowest specific work: v0 {grid[best, 6]:.2f} m/s, a {grid[best, 7]:.1f} m/s^2, "
          f"{r['w_spec_j_kg'][best]:.0f} J/kg at {3600 * r['m_dot_kg_s'][best]:.1f} kg/h")


if __name__ == "__main__":
    main()
