"""Named models with the papers' parameters and coordinates (DESIGN.md section 10).

* ``compass_gait``: Goswami, Thuilot and Espiau, *Compass-like biped robot, Part I:
  stability and bifurcation of passive gaits*, INRIA RR-2996 (1996), as in Drake's example:
  leg mass ``m`` at ``a`` from the foot and ``b`` from the hip (``l = a + b``), hip mass
  ``m_h``; ``q = (stance, swing)``, each leg's angle from the vertical, a leg's hip end at
  ``(l sin q, l cos q)`` from its foot; the slope descends towards +x; heel strike when the
  swing foot reaches the slope, ``stance + swing = 2 slope``, after mid-stance.
* ``simplest_walker``: Garcia, Chatterjee, Ruina and Coleman, *The simplest walking model*,
  J. Biomech. Eng. 120 (1998): massless legs of length ``l``, hip mass ``M``, feet of mass
  ``beta M``; their scaling (``g = l = M = 1``); ``q = (theta, phi)``, ``theta`` the stance
  leg from the slope's normal (the hip at ``l (-sin theta, cos theta)`` from the stance foot,
  downhill towards +x), ``phi`` the angle between the legs; heel strike at ``phi = 2 theta``
  after mid-stance (``theta`` through 0). Their model is the limit ``beta -> 0``; carnot
  needs a positive mass matrix and takes ``beta = 1e-5`` unless given, which moves the gait
  by ``O(beta)`` (1.5e-6 in theta at ``slope = 0.009``); a smaller ``beta`` makes the
  strike's Delassus matrix ill-conditioned (``1 / beta``), and its digits go with it.
* ``rimless_wheel``: McGeer, *Passive dynamic walking*, IJRR 9 (1990), and Tedrake's
  *Underactuated Robotics*: hub mass ``m``, inertia ``I`` about the hub, ``spokes`` spokes of
  length ``l`` (``2 alpha = 2 pi / spokes`` apart); ``q = (theta)``, the stance spoke from
  the vertical (the hub at ``(l sin theta, l cos theta)`` from its foot); the next spoke
  strikes at ``theta = slope + alpha``, the previous one (rocking back) at
  ``theta = slope - alpha``. With a point-mass hub (``I = 0``, Tedrake's wheel) the spokes
  are massless rods: each pushes on the hub only along itself, and the impact's floating
  coordinates are the hub's alone.

* ``double_pendulum``: two point masses ``m1``, ``m2`` at the ends of massless links
  ``l1``, ``l2`` from a fixed pivot; ``q = (theta1, theta2)``, the upper link from the
  downward vertical and the elbow's angle (the lower link relative to the upper); the elbow
  has a stop at ``theta2 = stop`` (``theta2 <= stop``), a joint limit struck with the file's
  restitution and held through a chatter (as a knee locks).

* ``hopping_leg``: a vertical two-mass hopper, our parameters (no published set is
  transcribed): a body of mass ``M`` on a massless prismatic spring leg (stiffness ``k``,
  rest length ``l0``, optional damper ``c``) ending in a foot of mass ``m``; ``q = (y_body,
  y_foot)``, heights above the ground (m), the leg's length ``l = y_body - y_foot``. Flight:
  both masses free, ``M y_body'' = k (l0 - l) - c l' - M g``,
  ``m y_foot'' = -k (l0 - l) + c l' - m g``; touchdown: the foot strikes the ground (the
  file's law; plastic by default, taking ``m v_foot^2 / 2``); stance: the foot held while
  the ground pushes, ``F = k (l0 - l) - c l' + m g``; lift-off where ``F`` falls to zero.

Every model is one :class:`~carnot.hybrid.mechanism.Mechanism` (floating coordinates, the
masses' positions, the feet), compiled once per parameter set and kept (the compile takes a
fraction of a second; a sweep over a slope builds one per slope).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from functools import lru_cache
from typing import Any

import numpy as np
import sympy as sp

from carnot.errors import InputError
from carnot.hybrid.guards import plane_guard
from carnot.hybrid.mechanism import Body, Damper, Mechanism, compile_mechanism
from carnot.hybrid.model import Guard, HybridModel

#: Each model's parameters and their defaults (None: required), with the bound each obeys.
PARAMETERS: dict[str, dict[str, float | None]] = {
    "compass_gait": {"m": 5.0, "m_h": 10.0, "a": 0.5, "b": 0.5, "slope": 0.0524, "g": 9.81},
    "simplest_walker": {"slope": 0.009, "beta": 1e-5, "g": 1.0, "l": 1.0, "M": 1.0},
    "rimless_wheel": {"m": 1.0, "l": 1.0, "spokes": 8.0, "slope": 0.08, "I": 0.0, "g": 9.81},
    "double_pendulum": {"m1": 1.0, "m2": 1.0, "l1": 1.0, "l2": 1.0, "g": 9.81, "stop": 0.0},
    "hopping_leg": {"M": 10.0, "m": 1.0, "k": 1.0e4, "l0": 0.5, "c": 0.0, "g": 9.81},
}
#: The chart's coordinate names of each model (DESIGN.md section 10).
COORDINATES = {
    "compass_gait": ("stance", "swing"),
    "simplest_walker": ("theta", "phi"),
    "rimless_wheel": ("theta",),
    "double_pendulum": ("theta1", "theta2"),
    "hopping_leg": ("y_body", "y_foot"),
}
MODEL_NAMES = tuple(PARAMETERS)
#: Parameters that may be zero (the others must be > 0); bounds on the slope (rad).
_MAY_BE_ZERO = {"I", "slope", "stop", "c"}
MAX_SLOPE = 0.5
_UNITS = {"m": "kg", "m_h": "kg", "M": "kg", "m1": "kg", "m2": "kg", "a": "m", "b": "m",
          "l": "m", "l1": "m", "l2": "m", "g": "m/s^2", "k": "N/m", "l0": "m"}  # fmt: skip


def check_parameters(name: str, given: Mapping[str, Any], where: str = "model") -> dict[str, float]:
    """The model's parameters: the defaults updated by ``given``, each a finite number in its
    bounds (InputError naming ``where.parameters.KEY`` otherwise).

    >>> check_parameters("rimless_wheel", {"spokes": 6})["spokes"]
    6.0
    >>> check_parameters("compass_gait", {"a": -1.0})
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: model.parameters.a: must be > 0 (m), got -1.0
    """
    if name not in PARAMETERS:
        raise InputError(f"{where}.name", f"must be one of {', '.join(MODEL_NAMES)}", name)
    defaults = PARAMETERS[name]
    unknown = sorted(set(given) - set(defaults))
    if unknown:
        raise InputError(f"{where}.parameters", f"unknown for {name} (known: "
                         f"{', '.join(defaults)})", unknown)  # fmt: skip
    out: dict[str, float] = {}
    for key, default in defaults.items():
        value = given.get(key, default)
        field_ = f"{where}.parameters.{key}"
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise InputError(field_, "must be a number", value)
        value = float(value)
        if not math.isfinite(value):
            raise InputError(field_, "must be finite", value)
        if key == "stop":
            if not -math.pi < value < math.pi:
                raise InputError(field_, "must be in (-pi, pi) (rad)", value)
        elif key == "slope":
            if not -MAX_SLOPE <= value <= MAX_SLOPE:
                raise InputError(field_, f"must be in [-{MAX_SLOPE}, {MAX_SLOPE}] (rad)", value)
        elif key in _MAY_BE_ZERO:
            if value < 0:
                raise InputError(field_, "must be >= 0", value)
        elif value <= 0:
            unit = _UNITS.get(key, "")
            raise InputError(field_, "must be > 0" + (f" ({unit})" if unit else ""), value)
        out[key] = value
    if name == "rimless_wheel":
        spokes = out["spokes"]
        if spokes != int(spokes) or not 3 <= spokes <= 1000:
            raise InputError(f"{where}.parameters.spokes", "must be an integer in [3, 1000]",
                             spokes)  # fmt: skip
        if abs(out["slope"]) >= math.pi / spokes:
            raise InputError(f"{where}.parameters.slope", "must be below the half angle "
                             "between spokes, pi / spokes (rad)", out["slope"])  # fmt: skip
    if name == "simplest_walker" and out["beta"] > 1.0:
        raise InputError(f"{where}.parameters.beta", "must be <= 1 (the feet's mass over the "
                         "hip's)", out["beta"])  # fmt: skip
    return out


def named_model(name: str, parameters: Mapping[str, Any] | None = None) -> HybridModel:
    """The named model with ``parameters`` (defaults otherwise), compiled once per set.

    >>> w = named_model("rimless_wheel", {"spokes": 6, "slope": 0.1})
    >>> w.coordinates, [g.name for g in w.guards]
    (('theta',), ['next_spoke', 'previous_spoke'])
    """
    values = check_parameters(name, parameters or {})
    return _build(name, tuple(sorted(values.items())))


@lru_cache(maxsize=64)
def _build(name: str, items: tuple[tuple[str, float], ...]) -> HybridModel:
    values = dict(items)
    return _BUILDERS[name](values)


def _vec(*entries: float) -> np.ndarray:
    return np.array(entries, dtype=float)


def _linear(coefficients: np.ndarray, constant: float = 0.0) -> tuple[
        Callable[[np.ndarray], float], Callable[[np.ndarray], np.ndarray]]:  # fmt: skip
    """``G(x) = c . x + k`` and its gradient."""
    c = np.asarray(coefficients, dtype=float)
    return (lambda x: float(c @ x + constant)), (lambda x: c)


def _compass_gait(p: dict[str, float]) -> HybridModel:
    m, m_h, a, b, slope, g = (p[k] for k in ("m", "m_h", "a", "b", "slope", "g"))
    ll = a + b
    x, y, st, sw = sp.symbols("x_hip y_hip stance swing")
    q_st, q_sw = sp.symbols("q_stance q_swing")
    hip = (x, y)

    def along(angle: Any, d: float) -> tuple[Any, Any]:  # d from the hip towards the foot
        return (x - d * sp.sin(angle), y - d * sp.cos(angle))

    mech = Mechanism(
        floating=(x, y, st, sw),
        bodies=(Body(mass=m_h, position=hip), Body(mass=m, position=along(st, b)),
                Body(mass=m, position=along(sw, b))),  # fmt: skip
        points={"stance_foot": along(st, ll), "swing_foot": along(sw, ll), "hip": hip},
        coordinates=(q_st, q_sw),
        embedding=(ll * sp.sin(q_st), ll * sp.cos(q_st), q_st, q_sw),
        gravity=(0, -g),
    )
    compiled = compile_mechanism(mech, {})
    strike, strike_grad = _linear(_vec(1, 1, 0, 0), -2 * slope)
    arm, _ = _linear(_vec(1, -1, 0, 0))
    swap = np.array([[0.0, 1.0], [1.0, 0.0]])
    guard = Guard(name="heel_strike", function=strike, gradient=strike_grad, direction=1,
                  arming=arm, arming_direction=1, striking="swing_foot",
                  holding=("stance_foot",), relabel=swap, offset=np.zeros(2),
                  velocity_relabel=_permutation(4, (0, 1, 3, 2)))  # fmt: skip
    return HybridModel(
        name="compass_gait", parameters=p, coordinates=COORDINATES["compass_gait"],
        floating=("x_hip", "y_hip", "stance", "swing"), mechanism=compiled, guards=(guard,),
        normal=_vec(math.sin(slope), math.cos(slope), 0.0), gravity=_vec(0.0, -g),
        total_mass=m_h + 2 * m, fall=lambda s: math.cos(s[0] - slope), slope=slope, stance=True,
        notes="the swing foot's touch of the slope at mid-stance (legs parallel) is ignored, "
        "as in Goswami et al. (1996): heel strike is armed once the swing foot has passed "
        "the stance foot",
    )  # fmt: skip


def _simplest_walker(p: dict[str, float]) -> HybridModel:
    slope, beta, g, ll, big_m = (p[k] for k in ("slope", "beta", "g", "l", "M"))
    x, y, th, ph = sp.symbols("x_hip y_hip theta phi")
    q_th, q_ph = sp.symbols("q_theta q_phi")
    stance = (x + ll * sp.sin(th), y - ll * sp.cos(th))
    swing = (x + ll * sp.sin(th - ph), y - ll * sp.cos(th - ph))
    mech = Mechanism(
        floating=(x, y, th, ph),
        bodies=(Body(mass=big_m, position=(x, y)), Body(mass=beta * big_m, position=stance),
                Body(mass=beta * big_m, position=swing)),  # fmt: skip
        points={"stance_foot": stance, "swing_foot": swing, "hip": (x, y)},
        coordinates=(q_th, q_ph),
        embedding=(-ll * sp.sin(q_th), ll * sp.cos(q_th), q_th, q_ph),
        gravity=(g * math.sin(slope), -g * math.cos(slope)),  # the slope's frame
    )
    compiled = compile_mechanism(mech, {})
    strike, strike_grad = _linear(_vec(-2, 1, 0, 0))
    arm, _ = _linear(_vec(1, 0, 0, 0))
    relabel = np.array([[1.0, -1.0], [0.0, -1.0]])  # theta+ = theta - phi, phi+ = -phi
    velocity_relabel = np.eye(4)
    velocity_relabel[2:, 2:] = relabel
    guard = Guard(name="heel_strike", function=strike, gradient=strike_grad, direction=1,
                  arming=arm, arming_direction=-1, striking="swing_foot",
                  holding=("stance_foot",), relabel=relabel, offset=np.zeros(2),
                  velocity_relabel=velocity_relabel)  # fmt: skip
    return HybridModel(
        name="simplest_walker", parameters=p, coordinates=COORDINATES["simplest_walker"],
        floating=("x_hip", "y_hip", "theta", "phi"), mechanism=compiled, guards=(guard,),
        normal=_vec(0.0, 1.0, 0.0), gravity=_vec(g * math.sin(slope), -g * math.cos(slope)),
        total_mass=big_m * (1 + 2 * beta), fall=lambda s: math.cos(s[0]), slope=slope,
        stance=True,
        notes="the swing foot's scuffing near mid-stance is ignored, as in Garcia et al. "
        "(1998): heel strike (phi = 2 theta) is armed once theta has passed 0; feet of mass "
        f"beta = {beta:g} of the hip's (their model is the limit beta -> 0)",
    )  # fmt: skip


def _rimless_wheel(p: dict[str, float]) -> HybridModel:
    m, ll, spokes, slope, inertia, g = (p[k] for k in ("m", "l", "spokes", "slope", "I", "g"))
    alpha = math.pi / spokes
    x, y, th = sp.symbols("x_hub y_hub theta")
    q_th = sp.Symbol("q_theta")
    offsets = {"stance_spoke": 0.0, "next_spoke": -2 * alpha, "previous_spoke": 2 * alpha}
    if inertia > 0:  # a rigid wheel: the hub and its rotation

        def tip(angle: Any) -> tuple[Any, Any]:
            return (x - ll * sp.sin(angle), y - ll * sp.cos(angle))

        mech = Mechanism(
            floating=(x, y, th),
            bodies=(Body(mass=m, position=(x, y), inertia=inertia, angle=th),),
            points={**{k: tip(th + d) for k, d in offsets.items()}, "hub": (x, y)},
            coordinates=(q_th,),
            embedding=(ll * sp.sin(q_th), ll * sp.cos(q_th), q_th),
            gravity=(0, -g),
        )
        floating: tuple[str, ...] = ("x_hub", "y_hub", "theta")
    else:  # massless spokes: rods on the hub, whose feet the chart places
        hub = (ll * sp.sin(q_th), ll * sp.cos(q_th))
        mech = Mechanism(
            floating=(x, y),
            bodies=(Body(mass=m, position=(x, y)),),
            points={"hub": (x, y)},
            rods={k: ("hub", (hub[0] - ll * sp.sin(q_th + d), hub[1] - ll * sp.cos(q_th + d)))
                  for k, d in offsets.items()},
            coordinates=(q_th,),
            embedding=hub,
            gravity=(0, -g),
        )
        floating = ("x_hub", "y_hub")
    nf = len(floating)
    compiled = compile_mechanism(mech, {})
    fwd, fwd_grad = _linear(_vec(1, 0), -(slope + alpha))
    back, back_grad = _linear(_vec(1, 0), -(slope - alpha))
    rate, _ = _linear(_vec(0, 1))
    one = np.eye(1)
    guards = (
        Guard(name="next_spoke", function=fwd, gradient=fwd_grad, direction=1,
              striking="next_spoke", holding=("stance_spoke",), relabel=one,
              offset=_vec(-2 * alpha), velocity_relabel=np.eye(nf)),
        Guard(name="previous_spoke", function=back, gradient=back_grad, direction=-1,
              arming=rate, arming_direction=-1, striking="previous_spoke",
              holding=("stance_spoke",), relabel=one, offset=_vec(2 * alpha),
              velocity_relabel=np.eye(nf)),
    )  # fmt: skip
    return HybridModel(
        name="rimless_wheel", parameters=p, coordinates=COORDINATES["rimless_wheel"],
        floating=floating, mechanism=compiled, guards=guards,
        normal=_vec(math.sin(slope), math.cos(slope), 0.0), gravity=_vec(0.0, -g),
        total_mass=m, slope=slope, stance=True,
        notes="the previous spoke's strike (rocking back) is armed once the wheel turns back",
    )  # fmt: skip


def _double_pendulum(p: dict[str, float]) -> HybridModel:
    m1, m2, l1, l2, g, stop = (p[k] for k in ("m1", "m2", "l1", "l2", "g", "stop"))
    t1, t2 = sp.symbols("theta1 theta2")
    elbow = (l1 * sp.sin(t1), -l1 * sp.cos(t1))
    tip = (elbow[0] + l2 * sp.sin(t1 + t2), elbow[1] - l2 * sp.cos(t1 + t2))
    mech = Mechanism(
        floating=(t1, t2),
        bodies=(Body(mass=m1, position=elbow), Body(mass=m2, position=tip)),
        points={"elbow": elbow, "tip": tip},
        coordinates=(t1, t2),
        embedding=(t1, t2),
        gravity=(0, -g),
    )
    compiled = compile_mechanism(mech, {})
    gap, gap_grad = _linear(_vec(0, -1, 0, 0), stop)  # g = stop - theta2 >= 0
    guard = Guard(name="elbow_stop", function=gap, gradient=gap_grad, direction=-1,
                  striking="elbow_stop", holding=(), relabel=np.eye(2), offset=np.zeros(2),
                  velocity_relabel=np.eye(2), moves_anchor=False,
                  limit_row=_vec(0.0, -1.0))  # fmt: skip
    return HybridModel(
        name="double_pendulum", parameters=p, coordinates=COORDINATES["double_pendulum"],
        floating=("theta1", "theta2"), mechanism=compiled, guards=(guard,),
        normal=_vec(0.0, 1.0, 0.0), gravity=_vec(0.0, -g), total_mass=m1 + m2,
        notes=f"the elbow stops at theta2 = {stop:g} rad (a joint limit, frictionless); a "
        "chatter against it ends with the elbow held there while the stop pushes",
    )  # fmt: skip


def _hopping_leg(p: dict[str, float]) -> HybridModel:
    big_m, m, k, l0, c, g = (p[key] for key in ("M", "m", "k", "l0", "c", "g"))
    y_b, y_f = sp.symbols("y_body y_foot")
    length = y_b - y_f
    mech = Mechanism(
        floating=(y_b, y_f),
        bodies=(Body(mass=big_m, position=(0, y_b)), Body(mass=m, position=(0, y_f))),
        points={"foot": (0, y_f), "body": (0, y_b)},
        coordinates=(y_b, y_f),
        embedding=(y_b, y_f),
        gravity=(0, -g),
        potential=k * (length - l0) ** 2 / 2,
        dampers=(Damper(coefficient=c, length=length),) if c > 0 else (),
    )
    compiled = compile_mechanism(mech, {})
    touchdown = plane_guard(compiled, "foot", name="touchdown")
    return HybridModel(
        name="hopping_leg", parameters=p, coordinates=COORDINATES["hopping_leg"],
        floating=COORDINATES["hopping_leg"], mechanism=compiled, guards=(touchdown,),
        normal=_vec(0.0, 1.0, 0.0), gravity=_vec(0.0, -g), total_mass=big_m + m,
        fall=lambda s: float(s[0] - s[1]),
        notes="vertical motion only; the foot's touchdown is a strike with the file's law, "
        "after which the foot is held on the ground while the ground pushes (stance), "
        "lifting off where that push falls to zero; the run ends if the leg's length "
        "reaches zero",
    )  # fmt: skip


def check_state(name: str, q: np.ndarray, where: str = "model.state.q") -> None:
    """The chart's coordinates ``q`` must be a state of the model: angles within
    ``[-2 pi, 2 pi]`` (rad), or for ``hopping_leg`` heights (m) with the foot on or above
    the ground and the body above the foot (InputError naming ``where`` otherwise).

    >>> check_state("hopping_leg", np.array([0.4, 0.5]))
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: model.state.q: must have the body above the foot (y_body > y_foot, m), got [0.4, 0.5]
    """  # noqa: E501
    values = [float(v) for v in q]
    if name == "hopping_leg":
        if values[1] < 0:
            raise InputError(where, "must have the foot on or above the ground (y_foot >= 0, "
                             "m)", values)  # fmt: skip
        if values[0] <= values[1]:
            raise InputError(where, "must have the body above the foot (y_body > y_foot, m)",
                             values)  # fmt: skip
    elif np.any(np.abs(q) > 2 * math.pi):
        raise InputError(where, "must be angles within [-2 pi, 2 pi] (rad)", values)


def _permutation(n: int, order: tuple[int, ...]) -> np.ndarray:
    return np.eye(n)[list(order)]


_BUILDERS: dict[str, Callable[[dict[str, float]], HybridModel]] = {
    "compass_gait": _compass_gait,
    "simplest_walker": _simplest_walker,
    "rimless_wheel": _rimless_wheel,
    "double_pendulum": _double_pendulum,
    "hopping_leg": _hopping_leg,
}
