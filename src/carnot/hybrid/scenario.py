"""Scenario files of systems in motion (DESIGN.md section 10): a named model, its numbers
and its state; never code.

Keys (unknown keys are errors; every message names the file and the key path)::

    format = 1                     title = "..." (optional)
    [model]       name (compass_gait | simplest_walker | rimless_wheel | double_pendulum |
                  hopping_leg),
                  parameters = {...}
                  (each model's, defaults otherwise: carnot.hybrid.models.PARAMETERS),
                  state = {q = [...], qdot = [...]} (the chart's coordinates, just after a
                  strike for a walker: the stance point at the origin; angles, or the
                  hopping leg's heights)
    [simulation]  duration (s, > 0, <= 1e6: required by carnot simulate), restitution
                  (default 0), friction (absent: the struck point sticks, as the papers
                  assume), law (newton | poisson | stronge)
    [cycle]       strikes (the period in strikes, default 1), tolerance (of |P(x) - x|,
                  default 1e-11)
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from carnot import validate
from carnot.errors import InputError
from carnot.hybrid.model import HybridModel, Law
from carnot.hybrid.models import COORDINATES, MODEL_NAMES, check_state, named_model
from carnot.io.scenario import read_scenario_data
from carnot.io.tables import known, require, table, top_level
from carnot.laws import LAW_NAMES

TOP_KEYS = ("format", "title", "model", "simulation", "cycle")
MODEL_KEYS = ("name", "parameters", "state")
SIM_KEYS = ("duration", "restitution", "friction", "law")
CYCLE_KEYS = ("strikes", "tolerance")
#: Longest duration (s) and most strikes per period.
MAX_DURATION = 1e6
MAX_STRIKES = 64


@dataclass(frozen=True, kw_only=True, eq=False)
class ModelScenario:
    """A model, its initial ``state`` x = (q, q'), the ``law`` of its strikes, the
    ``duration`` (s; ``None`` when the file gives none) and the cycle's ``strikes`` and
    ``tolerance``."""

    title: str
    model: HybridModel
    state: np.ndarray
    law: Law
    duration: float | None
    strikes: int
    tolerance: float


def is_model_scenario(data: Any) -> bool:
    """Whether parsed scenario data has a ``[model]`` table (this module's format)."""
    return isinstance(data, Mapping) and "model" in data


def load_model_scenario(path: str | Path, data: Any = None) -> ModelScenario:
    """Read a ``[model]`` scenario (``data``: already parsed), errors naming the file."""
    if data is None:
        data = read_scenario_data(path)
    try:
        return parse_model_scenario(data)
    except InputError as err:
        raise type(err)(f"{path}: {err.field}", err.problem, err.value,
                        show_value=err.show_value) from None  # fmt: skip


def parse_model_scenario(data: Any) -> ModelScenario:
    """Build a :class:`ModelScenario` from parsed data.

    >>> parse_model_scenario({"format": 1, "model": {"name": "walker"}})
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: model.name: must be one of compass_gait, simplest_walker, rimless_wheel, double_pendulum, hopping_leg, got 'walker'
    """  # noqa: E501
    top, title = top_level(data, TOP_KEYS)
    spec = table(require(top, "model", ""), "model")
    known(spec, MODEL_KEYS, "model")
    name = require(spec, "name", "model")
    if not isinstance(name, str) or name not in MODEL_NAMES:
        raise InputError("model.name", f"must be one of {', '.join(MODEL_NAMES)}", name)
    params = table(spec.get("parameters", {}), "model.parameters")
    model = named_model(name, params)
    state = _state(table(require(spec, "state", "model"), "model.state"), name)
    sim = table(top.get("simulation", {}), "simulation")
    known(sim, SIM_KEYS, "simulation")
    duration = None
    if "duration" in sim:
        duration = float(validate.positive_number(sim["duration"], "simulation.duration", "s"))
        if duration > MAX_DURATION:
            raise InputError("simulation.duration", f"must be <= {MAX_DURATION:g} s", duration)
    law = _law(sim)
    cyc = table(top.get("cycle", {}), "cycle")
    known(cyc, CYCLE_KEYS, "cycle")
    strikes = cyc.get("strikes", 1)
    if isinstance(strikes, bool) or not isinstance(strikes, int) or not 1 <= strikes <= MAX_STRIKES:
        raise InputError("cycle.strikes", f"must be an integer in [1, {MAX_STRIKES}]", strikes)
    tolerance = float(validate.number_in(cyc.get("tolerance", 1e-11), "cycle.tolerance",
                                         1e-15, 1e-3))  # fmt: skip
    return ModelScenario(title=title, model=model, state=state, law=law, duration=duration,
                         strikes=strikes, tolerance=tolerance)  # fmt: skip


def _state(spec: Mapping[str, Any], name: str) -> np.ndarray:
    known(spec, ("q", "qdot"), "model.state")
    n = len(COORDINATES[name])
    out: list[float] = []
    for key in ("q", "qdot"):
        value = require(spec, key, "model.state")
        field_ = f"model.state.{key}"
        if not isinstance(value, list) or len(value) != n:
            coords = ", ".join(COORDINATES[name])
            raise InputError(field_, f"must be a list of {n} numbers ({coords})", value)
        for k, v in enumerate(value):
            validate.finite_number(v, f"{field_}[{k}]")
        out.extend(float(v) for v in value)
    check_state(name, np.array(out[:n]))
    return np.array(out)


def _law(sim: Mapping[str, Any]) -> Law:
    e = float(validate.number_in(sim.get("restitution", 0.0), "simulation.restitution",
                                 0.0, 1.0))  # fmt: skip
    friction = sim.get("friction")
    if friction is not None:
        friction = float(validate.non_negative_number(friction, "simulation.friction"))
    law = sim.get("law", "newton")
    if law not in LAW_NAMES:
        raise InputError("simulation.law", f"must be one of {', '.join(LAW_NAMES)}", law)
    return Law(restitution=e, friction=friction, law=law)
