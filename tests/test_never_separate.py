"""The dissipation bound that proves a contact never separates, alone or with others
(:func:`carnot.laws.multiple.simultaneous.never_separate`, ``shut_when_separated``), the same
bound on a regime's own slice (``regime_ruled_out``), and the enumeration that skips the
regimes they rule out: the same answers, flags and certificates as the
enumeration that tries them all, on Unitree Go2's landing (its audit's reference problems)
and on random problems with several answers; and no answer separates a contact it proves.

Independent route: the same enumeration with the bound switched off (every regime tried,
as before the bound), compared bit for bit.
"""

from __future__ import annotations

from functools import partial
from pathlib import Path

import mujoco
import numpy as np
import pytest
from robots import GO2

import carnot.laws.multiple.simultaneous as simultaneous
import carnot.several as several
from carnot.laws.multiple import ContactRows
from carnot.laws.multiple.rows import velocity_scale
from carnot.rollout import EnergyAudit, RigidSettings
from carnot.solvers import resolve


def _digest(out) -> list:
    """Everything an outcome reports, its alternatives' too, for a comparison bit for bit."""
    return [
        (o.impulses.tobytes(), o.w_after.tobytes(), o.flags, o.residual,
         tuple((c.regime, c.impulse_normal, c.impulse_tangent, c.residual) for c in o.contacts),
         o.extra)
        for o in (out, *out.alternatives)
    ] + [out.certificate]  # fmt: skip


def _without_bound(monkeypatch: pytest.MonkeyPatch, call):
    """``call()`` with the bounds proving nothing (for one contact or several separated
    together: :func:`never_separate` asks :func:`shut_when_separated`; on a regime's slice,
    :func:`regime_ruled_out`): every regime tried."""
    with monkeypatch.context() as m:
        m.setattr(simultaneous, "shut_when_separated", lambda *args: frozenset())
        m.setattr(simultaneous, "regime_ruled_out", lambda *args: False)
        return call()


#: The enumeration's option for each regime an outcome reports (planar slips: either side,
#: the same equalities ``u_n = 0`` for the bound).
_OPTION = {"separate": "separate", "frictionless": "closed", "stick": "stick", "slip": "slip"}


def _ruled_out_answers(g, w, contacts, held, out) -> int:
    """How many answers of ``out`` (alternatives included) :func:`regime_ruled_out` rules
    out: zero where it is sound."""
    part = _taking_part(w, contacts, held)
    scale = velocity_scale(w, held)
    return sum(
        simultaneous.regime_ruled_out(g, w, contacts, held, part,
                                      [_OPTION[answer.contacts[i].regime] for i in part], scale)
        for answer in (out, *out.alternatives) if "no_solution" not in answer.flags
    )  # fmt: skip


def _count_ruled_out(monkeypatch: pytest.MonkeyPatch, call) -> tuple[object, int]:
    """``call()``'s outcome and how many regimes :func:`regime_ruled_out` ruled out in it."""
    ruled = simultaneous.regime_ruled_out
    count = 0

    def counting(*args):
        nonlocal count
        out = ruled(*args)
        count += bool(out)
        return out

    with monkeypatch.context() as m:
        m.setattr(simultaneous, "regime_ruled_out", counting)
        return call(), count


def _taking_part(w: np.ndarray, contacts, held) -> list[int]:
    tol = 1e-9 * velocity_scale(w, held)
    return [i for i, c in enumerate(contacts) if w[c.normal] <= tol]


def _go2_problems(monkeypatch: pytest.MonkeyPatch) -> list[tuple]:
    """The contact problems of Go2's audit (its home pose dropped 0.3 m, 1.5 s: the
    benchmark's landing, benchmarks/bench_audit_robot.py), as the solver is handed them."""
    seen: list[tuple] = []
    solve = several.resolve

    def record(g, w, contacts, held=None, options=None):
        seen.append((g, w, tuple(contacts), held, options))
        return solve(g, w, contacts, held, options)

    model = mujoco.MjModel.from_xml_path(str(Path(GO2)))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_KEY,
                                                               "home"))  # fmt: skip
    data.qpos[2] += 0.3
    with monkeypatch.context() as m:
        m.setattr(several, "resolve", record)
        audit = EnergyAudit(model, data, rigid=RigidSettings())
        for _ in range(round(1.5 / model.opt.timestep)):
            mujoco.mj_step(model, data)
            audit.observe()
        audit.finish()
    return seen


def test_go2_landing_same_answers_and_certificates(monkeypatch: pytest.MonkeyPatch) -> None:
    """Every reference problem of Go2's landing: the same outcome with the bound as without,
    certificate included; the bound proves some contact shut where the enumeration verifies
    uniqueness (its front leg's 8 rows: a foot, and a calf limit that no answer opens), and no
    answer of a verifying enumeration separates a contact it proves."""
    problems = _go2_problems(monkeypatch)
    assert len(problems) >= 5
    proved_in_verified = ruled_out = 0
    for g, w, contacts, held, options in problems:
        with_bound, ruled = _count_ruled_out(
            monkeypatch, partial(resolve, g, w, contacts, held, options)
        )
        ruled_out += ruled
        without = _without_bound(monkeypatch, partial(resolve, g, w, contacts, held, options))
        assert _digest(with_bound) == _digest(without)
        if with_bound.certificate.solver != "enumerate" or not isinstance(g, np.ndarray):
            continue
        assert _ruled_out_answers(g, w, contacts, held, with_bound) == 0
        part = _taking_part(w, contacts, held)
        proved = simultaneous.never_separate(g, w, contacts, held, part,
                                             velocity_scale(w, held))  # fmt: skip
        if with_bound.certificate.unique is not None:
            proved_in_verified += len(proved)
        for answer in (with_bound, *with_bound.alternatives):
            assert all(answer.contacts[i].regime != "separate" for i in proved)
    assert proved_in_verified >= 1
    # the front leg's 8 rows: five of its eight slip regimes (each a root search) ruled out
    # by their slices, the answer's among the three left
    assert ruled_out >= 5


def _random_problem(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, list]:
    """Two or three contacts (3D or planar Coulomb, or frictionless) on a random system of
    enough coordinates that ``G`` is positive definite, approaching or at rest, with
    friction up to 2 (where several answers occur)."""
    k = int(rng.integers(2, 4))
    kinds = rng.choice(["spatial", "planar", "frictionless"], size=k)
    rows, contacts = 0, []
    for kind in kinds:
        tangents = {"spatial": 2, "planar": 1, "frictionless": 0}[str(kind)]
        contacts.append(ContactRows(
            normal=rows, tangents=tuple(range(rows + 1, rows + 1 + tangents)),
            friction=0.0 if tangents == 0 else float(rng.uniform(0.1, 2.0)),
            restitution=float(rng.choice([0.0, 0.5]))))  # fmt: skip
        rows += 1 + tangents
    n = rows + int(rng.integers(0, 3))
    a = rng.normal(size=(n, n))
    mass_inv = np.linalg.inv(a @ a.T + 0.5 * np.eye(n))
    jac = rng.normal(size=(rows, n))
    g = jac @ mass_inv @ jac.T
    w = jac @ rng.normal(size=n)
    for c in contacts:  # approaching, or at rest
        w[c.normal] = -abs(w[c.normal]) if rng.random() < 0.8 else 0.0
    return 0.5 * (g + g.T), w, contacts


def test_random_problems_same_answers_and_sound(monkeypatch: pytest.MonkeyPatch) -> None:
    """Random problems, every regime enumerated (``verify=True``): the same outcome with the
    bound as without, alternatives and flags included; no answer separates a contact the
    bound proves, nor a set of contacts the bound proves unable to separate together. Among
    them, problems where the bound proves contacts shut and problems with several answers
    (so that both the skipping and the search for every answer are exercised)."""
    rng = np.random.default_rng(36)
    proved_any = several_answers = ruled_out = 0
    for _ in range(150):
        g, w, contacts = _random_problem(rng)
        part = _taking_part(w, contacts, None)
        proved = simultaneous.never_separate(g, w, contacts, None, part,
                                             velocity_scale(w, None))  # fmt: skip
        out, ruled = _count_ruled_out(monkeypatch, partial(
            simultaneous.resolve_simultaneous, g, w, contacts, verify=True))  # fmt: skip
        ruled_out += ruled
        assert _ruled_out_answers(g, w, contacts, None, out) == 0
        without = _without_bound(monkeypatch, partial(simultaneous.resolve_simultaneous, g, w,
                                                      contacts, verify=True))  # fmt: skip
        assert _digest(out) == _digest(without)
        for answer in (out, *out.alternatives):
            if "no_solution" not in answer.flags:
                assert all(answer.contacts[i].regime != "separate" for i in proved)
                apart = [i for i in part if answer.contacts[i].regime == "separate"]
                assert not simultaneous.shut_when_separated(g, w, contacts, None, part, apart,
                                                            velocity_scale(w, None))  # fmt: skip
        proved_any += bool(proved)
        several_answers += bool(out.alternatives)
    assert proved_any >= 20
    assert several_answers >= 1
    assert ruled_out >= 100


def test_a_contact_that_may_open_is_not_proved() -> None:
    """Two rows coupled so that pressing one opens the other: row 1 at rest next to row 0,
    ``G = [[1, 1], [1, 2]]`` (row 0's impulse lifts row 1): row 1 separates in the answer,
    so the bound must not prove it shut; row 0, approaching and pushed in by row 1, is."""
    g, w = np.array([[1.0, 1.0], [1.0, 2.0]]), np.array([-1.0, 0.0])
    contacts = [ContactRows(normal=0), ContactRows(normal=1)]
    out = simultaneous.resolve_simultaneous(g, w, contacts, verify=True)
    assert out.contacts[1].regime == "separate" and out.w_after[1] > 0.5
    assert simultaneous.never_separate(g, w, contacts, None, [0, 1], 1.0) == frozenset({0})


def test_singular_g_proves_nothing() -> None:
    """A box flat on four corners (``G`` 12 x 12 of rank 6): the other corners' ``G`` is not
    positive definite, so the bound proves nothing and every regime is tried."""
    from test_multiple_impact import box_landing

    model, contacts = box_landing(v=np.array([0.8, 0.3, -1.0]), omega=np.array([0, 0, 0.4]),
                                  mu=0.5)  # fmt: skip
    g, w = np.asarray(model.delassus), np.asarray(model.w)
    proved = simultaneous.never_separate(g, w, contacts, None, list(range(4)),
                                         velocity_scale(w, None))  # fmt: skip
    assert proved == frozenset()


def test_regime_slice_rules_out_only_what_cannot_hold() -> None:
    """:func:`regime_ruled_out` on the two rows of :func:`never_separate`'s example, every
    regime against the law solved by hand: only the answer, both shut with ``P = (2, 1)``
    N s, holds. Separating row 0 (then ``P_1 = 0`` and ``u_n0 = -1``) and both (``u = w``)
    are ruled out; separating row 1 (``P_0 = 1``, ``u_n1 = -1``) is ruled out by its ``u_n1``
    alone. With row 1 pulled open instead (``G_10 = +1``: row 0's impulse lifts row 1), the
    answer separates row 1, and that regime must not be ruled out."""
    c = [ContactRows(normal=0), ContactRows(normal=1)]
    w = np.array([-1.0, 0.0])
    g = np.array([[1.0, -1.0], [-1.0, 2.0]])
    regimes = [("closed", "closed"), ("separate", "closed"), ("closed", "separate"),
               ("separate", "separate")]  # fmt: skip
    ruled = [simultaneous.regime_ruled_out(g, w, c, None, [0, 1], r, 1.0) for r in regimes]
    assert ruled == [False, True, True, True]
    g_open = np.array([[1.0, 1.0], [1.0, 2.0]])
    out = simultaneous.resolve_simultaneous(g_open, w, c, verify=True)
    assert [o.regime for o in out.contacts] == ["frictionless", "separate"]
    assert not simultaneous.regime_ruled_out(g_open, w, c, None, [0, 1],
                                             ("closed", "separate"), 1.0)  # fmt: skip
    # a 3D contact sticking is shut entirely (u = 0): its tangent rows join the equalities
    g3 = np.eye(3) * 2.0
    c3 = [ContactRows(normal=0, tangents=(1, 2), friction=0.5)]
    w3 = np.array([-1.0, 0.3, 0.0])
    assert not simultaneous.regime_ruled_out(g3, w3, c3, None, [0], ("slip",), 1.0)
    assert simultaneous.regime_ruled_out(g3, w3, c3, None, [0], ("separate",), 1.0)


def _nearest_first_by_passes(ordered, near, skip):
    """The enumeration's order as it was first written: one pass over the product per
    distance from ``near`` and per count of contacts ``near`` does not separate."""
    import itertools

    for distance in range(len(near) + 1):
        for moved in range(distance + 1):
            for choice in itertools.product(*ordered):
                if choice in skip:
                    continue
                changed = [b for a, b in zip(choice, near, strict=True) if a != b]
                if len(changed) == distance and sum(b != "separate" for b in changed) == moved:
                    yield choice


def test_nearest_first_is_the_order_by_passes() -> None:
    """The order of the regimes after the first three (``_nearest_first``, a stable sort)
    against the passes it replaces, on random option lists of one to five contacts of every
    kind (their options in random order, as the prediction orders them) and random regimes
    to start from and to skip: the same sequence."""
    rng = np.random.default_rng(7)
    kinds = list(simultaneous._OPTIONS.values())
    for _ in range(200):
        ordered = [tuple(rng.permutation(kinds[int(rng.integers(len(kinds)))]).tolist())
                   for _ in range(int(rng.integers(1, 6)))]  # fmt: skip
        near, other, third = (tuple(str(rng.choice(o)) for o in ordered) for _ in range(3))
        skip = (near, other, third)
        assert list(simultaneous._nearest_first(ordered, near, skip)) == list(
            _nearest_first_by_passes(ordered, near, skip))
