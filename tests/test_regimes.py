"""The simultaneous law's regimes written once (carnot.laws.multiple.regimes): each regime's
system checked against the law it states (solved on a random Delassus operator, its answer
meets the regime's equations: Newton's restitution on the closed and slipping normals, zero
slip on the stuck tangents, Coulomb's slip impulse on the slipping ones), and the routes
that run it (the law's ``_columns`` as Python, the batch kernel's compiled leaf) on the same
bits."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from carnot.laws.multiple import regimes, simultaneous
from carnot.laws.multiple.rows import ContactRows, HeldRows

#: A spatial, a planar, a frictionless and a told-to-stick contact over 8 rows.
CONTACTS = (ContactRows(normal=0, tangents=(1, 2), restitution=0.3, friction=0.6),
            ContactRows(normal=3, tangents=(4,), restitution=0.0, friction=0.4),
            ContactRows(normal=5, restitution=0.5),
            ContactRows(normal=6, tangents=(7,), restitution=0.2, stick=True))  # fmt: skip


def _patterns() -> list[tuple[str, ...]]:
    options = [simultaneous._OPTIONS[c.kind] + ("out",) for c in CONTACTS]
    return list(itertools.product(*options))


def test_the_options_are_the_laws_kinds() -> None:
    assert simultaneous._OPTIONS == {
        "frictionless": ("closed", "separate"), "told_to_stick": ("stick", "separate"),
        "planar": ("stick", "slip+", "slip-", "separate"), "spatial": ("stick", "slip", "separate")}


def _solved(rng: np.random.Generator, pattern: tuple[str, ...]):  # type: ignore[no-untyped-def]
    """A random Delassus operator ``G`` (8 x 8, positive definite), ``w'``, a 3D slip
    direction ``s`` for contact 0, the regime's ``B`` and its answer ``x`` (``None`` where it
    fixes no row), ``Lambda = B x`` and ``w''``."""
    m = 8
    a = rng.normal(size=(m, m))
    g = a @ a.T + 0.1 * np.eye(m)
    w = rng.normal(size=m)
    angle = rng.uniform(0.0, 2.0 * np.pi)
    s = np.array([np.cos(angle), np.sin(angle)])
    b, rows, targets = simultaneous._columns(m, CONTACTS, None, pattern, w, {0: s})
    x = np.linalg.solve((g @ b)[rows], targets - w[rows]) if rows else None
    lam = b @ x if x is not None else np.zeros(m)
    return g, w, s, b, x, lam, w + g @ lam


def test_every_regimes_system_states_the_law() -> None:
    rng = np.random.default_rng(7)
    for pattern in _patterns():
        g, w, s, b, x, lam, after = _solved(rng, pattern)
        for c, option in zip(CONTACTS, pattern, strict=True):
            n, t = c.normal, c.tangents
            if option in ("out", "separate"):
                assert lam[[n, *t]].tolist() == [0.0] * (1 + len(t))
                continue
            assert after[n] == pytest.approx(-c.restitution * w[n], abs=1e-9)  # Newton
            if option == "stick":
                assert np.allclose(after[list(t)], 0.0, atol=1e-9)
            elif option == "slip":
                assert np.allclose(lam[list(t)], -c.friction * lam[n] * s, atol=1e-12)
            elif option in ("slip+", "slip-"):
                sign = 1.0 if option == "slip+" else -1.0
                assert lam[t[0]] == pytest.approx(-sign * c.friction * lam[n], abs=1e-12)
            else:  # closed: no tangent impulse
                assert lam[list(t)].tolist() == [0.0] * len(t)


def test_held_rows_come_first_and_end_at_their_targets() -> None:
    held = HeldRows(rows=(1,), target=(0.25,))
    contacts = CONTACTS[1:3]
    w = np.array([0.0, -1.0, 0.0, -2.0, 0.5, -0.5, 0.0, 0.0])
    b, rows, targets = simultaneous._columns(8, contacts, held, ("stick", "closed"), w, {})
    assert rows == [1, 3, 4, 5] and targets.tolist() == [0.25, -0.0, 0.0, 0.25]
    assert b.flags.f_contiguous and b.shape == (8, 4)
    assert np.array_equal(b, np.eye(8)[:, [1, 3, 4, 5]])


def test_the_batch_kernel_compiles_the_same_regimes() -> None:
    pytest.importorskip("numba")
    from carnot.batch import multi_kernel as mk

    rng = np.random.default_rng(8)
    m = 8
    nrow, trow, ntan, mu, e = simultaneous._layout(CONTACTS)[:5]
    out_c, out_p = np.zeros(4, dtype=np.int64), np.zeros(4, dtype=np.int64)
    for kind in (regimes.FRICTIONLESS_KIND, regimes.PLANAR, regimes.SPATIAL, regimes.TOLD_TO_STICK):
        assert mk._options(kind, out_c) == regimes.regime_options(kind, out_p)
        assert out_c.tolist() == out_p.tolist()
    for pattern in _patterns():
        w = rng.normal(size=m)
        dirs = rng.normal(size=(4, 2))
        codes = np.array([regimes.OPTION_NAMES.index(o) for o in pattern], dtype=np.int64)
        arrays = [(np.full((m, m), np.nan), np.zeros(m, dtype=np.int64), np.zeros(m))
                  for _ in range(2)]  # fmt: skip
        compiled = mk._columns(m, nrow, trow, ntan, mu, e, codes, w, dirs, *arrays[0])
        python = regimes.regime_columns(m, nrow, trow, ntan, mu, e, codes, w, dirs, *arrays[1])
        assert compiled == python
        q = compiled[0]
        for a, b in zip(arrays[0], arrays[1], strict=True):
            assert np.array_equal(a[..., :q] if a.ndim == 2 else a[:q],
                                  b[..., :q] if b.ndim == 2 else b[:q])


def test_a_regimes_inequalities_are_the_laws_conditions() -> None:
    """``lin_a x + lin_c`` at the regime's answer, contact by contact: Glocker's
    ``w_n'' + e w_n'`` where it separates, ``G_nn P_n`` where loaded, ``G_nn (mu P_n -+ P_t)``
    where stuck in a plane, ``+-w_t''`` or ``s . w_t''`` where slipping; the 3D stuck cone
    set apart. And the batch kernel's compiled leaf gives the same bits."""
    numba = pytest.importorskip("numba")  # noqa: F841 - the kernel's leaf below
    from carnot.batch import multi_kernel as mk

    rng = np.random.default_rng(9)
    k = len(CONTACTS)
    nrow, trow, _, mu, e = simultaneous._layout(CONTACTS)[:5]
    kinds = np.array([simultaneous._KIND_CODES[c.kind] for c in CONTACTS], dtype=np.int64)
    for pattern in _patterns():
        g, w, s, b, x, lam, after = _solved(rng, pattern)
        if x is None:
            continue
        lin_a, lin_c, cones = simultaneous._inequalities(g, w, CONTACTS, pattern, b, g @ b,
                                                         {0: s})  # fmt: skip
        values = iter(lin_a @ x + lin_c)
        for c, option in zip(CONTACTS, pattern, strict=True):
            n, t, gnn = c.normal, c.tangents, g[c.normal, c.normal]
            expected: list[float] = []
            if option == "separate":
                expected = [after[n] + c.restitution * w[n]]
            elif option != "out":
                expected = [gnn * lam[n]]
                if option == "stick" and c.kind == "planar":
                    expected += [gnn * (c.friction * lam[n] - lam[t[0]]),
                                 gnn * (c.friction * lam[n] + lam[t[0]])]  # fmt: skip
                elif option in ("slip+", "slip-"):
                    expected += [(1.0 if option == "slip+" else -1.0) * after[t[0]]]
                elif option == "slip":
                    expected += [float(s @ after[list(t)])]
            for value in expected:
                assert next(values) == pytest.approx(value, abs=1e-9)
        assert next(values, None) is None
        spatial_stuck = pattern[0] == "stick"
        assert cones == ([(0, (1, 2), 0.6)] if spatial_stuck else [])
        # the kernel's leaf, on the same arrays
        codes = np.array([regimes.OPTION_NAMES.index(o) for o in pattern], dtype=np.int64)
        dirs = np.zeros((k, 2))
        dirs[0] = s
        outs = [(np.zeros((3 * k, b.shape[1])), np.zeros(3 * k), np.zeros((k, 3)))
                for _ in range(2)]  # fmt: skip
        gb = np.ascontiguousarray(g @ b)
        bc = np.ascontiguousarray(b)
        got = [fn(g, w, nrow, trow, kinds, e, mu, codes, dirs, bc, b.shape[1], gb, *out)
               for fn, out in zip((mk._inequalities, regimes.regime_inequalities), outs,
                                  strict=True)]  # fmt: skip
        assert got[0] == got[1]
        for x_c, x_p in zip(*outs, strict=True):
            assert np.array_equal(x_c, x_p)


def test_the_prediction_orders_each_contacts_regimes_as_the_law_says() -> None:
    """A pull predicts separation, an impulse outside the cone slip against it (in 3D along
    ``-p_t / |p_t|``), else the first option stays; overloaded contacts put a separating one
    back slipping before sticking. The kernel's compiled leaf on the same numbers."""
    pytest.importorskip("numba")
    from carnot.batch import multi_kernel as mk

    rng = np.random.default_rng(10)
    k = len(CONTACTS)
    nrow, trow, ntan, mu, _ = simultaneous._layout(CONTACTS)[:5]
    kinds = np.array([simultaneous._KIND_CODES[c.kind] for c in CONTACTS], dtype=np.int64)
    nopt = np.zeros(k, dtype=np.int64)
    opts = np.zeros((k, 4), dtype=np.int64)
    for c in range(k):
        nopt[c] = regimes.regime_options(kinds[c], opts[c])
    g = np.eye(8)
    seen = set()
    for _ in range(300):
        p = rng.normal(size=8)
        runs = []
        for fn in (regimes.predicted_order, mk._predicted_order):
            out = (np.zeros((k, 4), dtype=np.int64), np.zeros((k, 2)), np.zeros(k, dtype=bool))
            overloaded = fn(g, nrow, trow, ntan, kinds, mu, np.ones(k, dtype=bool), nopt, opts,
                            *out, p, 1.0)  # fmt: skip
            runs.append((bool(overloaded), *out))
        assert runs[0][0] == runs[1][0]
        for a, b in zip(runs[0][1:], runs[1][1:], strict=True):
            assert np.array_equal(a, b)
        overloaded, order, direction, has = runs[0]
        for c, contact in enumerate(CONTACTS):
            first = regimes.OPTION_NAMES[order[c, 0]]
            p_n, p_t = p[contact.normal], p[list(contact.tangents)]
            outside = contact.kind in ("planar", "spatial") and np.linalg.norm(p_t) > mu[c] * p_n
            if p_n < -1e-9:
                assert first == "separate"
            elif outside and contact.kind == "planar":
                assert first == ("slip+" if p_t[0] < 0 else "slip-")
            elif outside:
                assert first == "slip" and has[c]
                assert np.allclose(direction[c], -p_t / np.linalg.norm(p_t), atol=1e-15)
            else:
                assert first == simultaneous._OPTIONS[contact.kind][0]
            assert sorted(order[c, : nopt[c]]) == sorted(opts[c, : nopt[c]])
            if overloaded and first == "separate" and contact.kind != "frictionless":
                assert regimes.OPTION_NAMES[order[c, nopt[c] - 1]] == "stick"
            seen.add((first, bool(overloaded)))
    assert {"separate", "slip", "slip+", "slip-", "stick", "closed"} <= {f for f, _ in seen}


def test_the_widest_regime_closes_what_separates_with_equality() -> None:
    """A separating contact whose ``w_n'' + e w_n'`` is zero (to the tolerance) is widened:
    closed if frictionless, stuck if told to or not slipping, else slipping along its
    post-impact slip; the others kept. The kernel's compiled leaf on the same numbers."""
    pytest.importorskip("numba")
    from carnot.batch import multi_kernel as mk

    rng = np.random.default_rng(11)
    k = len(CONTACTS)
    nrow, trow, ntan, _, e = simultaneous._layout(CONTACTS)[:5]
    kinds = np.array([simultaneous._KIND_CODES[c.kind] for c in CONTACTS], dtype=np.int64)
    tol = 1e-9
    widened = set()
    for pattern in _patterns():
        w = rng.normal(size=8)
        after = rng.normal(size=8)
        for c in rng.choice(k, size=2, replace=False):  # two contacts at equality
            contact = CONTACTS[c]
            after[contact.normal] = -contact.restitution * w[contact.normal]
            if rng.uniform() < 0.5:
                after[list(contact.tangents)] = 0.0
        codes = np.array([regimes.OPTION_NAMES.index(o) for o in pattern], dtype=np.int64)
        runs = []
        for fn in (regimes.widest_pattern, mk._widest_pattern):
            wide, dirs = np.zeros(k, dtype=np.int64), np.zeros((k, 2))
            with np.errstate(invalid="ignore"):  # (a slip pattern given no slip: 0/0)
                runs.append((fn(nrow, trow, ntan, kinds, e, w, after, codes, tol, wide, dirs),
                             wide, dirs))  # fmt: skip
        assert runs[0][0] == runs[1][0]
        assert np.array_equal(runs[0][1], runs[1][1])
        assert np.array_equal(runs[0][2], runs[1][2], equal_nan=True)  # (a slip at rest: 0/0)
        changed, wide, dirs = runs[0]
        for c, (contact, option) in enumerate(zip(CONTACTS, pattern, strict=True)):
            n, t = contact.normal, list(contact.tangents)
            at_equality = abs(after[n] + contact.restitution * w[n]) <= tol
            slip = after[t]
            if option != "separate" or not at_equality:
                assert regimes.OPTION_NAMES[wide[c]] == option
            elif contact.kind == "frictionless":
                assert regimes.OPTION_NAMES[wide[c]] == "closed"
            elif contact.kind == "told_to_stick" or np.linalg.norm(slip) <= tol:
                assert regimes.OPTION_NAMES[wide[c]] == "stick"
            elif contact.kind == "planar":
                assert regimes.OPTION_NAMES[wide[c]] == ("slip+" if slip[0] > 0 else "slip-")
            else:
                assert regimes.OPTION_NAMES[wide[c]] == "slip"
            if regimes.OPTION_NAMES[wide[c]] == "slip" and np.linalg.norm(slip) > 0.0:
                assert np.allclose(dirs[c], slip / np.linalg.norm(slip), atol=1e-15)
            if wide[c] != codes[c]:
                widened.add(regimes.OPTION_NAMES[wide[c]])
        assert changed == bool(np.any(wide != codes))
    assert widened == {"closed", "stick", "slip", "slip+", "slip-"}


def test_a_slip_regime_holds_only_where_its_contacts_slip_as_assumed() -> None:
    pytest.importorskip("numba")
    from carnot.batch import multi_kernel as mk

    rng = np.random.default_rng(12)
    _, trow, _, _, _ = simultaneous._layout(CONTACTS)[:5]
    verdicts = set()
    for pattern in _patterns():
        codes = np.array([regimes.OPTION_NAMES.index(o) for o in pattern], dtype=np.int64)
        angle = rng.uniform(0.0, 2.0 * np.pi)
        dirs = np.zeros((len(CONTACTS), 2))
        dirs[0] = np.cos(angle), np.sin(angle)
        after = rng.normal(size=8)
        expected = True
        if pattern[0] == "slip":
            expected = float(dirs[0] @ after[[1, 2]]) > 1e-9
        if pattern[1] in ("slip+", "slip-"):
            expected &= (1.0 if pattern[1] == "slip+" else -1.0) * after[4] > 1e-9
        got = regimes.slips_as_assumed(trow, codes, dirs, after, 1e-9)
        assert got == expected == mk._slips_as_assumed(trow, codes, dirs, after, 1e-9)
        verdicts.add(got)
    assert verdicts == {True, False}


def test_the_verdict_on_each_group_of_answers() -> None:
    """Answers with the same velocities but other impulses: statically indeterminate; a
    second group of velocities, or a continuum: multiple solutions. The kernel's compiled
    leaves on the same numbers."""
    pytest.importorskip("numba")
    from carnot.batch import multi_kernel as mk

    rng = np.random.default_rng(13)
    base_wa, base_imp = rng.normal(size=6), rng.normal(size=6)
    seen = set()
    for _ in range(200):
        n = int(rng.integers(1, 6))
        groups = rng.integers(0, 2, size=n)  # which of two velocity sets each answer has
        cand_wa = np.array([base_wa + 0.5 * gr + 1e-12 * rng.normal() for gr in groups])
        same_imp = rng.uniform() < 0.5
        cand_imp = np.array([base_imp + (0.0 if same_imp else 1e-3 * rng.normal(size=6))
                             for _ in range(n)])  # fmt: skip
        not_unique = rng.uniform(size=n) < 0.2
        continuum = rng.uniform(size=n) < 0.2
        info = np.column_stack([not_unique, continuum]).astype(np.int64)
        firsts = regimes.answer_groups(cand_wa, n, 1e-8)
        assert firsts == mk._answer_groups(cand_wa, n, 1e-8)
        starts = [j for j in range(n) if (firsts >> j) & 1]
        assert [int(groups[j]) for j in starts] == list(dict.fromkeys(int(x) for x in groups))
        for f in starts:
            verdict = regimes.group_verdict(cand_imp, cand_wa, not_unique, continuum, n, f,
                                            firsts, 1e-8, 1e-8)  # fmt: skip
            members = [j for j in range(n) if groups[j] == groups[f]]
            differ = any(np.abs(cand_imp[j] - cand_imp[f]).max() > 1e-8 * np.abs(
                cand_imp[members]).max() for j in members)  # fmt: skip
            assert verdict == (bool(not_unique[members].any() or differ),
                               bool(len(starts) > 1 or continuum[members].any()))  # fmt: skip
            if f == 0:  # the kernel's report: the first answer's group
                assert mk._group_verdict(cand_imp, cand_wa, info[:, 0], info[:, 1], n, 0,
                                         firsts, 1e-8, 1e-8) == verdict  # fmt: skip
            seen.add(verdict)
    assert seen == {(False, False), (True, False), (False, True), (True, True)}
