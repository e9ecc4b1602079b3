from os import PathLike
from typing import Any, Dict, Optional, Sequence, Union

from ._sawtooth import (
    CONSTRAINT_NAMES as CONSTRAINT_NAMES,
    CONSTRAINT_TOLERANCE as CONSTRAINT_TOLERANCE,
    LOWER_BOUNDS as LOWER_BOUNDS,
    REQUIREMENT_NAMES as REQUIREMENT_NAMES,
    REQUIREMENT_TOLERANCE as REQUIREMENT_TOLERANCE,
    UNSIMULATED_VIOLATION as UNSIMULATED_VIOLATION,
    UPPER_BOUNDS as UPPER_BOUNDS,
    VARIABLES as VARIABLES,
    Scenario as Scenario,
    __version__ as __version__,
    evaluate as evaluate,
    evaluate_problem as evaluate_problem,
    load_measured as load_measured,
    simulate as simulate,
)

_Path = Union[str, "PathLike[str]"]

def fit(data: _Path, setup: _Path, **options: Any) -> Dict[str, Any]:
    """``sawtooth fit --json`` in-process; options are its flags (pop, generations, particles,
    seed, engine, holdout, bootstrap, params=[...], objective, at={name: value}, out)."""

def diagnose(
    data: Union[_Path, Sequence[_Path]],
    setup: Union[_Path, Sequence[_Path]],
    out: Optional[_Path] = None,
    **options: Any,
) -> Dict[str, Any]:
    """``sawtooth diagnose --json`` in-process; gaps in %^2."""
