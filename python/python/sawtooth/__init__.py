"""sawtooth: the sawtooth-conveyor engine from Python.

Units: SI everywhere except where a name says otherwise. A design is the thesis's eight
variables in Table 5.3 units, in this order (see ``VARIABLES``)::

    l_c_mm, l_a_mm, l_b_mm, r_mm, omega_deg, delta_deg, v0_m_s, a_m_s2

Every function raises ``ValueError`` with the CLI's message for bad input (the field and the
rule it breaks). The same scenario and seed give the same numbers as ``sawtooth simulate``.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from typing import Any, Dict, Optional, Sequence, Union

from ._sawtooth import (  # noqa: F401
    CONSTRAINT_NAMES,
    CONSTRAINT_TOLERANCE,
    LOWER_BOUNDS,
    REQUIREMENT_NAMES,
    REQUIREMENT_TOLERANCE,
    UNSIMULATED_VIOLATION,
    UPPER_BOUNDS,
    VARIABLES,
    Scenario,
    __version__,
    _diagnose,
    _fit,
    evaluate,
    evaluate_problem,
    load_measured,
    simulate,
)

__all__ = [
    "Scenario",
    "evaluate",
    "evaluate_problem",
    "simulate",
    "load_measured",
    "fit",
    "diagnose",
    "VARIABLES",
    "LOWER_BOUNDS",
    "UPPER_BOUNDS",
    "CONSTRAINT_NAMES",
    "CONSTRAINT_TOLERANCE",
    "REQUIREMENT_NAMES",
    "REQUIREMENT_TOLERANCE",
    "UNSIMULATED_VIOLATION",
]

PathLike = Union[str, "os.PathLike[str]"]


def _list(value: Any) -> Any:
    """A list as the library's comma list; a dict as ``name=value`` pairs; else as given."""
    if isinstance(value, dict):
        return ",".join(f"{k}={v}" for k, v in value.items())
    if isinstance(value, (list, tuple)):
        return ",".join(str(v) for v in value)
    return value


def fit(data: PathLike, setup: PathLike, **options: Any) -> Dict[str, Any]:
    """Calibrate k_elastic, mu_fric (and k_drag, 1/s) against measured tooth masses.

    The library's fit, as ``sawtooth fit --data DATA --setup SETUP --json`` runs it, in-process
    (the GIL released); returns its JSON object as a dict: ``params``, ``objective``,
    ``sse_percent2`` (%^2), ``heldout``, ``uncertainty``, ``distribution``, ``metrics``.
    Keyword options are the command's flags with underscores: ``params=["k_elastic", "mu_fric"]``,
    ``objective="sse"``, ``pop``, ``generations``, ``polish``, ``particles`` (default: from the
    data), ``max_particles``, ``normalise="loaded"|"recovered"``, ``seed``, ``engine``,
    ``holdout``, ``bootstrap``,
    ``at={"k_elastic": 0.854, "mu_fric": 0.133}`` (score without fitting), ``out=DIR``.
    """
    for key in ("params", "at"):
        if key in options:
            options[key] = _list(options[key])
    if options.get("out") is not None:
        options["out"] = os.fspath(options["out"])
    return _fit(os.fspath(data), os.fspath(setup), **options)


def diagnose(
    data: Union[PathLike, Sequence[PathLike]],
    setup: Union[PathLike, Sequence[PathLike]],
    out: Optional[PathLike] = None,
    **options: Any,
) -> Dict[str, Any]:
    """Locate the sim-to-real gap and rank candidate effects (``sawtooth diagnose``).

    ``data`` and ``setup`` are one path each or equal-length lists (one pair per condition).
    Returns ``diagnosis.json``'s object as a dict (gaps in %^2). ``out`` receives report.md
    and the SVG plots; without it they go to a temporary directory that is removed.
    Keyword options are the command's flags with underscores (``effects``, ``seed``,
    ``engine``, ``particles``, ``max_particles``, ``pop``, ``generations``, ``polish``,
    ``normalise``, ``rescore_streams``, ``bootstrap``, ``params=["k_elastic", "mu_fric",
    "v_limit"]``: what every model fits); ``detection_limits=False`` leaves out each
    candidate's detection limit, ``suggest=True`` ranks the next measurement.
    """
    datas = [data] if isinstance(data, (str, os.PathLike)) else list(data)
    setups = [setup] if isinstance(setup, (str, os.PathLike)) else list(setup)
    for key in ("effects", "params"):
        if key in options:
            options[key] = _list(options[key])
    tmp = None
    if out is None:
        tmp = tempfile.mkdtemp(prefix="sawtooth-diagnose-")
        out = tmp
    try:
        return _diagnose([os.fspath(d) for d in datas], [os.fspath(s) for s in setups], os.fspath(out), **options)
    finally:
        if tmp is not None:
            shutil.rmtree(tmp, ignore_errors=True)
