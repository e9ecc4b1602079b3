"""The thesis's optimisation problem (5.2-5.3, listing D.5-D.7) as a pymoo ``Problem``.

Exactly the problem the built-in ``sawtooth optimize`` solves: the eight variables in
Table 5.3 units (``sawtooth.VARIABLES``) with the listing's bounds, the objectives
f_stroke (Hz) and W_spec (J/kg) with the 2 Hz penalty of Eq. 5.17-5.18 and D.6's penalty
values for designs that fail a viability check, and seven inequality constraints
``out["G"]`` (<= 0 feasible; mm; MATLAB's tolerance 1e-3 already subtracted): the linear chain
l_b <= r <= l_a <= l_c (Eq. 5.2) and c1-c4 of D.5. Designs that violate a constraint are not
simulated (their F is 1e12, as in the built-in optimiser; pymoo ranks them by G).

Every generation is evaluated by the built-in optimiser's own code
(``sawtooth.evaluate_problem``, i.e. ``sawtooth optimize``'s ``SawtoothProblem``), so F and G
are the numbers ``optimize`` ranks by.

Requirements (``requirements="table-2.2"`` or a TOML file with a ``[requirements]`` table, as
``optimize --requirements``): three more constraints, the worst relative shortfall over the
slopes of the feed rate, the power and the wire length (``REQUIREMENT_NAMES``; <= 0 met,
``REQUIREMENT_TOLERANCE`` subtracted), and with ``slopes_deg`` every design is evaluated at
each slope (one engine job) and F is the worst over them (``optimize --alpha FROM..TO
--alpha-points K``). A design the geometric constraints keep from being simulated has unknown
shortfalls: its first requirement constraint is ``UNSIMULATED_VIOLATION``, which ranks it
behind every simulated design as in the built-in optimiser.

Common random numbers: every design of one ``evaluate`` call (one pymoo generation) sees the
same particle streams; the seed moves on with each call like the built-in optimiser's
(``seed + k * 0x9E3779B97F4A7C15`` for call k), so the streams are refreshed per generation.

``ChainRepair`` is the built-in optimiser's repair (sort the four lengths into the chain, as
gamultiobj keeps linear constraints satisfied); pass it as ``repair=`` to a pymoo algorithm to
search the same space.
"""

from __future__ import annotations

import os
from typing import Any, Optional, Sequence

import numpy as np
from pymoo.core.problem import Problem
from pymoo.core.repair import Repair

from . import (
    CONSTRAINT_TOLERANCE,
    LOWER_BOUNDS,
    REQUIREMENT_TOLERANCE,
    UNSIMULATED_VIOLATION,
    UPPER_BOUNDS,
    Scenario,
    evaluate_problem,
)

_GOLDEN = 0x9E3779B97F4A7C15
_MASK = (1 << 64) - 1
#: F of a design that violates a constraint and is not simulated (the built-in optimiser's
#: value, which ``evaluate_problem`` returns).
INFEASIBLE_F = 1e12


def seed_for(base_seed: int, generation: int) -> int:
    """The particle-stream seed of ``generation`` (the built-in optimiser's rule)."""
    return (base_seed + generation * _GOLDEN) & _MASK


class SawtoothProblem(Problem):
    """Vectorised pymoo problem: 8 variables, 2 objectives, 7 inequality constraints
    (10 with requirements).

    ``SawtoothProblem(scenario=None, engine="cpu", common_random_numbers=True,
    requirements=None, slopes_deg=None, **kw)``: ``scenario`` is a :class:`sawtooth.Scenario`;
    without one, ``**kw`` build it (``env="lunar"``, ``config=PATH``, ``particles=100``,
    ``seed=0``, ``alpha_deg=35`` ...). With ``common_random_numbers=False`` every call uses the
    scenario's seed unchanged (the same streams for the whole run). ``requirements``:
    ``"table-2.2"`` or a TOML path; ``slopes_deg``: the slopes (degrees) every design is judged
    at, e.g. ``numpy.linspace(0, 40, 5)`` for Table 2.2's req. 1.6.3 (default: the scenario's
    alpha). ``evaluations`` counts the designs evaluated so far, ``generation`` the calls;
    ``last`` holds the last call's full result dict (``sawtooth.evaluate_problem``'s arrays:
    objectives, constraints, compliance, operating point, mass flow, distribution ...).
    """

    def __init__(
        self,
        scenario: Optional[Scenario] = None,
        engine: str = "cpu",
        common_random_numbers: bool = True,
        requirements: Optional[str] = None,
        slopes_deg: Optional[Sequence[float]] = None,
        **scenario_keywords: Any,
    ) -> None:
        if scenario is None:
            scenario = Scenario(**scenario_keywords)
        elif scenario_keywords:
            raise ValueError(
                "SawtoothProblem: give either a scenario or scenario keywords, not both "
                f"(got {sorted(scenario_keywords)})"
            )
        if not isinstance(scenario, Scenario):
            raise ValueError(f"SawtoothProblem: scenario must be a sawtooth.Scenario, got {type(scenario).__name__}")
        self.scenario = scenario
        self.engine = engine
        self.common_random_numbers = common_random_numbers
        self.requirements = None if requirements is None else os.fspath(requirements)
        self.slopes_deg = None if slopes_deg is None else [float(a) for a in slopes_deg]
        self.base_seed = scenario.seed
        self.generation = 0
        self.evaluations = 0
        self.last: Optional[dict] = None
        # one call with no design checks the requirements and slopes now, not mid-run
        evaluate_problem(
            scenario, np.zeros((0, 8)), engine=engine, requirements=self.requirements, slopes_deg=self.slopes_deg
        )
        super().__init__(
            n_var=8,
            n_obj=2,
            n_ieq_constr=7 + (3 if self.requirements is not None else 0),
            xl=np.asarray(LOWER_BOUNDS, dtype=float),
            xu=np.asarray(UPPER_BOUNDS, dtype=float),
            elementwise=False,
        )

    def _evaluate(self, x, out, *args, **kwargs):
        x = np.ascontiguousarray(np.atleast_2d(x), dtype=np.float64)
        r = evaluate_problem(
            self.scenario,
            x,
            engine=self.engine,
            generation=self.generation if self.common_random_numbers else 0,
            requirements=self.requirements,
            slopes_deg=self.slopes_deg,
        )
        self.generation += 1
        self.evaluations += len(x)
        self.last = r
        out["F"] = np.array(r["objectives"], dtype=float)
        g = r["constraints_mm"] - CONSTRAINT_TOLERANCE
        if self.requirements is not None:
            req = np.array(r["requirement_constraints"], dtype=float) - REQUIREMENT_TOLERANCE
            req[~r["simulated"]] = [UNSIMULATED_VIOLATION, 0.0, 0.0]
            g = np.hstack([g, req])
        out["G"] = g


class ChainRepair(Repair):
    """Sort l_c, l_a, r, l_b into the chain l_b <= r <= l_a <= l_c, clamped to the bounds
    (the built-in optimiser's repair)."""

    def _do(self, problem, X, **kwargs):
        X = np.array(X, dtype=float, copy=True)
        lo, hi = np.asarray(LOWER_BOUNDS), np.asarray(UPPER_BOUNDS)
        v = -np.sort(-X[:, [0, 1, 3, 2]], axis=1)  # descending: l_c, l_a, r, l_b
        X[:, 0] = np.clip(v[:, 0], lo[0], hi[0])
        X[:, 1] = np.clip(v[:, 1], lo[1], hi[1])
        X[:, 3] = np.clip(v[:, 2], lo[3], hi[3])
        X[:, 2] = np.clip(v[:, 3], lo[2], hi[2])
        return X


__all__ = ["SawtoothProblem", "ChainRepair", "seed_for", "INFEASIBLE_F"]
