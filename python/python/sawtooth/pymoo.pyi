from typing import Any, List, Optional, Sequence

import numpy as np
from pymoo.core.problem import Problem
from pymoo.core.repair import Repair

from . import Scenario

INFEASIBLE_F: float

def seed_for(base_seed: int, generation: int) -> int: ...

class SawtoothProblem(Problem):
    """8 variables (sawtooth.VARIABLES' units), objectives f_stroke (Hz) and W_spec (J/kg)
    (worst over ``slopes_deg``), 7 inequality constraints in mm (<= 0 feasible) and, with
    ``requirements``, 3 more: the relative shortfalls of feed rate, power and wire length
    (sawtooth.REQUIREMENT_NAMES); common random numbers per generation."""

    scenario: Scenario
    engine: str
    common_random_numbers: bool
    base_seed: int
    generation: int
    evaluations: int
    requirements: Optional[str]
    slopes_deg: Optional[List[float]]
    last: Optional[dict]
    def __init__(
        self,
        scenario: Optional[Scenario] = None,
        engine: str = "cpu",
        common_random_numbers: bool = True,
        requirements: Optional[str] = None,
        slopes_deg: Optional[Sequence[float]] = None,
        **scenario_keywords: Any,
    ) -> None: ...

class ChainRepair(Repair):
    def _do(self, problem: Any, X: np.ndarray, **kwargs: Any) -> np.ndarray: ...
