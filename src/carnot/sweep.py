"""Parameter sweeps: one scenario, many impacts (issue #5, items 4 and 5).

A sweep varies numbers of a scenario file, named by key paths (``contacts.0.restitution``,
``bodies.ball.velocity.2``, ``bodies.ball.inertia.0.1``: both symmetric entries), over a
grid (``--vary KEY=START:STOP:COUNT``: ``numpy.linspace``, several keys make a Cartesian
product, the first varying slowest) or by Monte Carlo (``--random KEY=DIST(...)`` with
``--samples N --seed S``). Both may be given: every grid point then gets the same ``N``
random samples (common random numbers, so that differences between grid points are not
sampling noise), rows ordered grid point by grid point.

Row ``i`` is a pure function of the plan and ``i``: grid values by ``numpy.unravel_index``,
random values from fixed blocks of :data:`RANDOM_BLOCK` samples, block ``k`` drawn from
``SeedSequence(seed, spawn_key=(k,))`` (what ``SeedSequence(seed).spawn`` gives its ``k``-th
child). Results therefore do not depend on the chunk size, the number of threads or the
scheduler, and a Dask task regenerates its own rows from its chunk index (nothing large is
shipped).

Two routes compute a chunk, with the same columns:

* the batch kernel (:func:`carnot.batch.point_impacts`), for one point contact between the
  scenario's bodies, under any law and friction (millions of impacts per second);
* otherwise a loop over :func:`carnot.solve_impact`, one row at a time (several contacts,
  constraints, a patch, a given impulse: slow, some thousand impacts per second or fewer
  with friction).

A simulation scenario (a ``[simulation]`` table, DESIGN.md section 8) takes a third route:
each row is one run of :func:`carnot.simulate.run`, and its columns are the quantities the
sweep records (``record``: :mod:`carnot.simulate.quantities`: overturned, maximum tilt,
number of impacts, energies, ...). Runs are long and hold the interpreter, so on local
cores they run in worker processes, not threads.

A model scenario (a ``[model]`` table, DESIGN.md section 10) takes a fourth route, ``cycle``:
each row is one :func:`carnot.hybrid.cycle.find_cycle` from the file's state, and its columns
are the orbit's period, state, Floquet multipliers (real and imaginary parts, largest modulus
first), the largest modulus, stability, the residual and the energy per period, so that a
bifurcation diagram over a slope is one sweep (``--plot``: :func:`carnot.plot_sweep.
plot_sweep`). Each row starts from the same guess (a row is a function of the plan and its
index alone, whatever the chunks): a row whose Newton iteration does not converge from there
is a failed row, its reason in ``error``. A section 8 scenario of free bodies with a ``[cycle]``
table takes the same road (``free_cycle``: :func:`carnot.simulate.cycle.find_cycle` per row,
the ball on a vibrating table over its amplitude).

Every varied value is validated as the scenario loader validates the file: the ends of each
range (and, for a few keys, every corner of the ranges) are put into the scenario and parsed
before anything runs, and each chunk checks its rows again (a normal that passes through
zero, an inertia tensor that stops being realizable).

A row that cannot be computed is never written as numbers silently: when any of its results
is not finite (or, on the ``solve_impact`` loop, the solver refuses it for a reason that is
not the input's, such as a jam), its result columns are written as NaN, the ``error`` column
names the reason (``""`` for a computed row), and the run's report counts it
(:attr:`SweepReport.failed`; ``carnot sweep`` prints a warning line on stderr). Inputs beyond
the loader's magnitude bounds (:mod:`carnot.validate`) are refused like any other bad value.

This module is a front end like the command line: it uses the scenario loader
(:mod:`carnot.io.scenario`) and the writers (:mod:`carnot.io.sweep_files`); the core does
not import it.
"""

from __future__ import annotations

import copy
import functools
import itertools
import math
import os
import re
import time
from collections import deque
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from carnot.errors import CarnotError, InputError
from carnot.validate import MAX_MAGNITUDE, MIN_SCALE

#: Monte Carlo samples per random block (a property of the plan, not of the chunks).
RANDOM_BLOCK = 16384
#: Rows per chunk: the batch kernel's, the ``solve_impact`` loop's (a progress step), and the
#: simulations' (each row a whole run).
CHUNK_BATCH = 16384
CHUNK_SOLVE = 512
CHUNK_SIMULATE = 4
#: Up to this many rows a sweep takes the ``solve_impact`` loop where a compiled kernel would
#: serve (``prepare_sweep(..., compiled=True)`` forces the kernel). Measured on 2 cores: a
#: cold compile of the one-contact kernel takes 9-36 s (frictionless to Coulomb), and a warm
#: cache's 1000 rows 0.46 s, while the loop does 1000 rows in 0.38 s (a ball) to 0.83 s (a rod
#: on a rough floor); the multi-contact kernel's cold compile takes 85-115 s, and the loop
#: 1-150 ms a row (a box landing on 4 corners), so 100 rows stay below 15 s.
UNCOMPILED_ROWS = {"batch": 1000, "multi": 100}
#: The batch kernel's per-impact flags, in the order of the ``warnings`` column's bits.
FLAGS = ("not_approaching", "negative_normal_impulse", "friction_insufficient", "energy_gain")
#: The Coulomb law's own flags in the ``warnings`` column: (bit of ``law_flags``, the name
#: the single-impact solver gives it). The law's energy gain is ``energy_gain`` already.
LAW_FLAGS = ((1, "normal_energy_gain"), (4, "jam"), (8, "integration_step_limit"))
#: Fields that are positive physical scales (at least carnot.validate.MIN_SCALE).
_SCALES = {"mass", "radius", "length", "size"}
#: Keys a body or contact may lack in the file, with the value the loader then uses.
_DEFAULTS = {"position": [0.0, 0.0, 0.0], "velocity": [0.0, 0.0, 0.0],
             "angular_velocity": [0.0, 0.0, 0.0], "friction": 0.0}  # fmt: skip
#: Scalar bounds of fields, for distributions without bounds: (low, high, low included).
_BOUNDS = {"mass": (0.0, math.inf, False), "restitution": (0.0, 1.0, True),
           "friction": (0.0, math.inf, True), "radius": (0.0, math.inf, False),
           "length": (0.0, math.inf, False), "inner_radius": (0.0, math.inf, True),
           "size": (0.0, math.inf, False)}  # fmt: skip


# ---------------------------------------------------------------------------------------------
# The plan: what varies, and how


@dataclass(frozen=True, kw_only=True)
class GridAxis:
    """``count`` values from ``start`` to ``stop`` (both included; ``stop < start`` runs
    down) of the scenario value at ``key``.

    >>> GridAxis(key="contacts.0.restitution", start=0.0, stop=1.0, count=3).values().tolist()
    [0.0, 0.5, 1.0]
    """

    key: str
    start: float
    stop: float
    count: int
    spec: str = ""

    def values(self) -> np.ndarray:
        return np.linspace(self.start, self.stop, self.count)

    def extremes(self) -> tuple[float, float]:
        if self.count == 1:  # linspace(start, stop, 1) is [start]
            return self.start, self.start
        return min(self.start, self.stop), max(self.start, self.stop)


@dataclass(frozen=True, kw_only=True)
class Distribution:
    """A distribution for Monte Carlo: ``uniform(low, high)``, ``loguniform(low, high)``
    (``0 < low``), ``normal(mu, sigma)``, ``lognormal(mu, sigma)`` (of the logarithm, as
    NumPy's), ``truncnorm(mu, sigma, low, high)`` (a normal restricted to ``[low, high]``,
    drawn by inverting its distribution function).

    >>> parse_distribution("truncnorm(0.5, 0.2, 0, 1)", "e").support()
    (0.0, 1.0)
    """

    name: str
    params: tuple[float, ...]

    def support(self) -> tuple[float, float]:
        """The smallest interval that holds every draw."""
        p = self.params
        if self.name in ("uniform", "loguniform", "truncnorm"):
            return p[-2], p[-1]
        if self.name == "lognormal":
            return 0.0, math.inf
        return -math.inf, math.inf

    def draw(self, gen: np.random.Generator, size: int) -> np.ndarray:
        p = self.params
        if self.name == "uniform":
            return gen.uniform(p[0], p[1], size)
        if self.name == "loguniform":
            return np.exp(gen.uniform(math.log(p[0]), math.log(p[1]), size))
        if self.name == "normal":
            return gen.normal(p[0], p[1], size)
        if self.name == "lognormal":
            return gen.lognormal(p[0], p[1], size)
        return _truncnorm(gen.random(size), *p)

    def __str__(self) -> str:
        return f"{self.name}({', '.join(f'{x:g}' for x in self.params)})"


def _truncnorm(u: np.ndarray, mu: float, sigma: float, low: float, high: float) -> np.ndarray:
    """Inverse distribution function of a normal truncated to [low, high], at ``u``. In the
    upper tail the mirrored form keeps its precision (ndtr(a) rounds to 1 there)."""
    from scipy.special import ndtr, ndtri

    a, b = (low - mu) / sigma, (high - mu) / sigma
    if a > 0:  # mirror: -x is truncated to [-b, -a], where ndtr is accurate
        lo, hi = ndtr(-b), ndtr(-a)
        x = -ndtri(hi - u * (hi - lo))
    else:
        lo, hi = ndtr(a), ndtr(b)
        x = ndtri(lo + u * (hi - lo))
    return np.clip(mu + sigma * x, low, high)


_DISTRIBUTIONS = {"uniform": 2, "loguniform": 2, "normal": 2, "lognormal": 2, "truncnorm": 4}


def parse_distribution(text: str, field_: str) -> Distribution:
    """``NAME(ARGS)`` -> a validated :class:`Distribution`.

    >>> parse_distribution("normal(1, 0)", "--random v")
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: --random v: normal(mu, sigma) needs sigma > 0, got 'normal(1, 0)'
    """
    match = re.fullmatch(r"\s*([a-z_]+)\s*\((.*)\)\s*", text)
    if match is None or match.group(1) not in _DISTRIBUTIONS:
        raise InputError(field_, "must be DIST(ARGS) with DIST one of uniform(low, high), "
                         "loguniform(low, high), normal(mu, sigma), lognormal(mu, sigma), "
                         "truncnorm(mu, sigma, low, high)", text)  # fmt: skip
    name = match.group(1)
    try:
        params = tuple(float(x) for x in match.group(2).split(","))
    except ValueError:
        raise InputError(field_, f"{name}(...) takes numbers", text) from None
    if len(params) != _DISTRIBUTIONS[name] or not all(map(math.isfinite, params)):
        raise InputError(field_, f"{name} takes {_DISTRIBUTIONS[name]} finite numbers", text)
    if name in ("normal", "lognormal", "truncnorm") and not params[1] > 0:
        raise InputError(field_, f"{name}(mu, sigma{', ...' * (name == 'truncnorm')}) needs "
                         "sigma > 0", text)  # fmt: skip
    if name in ("uniform", "loguniform", "truncnorm") and not params[-2] < params[-1]:
        raise InputError(field_, f"{name}: needs low < high", text)
    if name == "loguniform" and not params[0] > 0:
        raise InputError(field_, "loguniform(low, high) needs 0 < low", text)
    return Distribution(name=name, params=params)


@dataclass(frozen=True, kw_only=True)
class RandomAxis:
    """The scenario value at ``key`` drawn from ``distribution``."""

    key: str
    distribution: Distribution
    spec: str = ""

    def extremes(self) -> tuple[float, float]:
        return self.distribution.support()


def _canonical_key(key: str) -> str:
    """``contacts[0].restitution`` and ``contacts.0.restitution`` name the same value."""
    return re.sub(r"\[(\d+)\]", r".\1", key.strip())


def parse_vary(spec: str) -> GridAxis:
    """``KEY=START:STOP:COUNT`` -> :class:`GridAxis`.

    >>> parse_vary("bodies.ball.velocity.2=-1:-5:5").values().tolist()
    [-1.0, -2.0, -3.0, -4.0, -5.0]
    >>> parse_vary("contacts.0.restitution=0:1:2.5")
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: --vary contacts.0.restitution: COUNT must be an integer >= 1, got '2.5'
    """  # noqa: E501
    key, eq, rest = spec.partition("=")
    key = _canonical_key(key)
    parts = rest.split(":")
    if not eq or not key or len(parts) != 3:
        raise InputError("--vary", "must be KEY=START:STOP:COUNT", spec)
    field_ = f"--vary {key}"
    try:
        start, stop = float(parts[0]), float(parts[1])
    except ValueError:
        raise InputError(field_, "START and STOP must be numbers", rest) from None
    if not (math.isfinite(start) and math.isfinite(stop)):
        raise InputError(field_, "START and STOP must be finite", rest)
    if not re.fullmatch(r"\s*\+?\d+\s*", parts[2]) or int(parts[2]) < 1:
        raise InputError(field_, "COUNT must be an integer >= 1", parts[2])
    return GridAxis(key=key, start=start, stop=stop, count=int(parts[2]), spec=spec)


def parse_random(spec: str) -> RandomAxis:
    """``KEY=DIST(ARGS)`` -> :class:`RandomAxis`.

    >>> parse_random("contacts.0.friction=uniform(0, 0.5)").distribution
    Distribution(name='uniform', params=(0.0, 0.5))
    """
    key, eq, rest = spec.partition("=")
    key = _canonical_key(key)
    if not eq or not key:
        raise InputError("--random", "must be KEY=DIST(ARGS)", spec)
    return RandomAxis(key=key, distribution=parse_distribution(rest, f"--random {key}"),
                      spec=spec)  # fmt: skip


@dataclass(frozen=True, kw_only=True)
class SweepPlan:
    """The values of every row: a grid (possibly empty) times ``samples`` Monte Carlo draws
    (1 and no random axes: a pure grid). Row ``i`` is grid point ``i // samples``, sample
    ``i % samples``.

    >>> plan = make_plan(vary=["contacts.0.restitution=0:1:3", "bodies.b.mass=1:2:2"])
    >>> plan.rows, plan.values(0, plan.rows)["bodies.b.mass"].tolist()
    (6, [1.0, 2.0, 1.0, 2.0, 1.0, 2.0])
    """

    grid: tuple[GridAxis, ...] = ()
    random: tuple[RandomAxis, ...] = ()
    samples: int = 1
    seed: int = 0

    @property
    def keys(self) -> tuple[str, ...]:
        return tuple(a.key for a in self.grid) + tuple(a.key for a in self.random)

    @property
    def grid_shape(self) -> tuple[int, ...]:
        return tuple(a.count for a in self.grid)

    @property
    def rows(self) -> int:
        return math.prod(self.grid_shape) * self.samples

    def values(self, start: int, stop: int) -> dict[str, np.ndarray]:
        """The varied values of rows ``start`` to ``stop`` (excluded), by key."""
        rows = np.arange(start, stop, dtype=np.int64)
        out: dict[str, np.ndarray] = {}
        if self.grid:
            index = np.unravel_index(rows // self.samples, self.grid_shape)
            for axis, idx in zip(self.grid, index, strict=True):
                out[axis.key] = axis.values()[idx]
        if self.random:
            sample = rows % self.samples
            blocks = sample // RANDOM_BLOCK
            for r_axis in self.random:
                out[r_axis.key] = np.empty(len(rows))
            for block in np.unique(blocks):
                drawn = self.random_block(int(block))
                here = blocks == block
                for r_axis, values in zip(self.random, drawn, strict=True):
                    out[r_axis.key][here] = values[sample[here] % RANDOM_BLOCK]
        return out

    def random_block(self, block: int) -> list[np.ndarray]:
        """Samples ``block * RANDOM_BLOCK`` onwards of every random axis (in order)."""
        gen = np.random.Generator(np.random.PCG64(np.random.SeedSequence(
            self.seed, spawn_key=(block,))))  # fmt: skip
        return [axis.distribution.draw(gen, RANDOM_BLOCK) for axis in self.random]


def make_plan(
    *,
    vary: Sequence[str] = (),
    random: Sequence[str] = (),
    samples: int | None = None,
    seed: int | None = None,
) -> SweepPlan:
    """Parse and check the ``--vary`` and ``--random`` specifications.

    >>> make_plan(random=["contacts.0.friction=uniform(0, 1)"])
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: --samples: is required with --random (the number of Monte Carlo samples)
    """  # noqa: E501
    grid = tuple(parse_vary(s) for s in vary)
    rand = tuple(parse_random(s) for s in random)
    if not grid and not rand:
        raise InputError("sweep", "nothing varies: give --vary KEY=START:STOP:COUNT or "
                         "--random KEY=DIST(...)", show_value=False)  # fmt: skip
    keys = [a.key for a in grid] + [r.key for r in rand]
    for key in keys:
        if keys.count(key) > 1:
            raise InputError(key, "is varied twice (give it once, with --vary or --random)", key)
    if rand and samples is None:
        raise InputError("--samples", "is required with --random (the number of Monte Carlo "
                         "samples)", show_value=False)  # fmt: skip
    if not rand and samples is not None:
        raise InputError("--samples", "goes with --random", samples)
    if not rand and seed is not None:
        raise InputError("--seed", "goes with --random", seed)
    if samples is not None and (isinstance(samples, bool) or int(samples) != samples
                                or samples < 1):  # fmt: skip
        raise InputError("--samples", "must be an integer >= 1", samples)
    if seed is not None and (isinstance(seed, bool) or int(seed) != seed or seed < 0):
        raise InputError("--seed", "must be an integer >= 0", seed)
    return SweepPlan(grid=grid, random=rand, samples=int(samples or 1), seed=int(seed or 0))


# ---------------------------------------------------------------------------------------------
# The scenario: key paths, validation, the two routes


def _spec_of(plan: SweepPlan, key: str) -> str:
    for a in plan.grid:
        if a.key == key:
            return f"--vary {a.spec or key}"
    for r in plan.random:
        if r.key == key:
            return f"--random {r.spec or key}"
    return key


def _resolve(data: Mapping[str, Any], key: str) -> tuple[Any, ...]:
    """The path of ``key`` in the scenario's data, checked to name one number (or a value the
    loader defaults, such as an absent ``velocity``)."""
    parts = key.split(".")
    node: Any = data
    path: list[Any] = []
    for depth, part in enumerate(parts):
        here = ".".join(parts[:depth]) or "the scenario"
        if isinstance(node, Mapping):
            if part not in node:
                if part in _DEFAULTS and _default_applies(path, node, part):
                    node = copy.deepcopy(_DEFAULTS[part])
                    path.append(part)
                    continue
                known = ", ".join(map(str, node)) or "none"
                raise InputError(key, f"names nothing in the scenario: {here} has no "
                                 f"{part!r} (it has: {known})", show_value=False)  # fmt: skip
            node = node[part]
            path.append(part)
        elif isinstance(node, list):
            if not re.fullmatch(r"\d+", part):
                raise InputError(key, f"{here} is a list: give an index, not {part!r}",
                                 show_value=False)  # fmt: skip
            if int(part) >= len(node):
                raise InputError(key, f"index {part} is out of range ({here} has "
                                 f"{len(node)} entries)", show_value=False)  # fmt: skip
            node = node[int(part)]
            path.append(int(part))
        else:
            raise InputError(key, f"{here} is a single value, it has no {part!r}", node)
    if isinstance(node, (list, Mapping)):
        raise InputError(key, "is not a number (a list or table: add an index or a key)",
                         node)  # fmt: skip
    if isinstance(node, bool) or not isinstance(node, (int, float)):
        raise InputError(key, "is not a number", node)
    return tuple(path)


def _default_applies(path: list[Any], node: Mapping[str, Any], part: str) -> bool:
    """A defaulted key belongs to a movable body (vectors) or a contact (friction)."""
    if len(path) != 2:
        return False
    if path[0] == "bodies":
        return part != "friction" and not node.get("fixed", False)
    return path[0] == "contacts" and part == "friction"


def _set(data: Any, path: tuple[Any, ...], value: float) -> None:
    node: Any = data
    for part in path[:-1]:
        if isinstance(node, dict) and part not in node:  # an absent, defaulted key
            node[part] = copy.deepcopy(_DEFAULTS[part])
        node = node[part]
    node[path[-1]] = float(value)
    if len(path) == 5 and path[2] == "inertia":  # a tensor entry: both symmetric entries
        data["bodies"][path[1]]["inertia"][path[4]][path[3]] = float(value)


def _substituted(data: Mapping[str, Any], paths: Mapping[str, tuple[Any, ...]],
                 values: Mapping[str, float]) -> Any:  # fmt: skip
    out: Any = copy.deepcopy(dict(data))
    for key, value in values.items():
        _set(out, paths[key], value)
    return out


@dataclass(frozen=True, kw_only=True, eq=False)
class Column:
    """An output column: ``kind`` ``"float"`` (float64), ``"bool"`` or ``"category"`` (a
    string from a small set: int codes plus their names)."""

    name: str
    kind: str


@dataclass(frozen=True, kw_only=True, eq=False)
class Chunk:
    """Rows ``start`` to ``stop`` of a sweep: ``columns`` by name (float or bool arrays; a
    category column holds int32 codes into ``categories[name]``)."""

    start: int
    stop: int
    columns: dict[str, np.ndarray]
    categories: dict[str, tuple[str, ...]] = field(default_factory=dict)
    route: str = "batch"


@dataclass(frozen=True, kw_only=True, eq=False)
class Sweep:
    """A scenario with a plan, validated: everything a worker needs to compute any chunk
    (small: it is what a Dask task receives). ``route`` is ``"batch"`` or ``"solve"``."""

    source: str
    data: Mapping[str, Any]
    plan: SweepPlan
    paths: Mapping[str, tuple[Any, ...]]
    route: str
    why_solve: str
    columns: tuple[Column, ...]
    #: Simulations only: the folder relative paths start from (a ground-motion record) and
    #: the quantities recorded per run.
    base: str = "."
    record: tuple[str, ...] = ()

    @property
    def rows(self) -> int:
        return self.plan.rows

    def chunk(self, start: int, stop: int, *, parallel: bool = True) -> Chunk:
        """Compute rows ``start`` to ``stop``; ``parallel=False`` when several threads of the
        caller run chunks at once (Numba's parallel kernels must not run concurrently)."""
        values = self.plan.values(start, stop)
        if self.route == "batch":
            return _batch_chunk(self, start, stop, values, parallel)
        if self.route == "multi":
            return _multi_chunk(self, start, stop, values)
        if self.route == "simulate":
            return _simulate_chunk(self, start, stop, values)
        if self.route == "cycle":
            return _cycle_chunk(self, start, stop, values)
        if self.route == "free_cycle":
            return _free_cycle_chunk(self, start, stop, values)
        return _solve_chunk(self, start, stop, values)


def prepare_sweep(data: Any, plan: SweepPlan, source: str = "<scenario>",
                  record: Sequence[str] = (), *,
                  compiled: bool | None = None) -> Sweep:  # fmt: skip
    """Check ``plan`` against the scenario's parsed data and choose the route (``record``:
    the quantities of each run of a simulation scenario, all by default; see
    :mod:`carnot.simulate.quantities`).

    ``compiled``: ``None`` (the default) takes a compiled kernel only for more rows than
    :data:`UNCOMPILED_ROWS` (fewer finish on the ``solve_impact`` loop before a cold kernel
    would have compiled); ``True`` takes it whenever the scenario fits it; ``False`` never.

    >>> from carnot.io.scenario import read_scenario_data
    >>> data = read_scenario_data("examples/ball_on_floor.toml")
    >>> prepare_sweep(data, make_plan(vary=["contacts.0.restitution=0:1.5:4"]))
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: --vary contacts.0.restitution=0:1.5:4: contacts[0].restitution: must be in [0, 1], got 1.5
    """  # noqa: E501
    from carnot.io.scenario import parse_scenario

    if isinstance(data, Mapping) and "model" in data:
        if record:
            raise InputError("--record", "goes with a simulation scenario (a [simulation] "
                             "table); a [model] sweep records its orbit", ",".join(record))
        return _prepare_cycle(data, plan, source)
    if isinstance(data, Mapping) and "simulation" in data and "cycle" in data:
        if record:
            raise InputError("--record", "goes with a simulation scenario without [cycle]; "
                             "a [cycle] sweep records its orbit", ",".join(record))
        return _prepare_free_cycle(data, plan, source)
    if isinstance(data, Mapping) and "simulation" in data:
        return _prepare_simulation(data, plan, source, record)
    if record:
        raise InputError("--record", "goes with a simulation scenario (a [simulation] table)",
                         ",".join(record))  # fmt: skip
    problem = parse_scenario(data, source)
    paths = {key: _resolve_named(data, key, plan) for key in plan.keys}
    _check_ranges(data, plan, paths, source)
    route, why = _route(problem, paths, plan)
    if route in UNCOMPILED_ROWS and compiled is not True:
        if compiled is False:
            route, why = "solve", "compiled=False"
        elif plan.rows <= UNCOMPILED_ROWS[route]:
            route, why = "solve", (
                f"{plan.rows} rows (at most {UNCOMPILED_ROWS[route]}): the solve_impact loop "
                f"finishes before the {route} kernel would compile on a cold cache")
    return Sweep(source=source, data=data, plan=plan, paths=paths, route=route, why_solve=why,
                 columns=_columns(problem, plan))  # fmt: skip


def _resolve_named(data: Any, key: str, plan: SweepPlan) -> tuple[Any, ...]:
    try:
        return _resolve(data, key)
    except InputError as err:
        raise InputError(f"{_spec_of(plan, key).split('=')[0]}", err.problem, err.value,
                         show_value=err.show_value) from None  # fmt: skip


def _check_ranges(data: Any, plan: SweepPlan, paths: Mapping[str, tuple[Any, ...]],
                  source: str, parse_scenario: Callable[..., Any] | None = None
                  ) -> None:  # fmt: skip
    """Every value a range can reach must be one the loader accepts: unbounded distributions
    for bounded fields are refused; the ends of each range, alone and (for up to 10 keys)
    in every combination, are parsed like a file (by ``parse_scenario``: the bodies'
    loader unless given)."""
    if parse_scenario is None:
        from carnot.io.scenario import parse_scenario as parse_bodies

        parse_scenario = parse_bodies

    ends: dict[str, list[float]] = {}
    axes: list[GridAxis | RandomAxis] = [*plan.grid, *plan.random]
    for axis in axes:
        low, high = axis.extremes()
        name = str(paths[axis.key][-2 if isinstance(paths[axis.key][-1], int) else -1])
        if name in _BOUNDS and (math.isinf(low) or math.isinf(high)):
            b_low, b_high, closed = _BOUNDS[name]
            bound = (f"in [{b_low:g}, {b_high:g}]" if math.isfinite(b_high)
                     else f"{'>=' if closed else '>'} {b_low:g}")  # fmt: skip
            if (math.isinf(low) and math.isfinite(b_low)) or (
                math.isinf(high) and math.isfinite(b_high)
            ):
                assert isinstance(axis, RandomAxis)
                raise InputError(
                    f"--random {axis.key}",
                    f"must be {bound}, but {axis.distribution} draws values without that "
                    "bound (use uniform(low, high) or truncnorm(mu, sigma, low, high))",
                    axis.spec.partition("=")[2],
                )
        finite = sorted({x for x in (low, high) if math.isfinite(x)})
        if not finite:  # an unbounded field with an unbounded draw: its centre stands in
            finite = [axis.distribution.params[0]] if isinstance(axis, RandomAxis) else []
        ends[axis.key] = finite
    for key, vals in ends.items():  # one key at a time: the message names that key
        for value in vals:
            _parse_or_raise(parse_scenario, data, paths, {key: value}, source,
                            _spec_of(plan, key))  # fmt: skip
    if 1 < len(ends) <= 10:  # corners: keys that bound each other (inner radius, inertia)
        keys = list(ends)
        for combo in itertools.product(*(ends[k] for k in keys)):
            _parse_or_raise(
                parse_scenario,
                data,
                paths,
                dict(zip(keys, combo, strict=True)),
                source,
                "the ranges' corner "
                + ", ".join(f"{k}={v:g}" for k, v in zip(keys, combo, strict=True)),
            )


def _parse_or_raise(parse: Callable[..., Any], data: Any, paths: Mapping[str, tuple[Any, ...]],
                    values: Mapping[str, float], source: str, where: str) -> Any:  # fmt: skip
    try:
        return parse(_substituted(data, paths, values), source)
    except InputError as err:
        field_ = err.field.removeprefix(f"{source}: ")
        raise InputError(f"{where}: {field_}", err.problem, err.value,
                         show_value=err.show_value) from None  # fmt: skip


#: Key paths the batch route can take: (table, field) of a body or of contacts.0.
_BATCH_BODY = {"mass", "position", "velocity", "angular_velocity", "inertia"}
_BATCH_CONTACT = {"restitution", "friction", "point", "normal"}


def _route(problem: Any, paths: Mapping[str, tuple[Any, ...]], plan: SweepPlan
           ) -> tuple[str, str]:  # fmt: skip
    """``("batch", "")``, ``("multi", "")`` or ``("solve", why)``."""
    if len(problem.contacts) >= 2 and not problem.constraints:
        why = _why_not_multi(problem, paths)
        return ("multi", "") if not why else ("solve", why)
    if len(problem.contacts) != 1 or problem.constraints:
        return "solve", "the batch kernel takes exactly one contact and no constraints"
    c = problem.contacts[0]
    if c.patch is not None or c.is_given:
        return "solve", "the batch kernel takes no patch and no given impulse"
    movable = {n for n, b in problem.bodies.items() if not b.fixed}
    if movable - {c.a, c.b}:
        return "solve", "a body outside the contact (the batch kernel sees only a and b)"
    if problem.bodies[c.a].fixed:
        return "solve", "body a of the contact is fixed"
    for key, path in paths.items():
        if path[0] == "contacts" and path[2] not in _BATCH_CONTACT:
            return "solve", f"{key} is not an input of the batch kernel"
        if path[0] == "bodies" and path[2] not in _BATCH_BODY | _shape_dims():
            return "solve", f"{key} is not an input of the batch kernel"
    return "batch", ""


@functools.cache
def _shape_dims() -> frozenset[str]:
    """The numeric dimensions of shapes (their axis and orientation are not: solve route)."""
    from carnot.model.inertia import SHAPES

    keys = {k for _, req, opt in SHAPES.values() for k in (*req, *opt)}
    return frozenset(keys - {"axis", "orientation"})


# ---------------------------------------------------------------------------------------------
# Columns


def _columns(problem: Any, plan: SweepPlan) -> tuple[Column, ...]:
    """The output columns: the varied inputs, then per contact, per constraint, per movable
    body, the energies and the flags (see the module's README section)."""
    cols = [Column(name=k, kind="float") for k in plan.keys]
    for k, c in enumerate(problem.contacts):
        pre = f"contacts.{k}."
        cols += [Column(name=pre + f"impulse_{x}", kind="float") for x in "xyz"]
        if c.patch is not None or c.moment is not None:
            cols += [Column(name=pre + f"moment_{x}", kind="float") for x in "xyz"]
        cols += [Column(name=pre + "normal_impulse", kind="float"),
                 Column(name=pre + "dissipated", kind="float"),
                 Column(name=pre + "friction_required", kind="float"),
                 Column(name=pre + "regime", kind="category")]  # fmt: skip
    for k, _ in enumerate(problem.constraints):
        cols += [Column(name=f"constraints.{k}.impulse_{x}", kind="float") for x in "xyz"]
    for name, body in problem.bodies.items():
        if not body.fixed:
            cols += [Column(name=f"bodies.{name}.velocity_after_{x}", kind="float")
                     for x in "xyz"]  # fmt: skip
            cols += [Column(name=f"bodies.{name}.angular_velocity_after_{x}", kind="float")
                     for x in "xyz"]  # fmt: skip
    cols += [
        Column(name=n, kind="float")
        for n in (
            "energy_before",
            "energy_after",
            "dissipated",
            "dissipated_theorem",
            "lost_velocities",
        )
    ]
    cols += [Column(name=f, kind="bool") for f in FLAGS]
    cols.append(Column(name="warnings", kind="category"))
    cols.append(Column(name="error", kind="category"))
    return tuple(cols)


#: A simulation's quantities that are NaN in a computed run (carnot.simulate.quantities).
_MAY_BE_NAN = ("rest_time", "impact_energy_ratio_min", "impact_energy_ratio_max")
#: The ``error`` column's reason for a row with a result that is not finite.
NON_FINITE = "non-finite result"


def _mark_failed(sweep: Sweep, cols: dict[str, np.ndarray], reasons: dict[int, str]) -> None:
    """Fill the ``error`` column (codes into :func:`_error_names`' order, by first use) and
    blank the results of failed rows: ``reasons`` (row in the chunk -> why) gathered so far,
    plus every row with a result column (not the varied inputs, not ``friction_required``,
    NaN where the contact does not stick) that is not finite."""
    varied = set(sweep.plan.keys)
    results = [c.name for c in sweep.columns
               if c.kind == "float" and c.name not in varied
               and not c.name.endswith(".friction_required")
               and not (sweep.route == "simulate" and c.name in _MAY_BE_NAN)]  # fmt: skip
    n = len(cols["warnings"])
    if sweep.route in ("cycle", "free_cycle"):  # an orbit's numbers, or its reason
        results = []
    bad = np.zeros(n, dtype=bool)
    for name in results:
        bad |= ~np.isfinite(cols[name])
    for row in np.flatnonzero(bad).tolist():
        reasons.setdefault(row, NON_FINITE)
    code = np.zeros(n, dtype=np.int32)
    names: dict[str, int] = {"": 0}
    failed = np.array(sorted(reasons), dtype=np.intp)
    for j, why in reasons.items():
        code[j] = names.setdefault(why, len(names))
    if failed.size:
        for name in results:  # a copy: a column may be a read-only view of the kernel's
            cols[name] = np.array(cols[name], dtype=float)
            cols[name][failed] = np.nan
    cols["error"] = code


def _error_names(cols: dict[str, np.ndarray], reasons: dict[int, str]) -> tuple[str, ...]:
    """The ``error`` column's categories, in code order (as :func:`_mark_failed` gave them)."""
    names: dict[str, int] = {"": 0}
    for why in reasons.values():
        names.setdefault(why, len(names))
    return tuple(sorted(names, key=names.__getitem__))


def _warning_names() -> tuple[str, ...]:
    """Code ``k`` of the batch ``warnings`` column: the flags whose bits are set in ``k``."""
    names = FLAGS + tuple(name for _, name in LAW_FLAGS)
    return tuple(",".join(f for b, f in enumerate(names) if k >> b & 1)
                 for k in range(1 << len(names)))  # fmt: skip


# ---------------------------------------------------------------------------------------------
# Route 1: the batch kernel


def _batch_chunk(sweep: Sweep, start: int, stop: int, values: Mapping[str, np.ndarray],
                 parallel: bool) -> Chunk:  # fmt: skip
    from carnot.io.scenario import parse_scenario

    n = stop - start
    problem = parse_scenario(sweep.data, sweep.source)
    c = problem.contacts[0]
    by_target: dict[tuple[Any, ...], np.ndarray] = {sweep.paths[k]: v for k, v in values.items()}

    def scalar(table: str, name: Any, key: str, base: float) -> Any:
        return by_target.get((table, name, key), base)

    def vector(table: str, name: Any, key: str, base: np.ndarray) -> Any:
        varied = [(i, by_target[(table, name, key, i)]) for i in range(3)
                  if (table, name, key, i) in by_target]  # fmt: skip
        if not varied:
            return base
        out = np.empty((n, 3))
        out[:] = base
        for i, v in varied:
            out[:, i] = v
        return out

    def bodies(name: str) -> Any:
        return _batch_bodies(problem, name, scalar, vector, sweep, by_target, n, start)

    normal = vector("contacts", 0, "normal", c.normal)
    if np.ndim(normal) == 2:
        # a zero normal: its largest |component| (a norm would overflow at 1e200: a warning)
        bad = ~(np.max(np.abs(normal), axis=1) > 0)
        if bad.any():
            _raise_row(sweep, start + int(np.argmax(bad)))
    restitution = scalar("contacts", 0, "restitution", c.restitution)
    friction = scalar("contacts", 0, "friction", c.friction)
    _check_bounds(sweep, start, values)
    from carnot.batch import point_impacts

    out = point_impacts(bodies(c.a), bodies(c.b), vector("contacts", 0, "point", c.point),
                        normal, restitution, tangential=c.tangential, friction=friction,
                        law=c.law, parallel=parallel)  # fmt: skip
    cols: dict[str, np.ndarray] = dict(values)

    def put(name: str, arr: Any) -> None:
        cols[name] = np.ascontiguousarray(np.broadcast_to(arr, (n,)))

    pre = "contacts.0."
    for i, x in enumerate("xyz"):
        put(pre + f"impulse_{x}", out.impulse[..., i])
    put(pre + "normal_impulse", out.normal_impulse)
    put(pre + "dissipated", out.dissipated_theorem)
    put(pre + "friction_required", out.friction_required)
    put(pre + "regime", np.asarray(out.regime, dtype=np.int32))
    for name, v_after, om_after in (
        (c.a, out.velocity_a, out.angular_velocity_a),
        (c.b, out.velocity_b, out.angular_velocity_b),
    ):
        if v_after is None or om_after is None:  # a fixed b
            continue
        for i, x in enumerate("xyz"):
            put(f"bodies.{name}.velocity_after_{x}", v_after[..., i])
            put(f"bodies.{name}.angular_velocity_after_{x}", om_after[..., i])
    put("energy_before", out.before)
    put("energy_after", out.after)
    put("dissipated", out.dissipated)
    put("dissipated_theorem", out.dissipated_theorem)
    put("lost_velocities", out.lost_velocities)
    code = np.zeros(n, dtype=np.int32)
    for bit, flag in enumerate(FLAGS):
        put(flag, np.asarray(getattr(out, flag), dtype=bool))
        code |= cols[flag].astype(np.int32) << bit
    law_flags = np.broadcast_to(np.asarray(out.law_flags, dtype=np.int32), (n,))
    for bit, (mask, _) in enumerate(LAW_FLAGS, start=len(FLAGS)):
        code |= ((law_flags & mask) != 0).astype(np.int32) << bit
    cols["warnings"] = code
    reasons: dict[int, str] = {}
    _mark_failed(sweep, cols, reasons)
    return Chunk(
        start=start,
        stop=stop,
        columns=cols,
        route="batch",
        categories={pre + "regime": _batch_regimes(), "warnings": _warning_names(),
                    "error": _error_names(cols, reasons)},  # fmt: skip
    )


def _check_bounds(sweep: Sweep, start: int, values: Mapping[str, np.ndarray]) -> None:
    """The varied fields' own bounds, row by row (a safety net), and the loader's magnitude
    bounds (:mod:`carnot.validate`: a normal(0, 1e200) draw)."""
    for key, v in values.items():
        name = sweep.paths[key][2]
        if name in _BOUNDS:
            low, high, closed = _BOUNDS[name]
            bad = ~(((v >= low) if closed else (v > low)) & (v <= high))
            if bad.any():
                _raise_row(sweep, start + int(np.argmax(bad)))
        # the loader's magnitude bounds (carnot.validate): a normal(0, 1e200) draw
        bad = ~(np.abs(v) <= MAX_MAGNITUDE)
        if name in _SCALES:
            bad |= ~(v >= MIN_SCALE)
        if bad.any():
            _raise_row(sweep, start + int(np.argmax(bad)))


# ---------------------------------------------------------------------------------------------
# Route 1b: the multi-contact batch kernel (carnot.batch.multi_impacts)

#: The multi-contact kernel's regime names (carnot.batch.multi.REGIME_NAMES), by code.
_MULTI_REGIMES = ("separate", "frictionless", "stick", "slip")
#: Its flags in the ``warnings`` column, in the order solve_impact reports them.
_MULTI_FLAGS = ("statically_indeterminate", "multiple_solutions", "no_solution",
                "not_converged", "separating_contact_approaches", "energy_gain")  # fmt: skip


def _why_not_multi(problem: Any, paths: Mapping[str, tuple[Any, ...]]) -> str:
    """Why two or more contacts cannot take the multi-contact batch route ("" when they can):
    point contacts between the same two bodies (``a`` movable), sliding or frictionless
    (not told to stick), under the simultaneous law, within its limits, by the solver the
    kernel compiles: the enumeration, which ``auto`` chooses within the kernel's limits
    (:func:`carnot.solvers.resolve`); not the iterative solver nor the traced families'
    enumeration of every regime, whose answers and flags may differ (the loop runs them)."""
    from carnot.batch.multi import MAX_CONTACTS, MAX_ROWS

    if problem.multiple_impact != "simultaneous":
        return "the multi-contact batch kernel solves the simultaneous law only"
    solver = problem.solver
    if solver is not None and solver.name == "iterative":
        return ("the scenario's [solver] is iterative; the multi-contact batch kernel is the "
                "enumeration")  # fmt: skip
    if solver is not None and solver.trace_families:
        return ("the scenario's [solver] traces families (every regime tried); the "
                "multi-contact batch kernel does not")  # fmt: skip
    first = problem.contacts[0]
    for c in problem.contacts:
        if c.patch is not None or c.is_given or c.sticks:
            return "the multi-contact batch kernel takes point contacts that may slip only"
        if (c.a, c.b) != (first.a, first.b):
            return "the multi-contact batch kernel takes contacts between the same two bodies"
    movable = {n for n, b in problem.bodies.items() if not b.fixed}
    if problem.bodies[first.a].fixed or movable - {first.a, first.b}:
        return "the multi-contact batch kernel takes a movable a and b (or a fixed b) only"
    k = len(problem.contacts)
    rows = k + 2 * k  # at most: every contact with friction somewhere in the sweep
    if k > MAX_CONTACTS or (rows > MAX_ROWS and any(
            c.friction > 0 or ("contacts", i, "friction") in {p[:3] for p in paths.values()}
            for i, c in enumerate(problem.contacts))):  # fmt: skip
        return "more contact rows than the multi-contact batch kernel takes"
    for key, path in paths.items():
        if path[0] == "contacts" and path[2] not in _BATCH_CONTACT:
            return f"{key} is not an input of the batch kernel"
        if path[0] == "bodies" and path[2] not in _BATCH_BODY | _shape_dims():
            return f"{key} is not an input of the batch kernel"
    return ""


def _multi_chunk(sweep: Sweep, start: int, stop: int, values: Mapping[str, np.ndarray]
                 ) -> Chunk:  # fmt: skip
    """Rows ``start`` to ``stop`` by :func:`carnot.batch.multi.multi_impacts`: the same
    columns as the ``solve_impact`` loop gives a multi-contact scenario."""
    from carnot.batch.multi import multi_impacts
    from carnot.io.scenario import parse_scenario

    n = stop - start
    problem = parse_scenario(sweep.data, sweep.source)
    contacts = problem.contacts
    by_target: dict[tuple[Any, ...], np.ndarray] = {sweep.paths[k]: v for k, v in values.items()}

    def per_row(table: str, name: Any, key: str, base: Any) -> np.ndarray:
        base = np.asarray(base, dtype=float)
        out = np.empty((n,) + base.shape)
        out[:] = base
        if base.ndim == 0:
            if (table, name, key) in by_target:
                out[:] = by_target[(table, name, key)]
            return out
        for i in range(3):
            if (table, name, key, i) in by_target:
                out[:, i] = by_target[(table, name, key, i)]
        return out

    def bodies(name: str) -> Any:
        return _batch_bodies(problem, name, per_row, per_row, sweep, by_target, n, start)

    points = np.stack([per_row("contacts", k, "point", c.point) for k, c in enumerate(contacts)],
                      axis=1)  # fmt: skip
    normals = np.stack([per_row("contacts", k, "normal", c.normal)
                        for k, c in enumerate(contacts)], axis=1)  # fmt: skip
    bad = ~(np.linalg.norm(normals, axis=2) > 0).all(axis=1)
    if bad.any():
        _raise_row(sweep, start + int(np.argmax(bad)))
    restitution = np.stack([per_row("contacts", k, "restitution", c.restitution)
                            for k, c in enumerate(contacts)], axis=1)  # fmt: skip
    friction = np.stack([per_row("contacts", k, "friction", c.friction)
                         for k, c in enumerate(contacts)], axis=1)  # fmt: skip
    _check_bounds(sweep, start, values)
    first = contacts[0]
    out = multi_impacts(bodies(first.a), bodies(first.b), points, normals, restitution,
                        friction)  # fmt: skip
    cols: dict[str, np.ndarray] = dict(values)
    for k in range(len(contacts)):
        pre = f"contacts.{k}."
        for i, x in enumerate("xyz"):
            cols[pre + f"impulse_{x}"] = np.ascontiguousarray(out.impulse[:, k, i])
        cols[pre + "normal_impulse"] = np.ascontiguousarray(out.normal_impulse[:, k])
        cols[pre + "dissipated"] = np.ascontiguousarray(out.dissipated_by_contact[:, k])
        cols[pre + "friction_required"] = np.full(n, np.nan)  # (contacts told to stick only)
        cols[pre + "regime"] = out.regime[:, k].astype(np.int32)
    for name, v_after, om_after in ((first.a, out.velocity_a, out.angular_velocity_a),
                                    (first.b, out.velocity_b, out.angular_velocity_b)):  # fmt: skip
        if v_after is None or om_after is None:
            continue
        for i, x in enumerate("xyz"):
            cols[f"bodies.{name}.velocity_after_{x}"] = np.ascontiguousarray(v_after[:, i])
            cols[f"bodies.{name}.angular_velocity_after_{x}"] = np.ascontiguousarray(
                om_after[:, i])  # fmt: skip
    cols["energy_before"], cols["energy_after"] = out.before, out.after
    cols["dissipated"], cols["dissipated_theorem"] = out.dissipated, out.dissipated_theorem
    cols["lost_velocities"] = out.lost_velocities
    size = np.linalg.norm(out.impulse, axis=2)
    cols["not_approaching"] = np.zeros(n, dtype=bool)
    cols["negative_normal_impulse"] = (out.normal_impulse < -1e-12 * size).any(axis=1)
    cols["friction_insufficient"] = np.zeros(n, dtype=bool)
    cols["energy_gain"] = np.asarray(out.energy_gain, dtype=bool)
    names: dict[str, int] = {"": 0}
    warnings = np.zeros(n, dtype=np.int32)
    flag_columns = [np.asarray(getattr(out, f), dtype=bool) for f in _MULTI_FLAGS]
    bits = sum(col.astype(np.int64) << b for b, col in enumerate(flag_columns))
    for code in np.unique(bits).tolist():
        label = ",".join(f for b, f in enumerate(_MULTI_FLAGS) if code >> b & 1)
        warnings[bits == code] = names.setdefault(label, len(names))
    cols["warnings"] = warnings
    reasons: dict[int, str] = {}
    _mark_failed(sweep, cols, reasons)
    categories: dict[str, tuple[str, ...]] = {f"contacts.{k}.regime": _MULTI_REGIMES
                                              for k in range(len(contacts))}  # fmt: skip
    categories["warnings"] = tuple(sorted(names, key=names.__getitem__))
    categories["error"] = _error_names(cols, reasons)
    return Chunk(start=start, stop=stop, columns=cols, categories=categories, route="multi")


def _batch_regimes() -> tuple[str, ...]:
    """The batch kernel's regime names, indexed by code (carnot.batch.REGIME_NAMES)."""
    from carnot.batch.laws import REGIME_NAMES

    return tuple(REGIME_NAMES.get(k, f"regime {k}") for k in range(max(REGIME_NAMES) + 1))


def _inertia(
    sweep: Sweep,
    name: str,
    body: Any,
    mass: Any,
    by_target: Mapping[tuple[Any, ...], np.ndarray],
    n: int,
    start: int,
) -> Any:
    """The body's inertia per row: scaled with a shaped body's mass, recomputed from varied
    shape dimensions (once per distinct set of dimensions), or with varied entries (both
    symmetric entries set), checked row by row like the loader checks a file."""
    from carnot.model.inertia import shape_inertia

    spec = sweep.data["bodies"][name]
    varied = {p: v for p, v in by_target.items() if p[:2] == ("bodies", name)}
    dims = {p: v for p, v in varied.items() if p[2] not in _BATCH_BODY}
    if "shape" in spec and dims:
        table = {
            k: (v if k != "size" else list(v))
            for k, v in spec.items()
            if k in _shape_dims() or k in ("axis", "orientation")
        }
        keys = sorted(dims)
        stacked = np.column_stack([dims[k] for k in keys])
        unique, inverse = np.unique(stacked, axis=0, return_inverse=True)
        per_unit = np.empty((len(unique), 3, 3))
        for row, vals in enumerate(unique):
            these = copy.deepcopy(table)
            for path, value in zip(keys, vals, strict=True):
                if len(path) == 4:
                    these[path[2]][path[3]] = float(value)
                else:
                    these[path[2]] = float(value)
            try:
                per_unit[row] = shape_inertia(spec["shape"], 1.0, **these)
            except InputError:
                _raise_row(sweep, start + int(np.argmax(inverse.ravel() == row)))
        return per_unit[inverse.ravel()] * np.asarray(mass, dtype=float).reshape(-1, 1, 1)
    if "shape" in spec and ("bodies", name, "mass") in varied:
        return body.inertia_com[None] * (np.asarray(mass) / body.mass)[:, None, None]
    entries = [(p, v) for p, v in varied.items() if p[2] == "inertia"]
    if not entries:
        return body.inertia_com
    raw = np.array(spec["inertia"], dtype=float)
    out = np.empty((n, 3, 3))
    out[:] = raw
    for path, v in entries:
        out[:, path[3], path[4]] = out[:, path[4], path[3]] = v
    # the loader's checks (validate.inertia_tensor), vectorised; its message for the first
    # row that fails
    scale = np.max(np.abs(out), axis=(1, 2))
    asym = np.max(np.abs(out - out.transpose(0, 2, 1)), axis=(1, 2)) > 1e-9 * scale
    sym = 0.5 * (out + out.transpose(0, 2, 1))
    moments = np.linalg.eigvalsh(sym)
    bad = (
        asym
        | (moments[:, 0] <= 1e-12 * scale)
        | (moments[:, 0] < MIN_SCALE)
        | ~(scale <= MAX_MAGNITUDE)
        | (moments[:, 2] > (moments[:, 0] + moments[:, 1]) * (1.0 + 1e-9))
    )
    if bad.any():
        _raise_row(sweep, start + int(np.argmax(bad)))
    return sym


def _raise_row(sweep: Sweep, row: int) -> None:
    """The loader's message for one row (its values put into the scenario), naming the row."""
    from carnot.io.scenario import parse_scenario

    values = {k: float(v[0]) for k, v in sweep.plan.values(row, row + 1).items()}
    where = f"row {row} (" + ", ".join(f"{k}={v:g}" for k, v in values.items()) + ")"
    _parse_or_raise(parse_scenario, sweep.data, sweep.paths, values, sweep.source, where)
    raise InputError(where, "is outside the values the batch kernel takes", values)


# ---------------------------------------------------------------------------------------------
# Route 2: solve_impact row by row


def _solve_chunk(sweep: Sweep, start: int, stop: int, values: Mapping[str, np.ndarray]
                 ) -> Chunk:  # fmt: skip
    from carnot.io.scenario import parse_scenario
    from carnot.solve import solve_impact

    n = stop - start
    cols = _blank_columns(sweep, n, values)
    names: dict[str, dict[str, int]] = {c.name: {} for c in sweep.columns if c.kind == "category"}

    def category(col: str, label: str) -> int:
        return names[col].setdefault(label, len(names[col]))

    reasons: dict[int, str] = {}
    for col in names:  # code 0, the value a failed row keeps: no warning, no regime
        category(col, "")
    for j in range(n):
        row = {k: float(v[j]) for k, v in values.items()}
        where = f"row {start + j} (" + ", ".join(f"{k}={v:g}" for k, v in row.items()) + ")"
        problem = _parse_or_raise(parse_scenario, sweep.data, sweep.paths, row, sweep.source,
                                  where)  # fmt: skip
        try:
            result = solve_impact(problem)
        except InputError as err:
            field_ = err.field.removeprefix(f"{sweep.source}: ")
            raise InputError(f"{where}: {field_}", err.problem, err.value,
                             show_value=err.show_value) from None  # fmt: skip
        except CarnotError as err:  # not the input's fault (a jam): this row only, reported
            reasons[j] = " ".join(str(err).split())[:200]
            continue
        for k, o in enumerate(result.contacts):
            pre = f"contacts.{k}."
            for i, x in enumerate("xyz"):
                cols[pre + f"impulse_{x}"][j] = o.impulse[i]
                if pre + f"moment_{x}" in cols:
                    cols[pre + f"moment_{x}"][j] = o.moment[i]
            cols[pre + "normal_impulse"][j] = o.normal_impulse
            cols[pre + "dissipated"][j] = o.dissipated
            if o.friction_required is not None:
                cols[pre + "friction_required"][j] = o.friction_required
            cols[pre + "regime"][j] = category(pre + "regime", o.regime)
        for k, o in enumerate(result.constraints):
            for i, x in enumerate("xyz"):
                cols[f"constraints.{k}.impulse_{x}"][j] = o.impulse[i]
        for name, motion in result.bodies.items():
            if not motion.fixed:
                for i, x in enumerate("xyz"):
                    cols[f"bodies.{name}.velocity_after_{x}"][j] = motion.velocity_after[i]
                    cols[f"bodies.{name}.angular_velocity_after_{x}"][j] = \
                        motion.angular_velocity_after[i]  # fmt: skip
        e = result.energy
        cols["energy_before"][j], cols["energy_after"][j] = e.before, e.after
        cols["dissipated"][j], cols["dissipated_theorem"][j] = e.dissipated, e.dissipated_theorem
        cols["lost_velocities"][j] = e.lost_velocities
        codes = result.flag_codes()
        for flag in FLAGS:
            cols[flag][j] = flag in codes
        cols["warnings"][j] = category("warnings", ",".join(dict.fromkeys(codes)))
    _mark_failed(sweep, cols, reasons)
    categories = {col: tuple(sorted(m, key=m.__getitem__)) for col, m in names.items()}
    categories["error"] = _error_names(cols, reasons)
    return Chunk(start=start, stop=stop, columns=cols, categories=categories, route="solve")


# ---------------------------------------------------------------------------------------------
# Route 3: simulations, one run per row


def _parse_simulation(data: Any, source: str, base: str) -> Any:
    """The simulation loader with the sweep's calling convention (module level: picklable)."""
    from carnot.simulate.scenario import parse_simulation

    return parse_simulation(data, Path(base))


def _prepare_simulation(data: Mapping[str, Any], plan: SweepPlan, source: str,
                        record: Sequence[str]) -> Sweep:  # fmt: skip
    from carnot.simulate import quantities

    wanted = quantities.check_record(record)
    base = str(Path(source).parent)
    parse = functools.partial(_parse_simulation, base=base)
    sim = _parse_or_raise(parse, data, {}, {}, source, source)
    paths = {key: _resolve_named(data, key, plan) for key in plan.keys}
    _check_ranges(data, plan, paths, source, parse)
    cols = [Column(name=k, kind="float") for k in plan.keys]
    cols += [Column(name=name, kind=kind) for name, kind in quantities.columns(sim, wanted)]
    cols += [Column(name="warnings", kind="category"), Column(name="error", kind="category")]
    return Sweep(source=source, data=data, plan=plan, paths=paths, route="simulate",
                 why_solve="", columns=tuple(cols), base=base, record=wanted)  # fmt: skip


def _blank_columns(sweep: Sweep, n: int, values: Mapping[str, np.ndarray]
                   ) -> dict[str, np.ndarray]:  # fmt: skip
    """A chunk's columns before its rows are run: the varied ``values``, every result NaN
    (False, code 0) until its row is computed."""
    cols: dict[str, np.ndarray] = {c.name: (np.zeros(n, dtype=bool) if c.kind == "bool"
                                            else np.zeros(n, dtype=np.int32)
                                            if c.kind == "category" else np.full(n, np.nan))
                                   for c in sweep.columns}  # fmt: skip
    cols.update(values)
    return cols


def _simulate_chunk(sweep: Sweep, start: int, stop: int, values: Mapping[str, np.ndarray]
                    ) -> Chunk:  # fmt: skip
    """Rows ``start`` to ``stop``: each row's scenario loaded (its values put in) and run.
    A run the simulation cannot finish (more than ``max_events``, a contact mode it does not
    handle) is a failed row, its reason in ``error``; a value the loader refuses stops the
    sweep, naming the row."""
    from carnot.simulate import quantities
    from carnot.simulate.loop import run

    n = stop - start
    cols = _blank_columns(sweep, n, values)
    warnings: dict[str, int] = {"": 0}
    reasons: dict[int, str] = {}
    parse = functools.partial(_parse_simulation, base=sweep.base)
    samples = quantities.needs_samples(sweep.record)
    for j in range(n):
        row = {k: float(v[j]) for k, v in values.items()}
        where = f"row {start + j} (" + ", ".join(f"{k}={v:g}" for k, v in row.items()) + ")"
        sim = _parse_or_raise(parse, sweep.data, sweep.paths, row, sweep.source, where)
        try:
            result = run(sim, record=samples)
        except CarnotError as err:  # max_events, a mode not handled: this row only, reported
            reasons[j] = " ".join(str(err).split())[:200]
            continue
        for name, value in quantities.measure(result, sweep.record).items():
            cols[name][j] = value
        codes = dict.fromkeys(f.code for e in result.events if e.impact is not None
                              for f in (*e.impact.result.warnings, *e.impact.flags))  # fmt: skip
        cols["warnings"][j] = warnings.setdefault(",".join(codes), len(warnings))
    _mark_failed(sweep, cols, reasons)
    return Chunk(start=start, stop=stop, columns=cols, route="simulate",
                 categories={"warnings": tuple(sorted(warnings, key=warnings.__getitem__)),
                             "error": _error_names(cols, reasons)})  # fmt: skip


# ---------------------------------------------------------------------------------------------
# Route 4: periodic orbits of a model in motion, one Newton shooting per row


def _parse_model(data: Any, source: str) -> Any:
    """The model loader with the sweep's calling convention (module level: picklable)."""
    from carnot.hybrid.scenario import parse_model_scenario

    return parse_model_scenario(data)


def _cycle_columns(scenario: Any) -> list[tuple[str, str]]:
    n = scenario.model.n
    names = scenario.model.coordinates
    cols = [("period", "float"), ("converged", "bool"), ("stable", "bool"),
            ("residual", "float"), ("iterations", "float")]  # fmt: skip
    cols += [(f"q.{c}", "float") for c in names] + [(f"qdot.{c}", "float") for c in names]
    for k in range(2 * n - 1):
        cols += [(f"multiplier_{k}.re", "float"), (f"multiplier_{k}.im", "float")]
    cols += [("max_multiplier", "float"), ("energy_impacts", "float"),
             ("potential_drop", "float")]  # fmt: skip
    return cols


def _prepare_cycle(data: Mapping[str, Any], plan: SweepPlan, source: str) -> Sweep:
    sc = _parse_or_raise(_parse_model, data, {}, {}, source, source)
    paths = {key: _resolve_named(data, key, plan) for key in plan.keys}
    _check_ranges(data, plan, paths, source, _parse_model)
    cols = [Column(name=k, kind="float") for k in plan.keys]
    cols += [Column(name=name, kind=kind) for name, kind in _cycle_columns(sc)]
    cols += [Column(name="warnings", kind="category"), Column(name="error", kind="category")]
    return Sweep(source=source, data=data, plan=plan, paths=paths, route="cycle",
                 why_solve="", columns=tuple(cols), base=str(Path(source).parent))  # fmt: skip


def _cycle_chunk(sweep: Sweep, start: int, stop: int, values: Mapping[str, np.ndarray]
                 ) -> Chunk:  # fmt: skip
    """Rows ``start`` to ``stop``: each row's model built with its values and its orbit
    sought from the file's state."""
    from carnot.hybrid.cycle import find_cycle

    n = stop - start
    cols = _blank_columns(sweep, n, values)
    warnings: dict[str, int] = {"": 0}
    reasons: dict[int, str] = {}
    for j in range(n):
        row = {k: float(v[j]) for k, v in values.items()}
        where = f"row {start + j} (" + ", ".join(f"{k}={v:g}" for k, v in row.items()) + ")"
        sc = _parse_or_raise(_parse_model, sweep.data, sweep.paths, row, sweep.source, where)
        c = find_cycle(sc.model, sc.state, sc.law, steps=sc.strikes, tolerance=sc.tolerance)
        cols["warnings"][j] = warnings.setdefault(",".join(c.flags), len(warnings))
        if not c.converged:
            reasons[j] = f"no periodic orbit from the file's state (residual {c.residual:.3g})"
            continue
        m = sc.model.n
        cols["period"][j] = c.period
        cols["converged"][j] = True
        cols["stable"][j] = bool(c.stable)
        cols["residual"][j] = c.residual
        cols["iterations"][j] = c.iterations
        for k, name in enumerate(sc.model.coordinates):
            cols[f"q.{name}"][j] = c.state[k]
            cols[f"qdot.{name}"][j] = c.state[m + k]
        if c.multipliers is not None:
            for k, z in enumerate(c.multipliers):
                cols[f"multiplier_{k}.re"][j] = z.real
                cols[f"multiplier_{k}.im"][j] = z.imag
            cols["max_multiplier"][j] = float(np.max(np.abs(c.multipliers)))
        cols["energy_impacts"][j] = c.energy["impacts"]
        cols["potential_drop"][j] = c.energy["potential_drop"]
    _mark_failed(sweep, cols, reasons)
    return Chunk(start=start, stop=stop, columns=cols, route="cycle",
                 categories={"warnings": tuple(sorted(warnings, key=warnings.__getitem__)),
                             "error": _error_names(cols, reasons)})  # fmt: skip


def _parse_free_cycle(data: Any, source: str, base: str) -> Any:
    """A free-body cycle scenario: the simulation (``duration`` not needed: each return flies
    as long as it takes) and its ``[cycle]`` settings (module level: picklable)."""
    from carnot.simulate.scenario import cycle_settings, parse_simulation

    if isinstance(data.get("simulation"), dict) and "duration" not in data["simulation"]:
        data = {**data, "simulation": {**data["simulation"], "duration": 1.0}}
    return parse_simulation(data, Path(base)), cycle_settings(data)


#: The free-body orbit's columns (the two largest multipliers: the count may differ by row,
#: as the neutral directions do).
_FREE_CYCLE_COLUMNS = (("period", "float"), ("forcing_periods", "float"), ("converged", "bool"),
                       ("stable", "bool"), ("residual", "float"), ("iterations", "float"),
                       ("multiplier_0.re", "float"), ("multiplier_0.im", "float"),
                       ("multiplier_1.re", "float"), ("multiplier_1.im", "float"),
                       ("max_multiplier", "float"), ("energy_impacts", "float"),
                       ("ground_work", "float"))  # fmt: skip


def _prepare_free_cycle(data: Mapping[str, Any], plan: SweepPlan, source: str) -> Sweep:
    base = str(Path(source).parent)
    parse = functools.partial(_parse_free_cycle, base=base)
    _parse_or_raise(parse, data, {}, {}, source, source)
    paths = {key: _resolve_named(data, key, plan) for key in plan.keys}
    _check_ranges(data, plan, paths, source, parse)
    cols = [Column(name=k, kind="float") for k in plan.keys]
    cols += [Column(name=name, kind=kind) for name, kind in _FREE_CYCLE_COLUMNS]
    cols += [Column(name="warnings", kind="category"), Column(name="error", kind="category")]
    return Sweep(source=source, data=data, plan=plan, paths=paths, route="free_cycle",
                 why_solve="", columns=tuple(cols), base=base)  # fmt: skip


def _free_cycle_chunk(sweep: Sweep, start: int, stop: int, values: Mapping[str, np.ndarray]
                      ) -> Chunk:  # fmt: skip
    """Rows ``start`` to ``stop``: each row's scenario built with its values and its orbit
    sought by :func:`carnot.simulate.cycle.find_cycle` from the file's state."""
    from carnot.simulate.cycle import find_cycle

    n = stop - start
    cols = _blank_columns(sweep, n, values)
    warnings: dict[str, int] = {"": 0}
    reasons: dict[int, str] = {}
    parse = functools.partial(_parse_free_cycle, base=sweep.base)
    for j in range(n):
        row = {k: float(v[j]) for k, v in values.items()}
        where = f"row {start + j} (" + ", ".join(f"{k}={v:g}" for k, v in row.items()) + ")"
        sim, (strikes, tolerance) = _parse_or_raise(parse, sweep.data, sweep.paths, row,
                                                    sweep.source, where)  # fmt: skip
        c = find_cycle(sim, strikes=strikes, tolerance=tolerance)
        cols["warnings"][j] = warnings.setdefault(",".join(c.flags), len(warnings))
        if not c.converged:
            reasons[j] = f"no periodic orbit from the file's state (residual {c.residual:.3g})"
            continue
        cols["period"][j] = c.period
        cols["forcing_periods"][j] = c.forcing_periods
        cols["converged"][j] = True
        cols["stable"][j] = bool(c.stable)
        cols["residual"][j] = c.residual
        cols["iterations"][j] = c.iterations
        if c.multipliers is not None and len(c.multipliers):
            order = np.argsort(-np.abs(c.multipliers), kind="stable")
            for k, z in enumerate(np.asarray(c.multipliers)[order][:2]):
                cols[f"multiplier_{k}.re"][j] = z.real
                cols[f"multiplier_{k}.im"][j] = z.imag
            cols["max_multiplier"][j] = float(np.max(np.abs(c.multipliers)))
        cols["energy_impacts"][j] = c.energy.get("impacts", np.nan)
        cols["ground_work"][j] = c.energy.get("ground_work", np.nan)
    _mark_failed(sweep, cols, reasons)
    return Chunk(start=start, stop=stop, columns=cols, route="free_cycle",
                 categories={"warnings": tuple(sorted(warnings, key=warnings.__getitem__)),
                             "error": _error_names(cols, reasons)})  # fmt: skip


# ---------------------------------------------------------------------------------------------
# Running: threads or Dask, chunks written in order


@dataclass(frozen=True, kw_only=True)
class SweepReport:
    """What a run did: ``rows`` written to ``path`` in ``chunks`` chunks, by ``route``
    (``"batch"``, ``"solve"``, or ``"batch+solve"`` when some chunks needed the loop), in
    ``seconds`` of wall time, on ``runner`` (``"threads(N)"`` or ``"dask(ADDRESS)"``)."""

    path: str
    rows: int
    chunks: int
    route: str
    seconds: float
    runner: str
    flag_counts: dict[str, int]
    #: Rows that could not be computed (results NaN, the reason in the ``error`` column).
    failed: int = 0


def chunk_bounds(rows: int, chunk_size: int) -> list[tuple[int, int]]:
    """``[(start, stop), ...]`` covering ``rows`` rows.

    >>> chunk_bounds(5, 2)
    [(0, 2), (2, 4), (4, 5)]
    """
    return [(s, min(s + chunk_size, rows)) for s in range(0, rows, chunk_size)]


def _compute(sweep: Sweep, bounds: tuple[int, int], parallel: bool) -> Chunk:
    """A task: one chunk, regenerated from its bounds (module level, so Dask can ship it)."""
    return sweep.chunk(bounds[0], bounds[1], parallel=parallel)


def _threads(sweep: Sweep, bounds: list[tuple[int, int]], workers: int) -> Iterator[Chunk]:
    """Chunks in order, ``workers`` threads, at most ``2 workers`` chunks in memory."""
    if workers <= 1:
        for b in bounds:
            yield _compute(sweep, b, True)
        return
    from concurrent.futures import ThreadPoolExecutor

    with ThreadPoolExecutor(max_workers=workers, thread_name_prefix="carnot-sweep") as pool:
        yield from _in_order(pool, sweep, bounds, workers)


def _processes(sweep: Sweep, bounds: list[tuple[int, int]], workers: int) -> Iterator[Chunk]:
    """Chunks in order from ``workers`` processes (simulations are pure Python most of the
    time: threads would share one interpreter), at most ``2 workers`` chunks in flight. The
    workers are spawned (a clean interpreter each, whatever threads the caller runs)."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=min(workers, len(bounds)), mp_context=context) as pool:
        yield from _in_order(pool, sweep, bounds, workers)


def _in_order(pool: Any, sweep: Sweep, bounds: list[tuple[int, int]], workers: int
              ) -> Iterator[Chunk]:  # fmt: skip
    """The chunks of ``bounds`` computed on ``pool`` and yielded in order, at most
    ``2 workers`` in flight (the rest cancelled if the caller stops early)."""
    pending: deque[Any] = deque()
    todo = iter(bounds)
    try:
        for b in itertools.islice(todo, 2 * workers):
            pending.append(pool.submit(_compute, sweep, b, False))
        while pending:
            chunk = pending.popleft().result()
            nxt = next(todo, None)
            if nxt is not None:
                pending.append(pool.submit(_compute, sweep, nxt, False))
            yield chunk
    finally:
        for f in pending:
            f.cancel()


def _dask(sweep: Sweep, bounds: list[tuple[int, int]], client: Any) -> Iterator[Chunk]:
    """Chunks in order from a Dask cluster: the sweep is scattered once, each task computes
    its chunk from its bounds; a window of twice the cluster's threads bounds the memory."""
    window = max(2, 2 * sum(client.nthreads().values()))
    remote = client.scatter(sweep, broadcast=True, hash=False)
    pending: deque[Any] = deque()
    todo = iter(bounds)
    try:
        for b in itertools.islice(todo, window):
            pending.append(client.submit(_compute, remote, b, False, pure=False))
        while pending:
            future = pending.popleft()
            chunk = future.result()
            future.release()
            nxt = next(todo, None)
            if nxt is not None:
                pending.append(client.submit(_compute, remote, nxt, False, pure=False))
            yield chunk
    finally:
        for f in pending:
            f.cancel()


def run_sweep(
    sweep: Sweep,
    out: str | Path,
    *,
    chunk_size: int | None = None,
    workers: int | None = None,
    client: Any = None,
    scheduler: str | None = None,
    progress: bool = False,
) -> SweepReport:
    """Compute every row of ``sweep`` and write them, in order, to ``out`` (``.parquet`` or
    ``.csv``; written to a temporary file beside it and renamed at the end, so a failed run
    leaves no partial file). Memory: a few chunks at a time, whatever the number of rows.

    ``chunk_size``: rows per chunk (default 16384 on the batch route, 512 on the
    ``solve_impact`` loop, 4 simulations); ``workers``: local threads, or processes for
    simulations (default: the CPU count); ``client``
    (a ``distributed.Client``) or ``scheduler`` (its address): run the chunks on that Dask
    cluster instead. ``progress``: a tqdm bar on stderr.

    >>> import tempfile
    >>> from carnot.io.scenario import read_scenario_data
    >>> data = read_scenario_data("examples/ball_on_floor.toml")
    >>> sweep = prepare_sweep(data, make_plan(vary=["contacts.0.restitution=0:1:11"]))
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     report = run_sweep(sweep, f"{tmp}/e.csv")
    >>> report.rows, report.route
    (11, 'solve')
    """
    from carnot.io.sweep_files import check_output_path, open_writer

    path = check_output_path(out)
    if chunk_size is None:
        chunk_size = (CHUNK_BATCH if sweep.route in ("batch", "multi") else CHUNK_SIMULATE
                      if sweep.route in ("simulate", "cycle", "free_cycle") else CHUNK_SOLVE)
        # fmt: skip
    if isinstance(chunk_size, bool) or int(chunk_size) != chunk_size or chunk_size < 1:
        raise InputError("--chunk-size", "must be an integer >= 1", chunk_size)
    if workers is not None and (int(workers) != workers or workers < 1):
        raise InputError("--workers", "must be an integer >= 1", workers)
    bounds = chunk_bounds(sweep.rows, int(chunk_size))
    own_client = None
    if client is None and scheduler is not None:
        own_client = client = _connect(scheduler)
    began = time.perf_counter()
    routes: set[str] = set()
    flags = dict.fromkeys(FLAGS, 0)
    failed = 0
    try:
        if client is not None:
            chunks = _dask(sweep, bounds, client)
            runner = f"dask({getattr(client.scheduler, 'address', '?')})"
        else:
            n = int(workers or os.cpu_count() or 1)
            if sweep.route in ("simulate", "cycle", "free_cycle") and n > 1 and len(bounds) > 1:
                chunks = _processes(sweep, bounds, n)
                runner = f"processes({n})"
            else:
                chunks = _threads(sweep, bounds, n)
                runner = f"threads({n})"
        with _progress(sweep.rows, progress, sweep.route) as bar, \
                open_writer(path, sweep.columns) as writer:  # fmt: skip
            for chunk in chunks:
                writer.write(chunk)
                routes.add(chunk.route)
                for flag in FLAGS:
                    if flag in chunk.columns:  # not in a simulation's columns
                        flags[flag] += int(np.count_nonzero(chunk.columns[flag]))
                failed += int(np.count_nonzero(chunk.columns["error"]))
                bar.update(chunk.stop - chunk.start)
    finally:
        if own_client is not None:
            own_client.close()
    return SweepReport(
        path=str(path),
        rows=sweep.rows,
        chunks=len(bounds),
        route="+".join(sorted(routes)) or sweep.route,
        seconds=time.perf_counter() - began,
        runner=runner,
        flag_counts=flags,
        failed=failed,
    )


def _connect(address: str) -> Any:
    try:
        from distributed import Client
    except ImportError:  # pragma: no cover - an extra of carnot[sweep]
        raise InputError("--scheduler", "needs dask[distributed] (pip install carnot[sweep])",
                         address) from None  # fmt: skip
    try:
        return Client(address, timeout=10)
    except (OSError, TimeoutError, ValueError) as err:
        raise InputError("--scheduler", f"cannot connect ({err})", address) from None


class _NoBar:
    def update(self, n: int) -> None:
        pass

    def __enter__(self) -> _NoBar:
        return self

    def __exit__(self, *exc: object) -> None:
        pass


def _progress(total: int, show: bool, route: str) -> Any:
    if not show:
        return _NoBar()
    from tqdm import tqdm

    return tqdm(
        total=total,
        unit=" runs" if route in ("simulate", "cycle", "free_cycle") else " impacts",
        dynamic_ncols=True,
        desc="sweep" if route in ("batch", "multi", "simulate", "cycle", "free_cycle")
        else "sweep (solve_impact, slow)",
    )


def sweep_file(
    scenario: str | Path,
    out: str | Path,
    *,
    vary: Sequence[str] = (),
    random: Sequence[str] = (),
    samples: int | None = None,
    seed: int | None = None,
    record: Sequence[str] = (),
    compiled: bool | None = None,
    **run: Any,
) -> SweepReport:
    """Read a scenario file, plan, check and run a sweep (what ``carnot sweep`` does);
    ``record``: the quantities of each run of a simulation scenario; ``compiled``: as in
    :func:`prepare_sweep`; ``run``: the keywords of :func:`run_sweep`."""
    from carnot.io.scenario import read_scenario_data
    from carnot.io.sweep_files import check_output_path

    check_output_path(out)  # before any work
    plan = make_plan(vary=vary, random=random, samples=samples, seed=seed)
    sweep = prepare_sweep(read_scenario_data(scenario), plan, str(scenario), record,
                          compiled=compiled)  # fmt: skip
    return run_sweep(sweep, out, **run)


def _batch_bodies(problem: Any, name: str, number: Any, vector: Any, sweep: Any,
                  by_target: Any, n: int, start: int) -> Any:  # fmt: skip
    """Body ``name`` of ``problem`` as the batch's :class:`carnot.batch.BatchBodies` for a
    chunk of ``n`` rows, its varied values read by ``number`` (the mass) and ``vector``
    (position, velocity, angular velocity), each ``(table, name, key, default)``; ``None`` for
    a fixed body. Shared by the single-contact and the multi-contact batch routes."""
    from carnot.batch import BatchBodies
    from carnot.model.bodies import RigidBody

    body = problem.bodies[name]
    if not isinstance(body, RigidBody):
        return None
    mass = number("bodies", name, "mass", body.mass)
    return BatchBodies(
        mass=mass,
        inertia_com=_inertia(sweep, name, body, mass, by_target, n, start),
        position_com=vector("bodies", name, "position", body.position_com),
        velocity_com=vector("bodies", name, "velocity", body.velocity_com),
        angular_velocity=vector("bodies", name, "angular_velocity", body.angular_velocity),
    )
