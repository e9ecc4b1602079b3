from typing import Any, Optional

import numpy as np
from pymoo.core.problem import Problem
from pymoo.core.repair import Repair

from . import Scenario

INFEASIBLE_F: float

def seed_for(base_seed: int, generation: int) -> int: ...

class SawtoothProblem(Problem):
    """8 variables (sawtooth.VARIABLES' units), objectives f_stroke (Hz) and W_spec (J/kg),
    7 inequality constraints in mm (<= 0 feasible), common random numbers per generation."""

    scenario: Scenario
    engine: str
    common_random_numbers: bool
    base_seed: int
    generation: int
    evaluations: int
    last: Optional[dict]
    def __init__(
        self,
        scenario: Optional[Scenario] = None,
        engine: str = "cpu",
        common_random_numbers: bool = True,
        **scenario_keywords: Any,
    ) -> None: ...

class ChainRepair(Repair):
    def _do(self, problem: Any, X: np.ndarray, **kwargs: Any) -> np.ndarray: ...
