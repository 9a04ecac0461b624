"""Siconos' frictional contact corpus (tests/data/siconos) and its error (carnot.io.siconos).

Every shipped file loads with consistent sizes; W is symmetric positive semi-definite to
round-off where Siconos ships it so (and within the stated margins where it does not); the
loader refuses malformed files by name; ``fc3d_error`` is zero at hand-made exact solutions,
positive off them, equal to hand computations, to a line-by-line transliteration of the C
loop, and to values that python3-siconos 4.4's ``fc3d_compute_error`` gave on these files.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

import carnot.io.siconos as siconos
from carnot.errors import InputError
from carnot.io.siconos import fc2d_error, fc3d_error, parse_siconos_fc, read_siconos_fc

DATA = Path(__file__).parent / "data" / "siconos"
FILES = sorted(DATA.glob("*.dat"))

# Files whose W Siconos ships symmetric and positive semi-definite to round-off.
SYMMETRIC = [
    "FrictionContact3D_1c.dat",
    "FC3D_Example1.dat",
    "FC3D_Example1_SBM.dat",
    "NESpheres_10_1.dat",
    "BoxesStack1-i100000-32.hdf5.dat",
    "FrictionContactProblem00031.dat",
    "FrictionContactProblem00071.dat",
    "FrictionContactProblem00374.dat",
    "FrictionContactProblem00394.dat",
]


def test_the_corpus_is_there() -> None:
    assert len(FILES) == 32
    assert sum(f.stat().st_size for f in FILES) < 5_000_000
    notice = " ".join((DATA / "NOTICE").read_text().split())
    assert "Apache License, Version 2.0" in notice
    assert "6070f0f6fcd9e12457f509211e88a1a583b811bc" in notice


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.name)
def test_every_file_loads_consistently(path: Path) -> None:
    problem = read_siconos_fc(path)
    m, nc, d = problem.size, problem.contacts, problem.dimension
    assert problem.name == path.name
    assert d in (2, 3) and nc > 0 and m == d * nc
    assert problem.delassus.shape == (m, m)
    assert problem.q.shape == (m,) and problem.mu.shape == (nc,)
    assert np.all(np.isfinite(problem.q)) and np.all(problem.mu >= 0.0)
    storage = path.read_text().split()[2]
    assert problem.storage == {"0": "dense", "1": "sparse-block"}[storage]
    assert sp.issparse(problem.delassus) == (problem.storage == "sparse-block")
    w = problem.dense_delassus()
    assert np.all(np.isfinite(w)) and np.all(np.diag(w) > 0.0)
    # as shipped: symmetric to 3e-3 and positive semi-definite to 1e-6, relative (README)
    scale = np.abs(w).max()
    assert np.abs(w - w.T).max() <= 3e-3 * scale
    assert np.linalg.eigvalsh((w + w.T) / 2).min() >= -1e-6 * scale


@pytest.mark.parametrize("name", SYMMETRIC)
def test_symmetric_positive_semidefinite_to_round_off(name: str) -> None:
    w = read_siconos_fc(DATA / name).dense_delassus()
    scale = np.abs(w).max()
    assert np.abs(w - w.T).max() <= 1e-15 * scale
    assert np.linalg.eigvalsh(w).min() >= -1e-14 * scale


def test_the_readme_lists_every_file_with_its_sizes() -> None:
    rows = re.findall(
        r"^\| `([^`]+)` \| (\d) \| (\d+) \| (\d+) \| ([a-z-]+) \|",
        (DATA / "README.md").read_text(),
        flags=re.M,
    )
    assert sorted(r[0] for r in rows) == [f.name for f in FILES]
    for name, d, nc, m, storage in rows:
        problem = read_siconos_fc(DATA / name)
        assert (problem.dimension, problem.contacts, problem.size, problem.storage) == (
            int(d), int(nc), int(m), storage,
        )  # fmt: skip


def test_dense_and_sparse_block_files_of_one_problem_agree() -> None:
    dense = read_siconos_fc(DATA / "FC3D_Example1.dat")
    block = read_siconos_fc(DATA / "FC3D_Example1_SBM.dat")
    assert np.array_equal(dense.delassus, block.dense_delassus())
    assert np.array_equal(dense.q, block.q) and np.array_equal(dense.mu, block.mu)


def test_dense_w_is_read_column_major() -> None:
    # Rover4396's second written line starts with -1.5433...e-4: column 1, row 0, as
    # python3-siconos' NM_get_value(M, 0, 1) gives it; row 1, column 0 is -1.5159...e-4.
    w = read_siconos_fc(DATA / "Rover4396.dat").delassus
    assert w[0, 1] == -1.543351006400240027841009e-04
    assert w[1, 0] == -1.515988037597431909581092e-04


def test_sparse_block_w_is_read_column_major_in_each_block() -> None:
    text = "3 2  1 6 6  2  2 2  3 6  3 6  3 2  0 1 2  0 1  "  # two diagonal 3x3 blocks
    text += "0 " + " ".join(str(v) for v in range(1, 10)) + " "
    text += "1 " + " ".join(str(v) for v in range(11, 20)) + " "
    text += "0 0 0 0 0 0  0.5 0.25"
    problem = parse_siconos_fc(text, "two.dat")
    w = problem.dense_delassus()
    assert w[:3, :3].tolist() == [[1, 4, 7], [2, 5, 8], [3, 6, 9]]
    assert w[3:, 3:].tolist() == [[11, 14, 17], [12, 15, 18], [13, 16, 19]]
    assert not w[:3, 3:].any() and not w[3:, :3].any()
    assert problem.mu.tolist() == [0.5, 0.25]


# values of python3-siconos 4.4: fc3d_compute_error(problem, r, u, 1e-8, options, ||q||)
# at r = (1 + 0.01 k for normal rows k, 0.3 cos k for tangent rows)
SICONOS_ERRORS = {
    "Rover4396.dat": 0.24912823609768278,
    "FC3D_Example1_SBM.dat": 0.07251267213602364,
    "NESpheres_10_1.dat": 0.4601616971763908,
    "Capsules-i101-404.dat": 0.34009041369953397,
    "Confeti-ex03-Fc3D-SBM.dat": 0.5852147850045667,
}


@pytest.mark.parametrize("name", sorted(SICONOS_ERRORS))
def test_fc3d_error_matches_siconos(name: str) -> None:
    problem = read_siconos_fc(DATA / name)
    k = np.arange(problem.size)
    r = np.where(k % 3 == 0, 1.0 + 0.01 * k, 0.3 * np.cos(k))
    assert problem.error(r) == pytest.approx(SICONOS_ERRORS[name], rel=1e-14)


def _c_loop_error(w: np.ndarray, q: np.ndarray, mu: np.ndarray, r: np.ndarray) -> float:
    """fc3d_compute_error and projectionOnCone, transliterated one contact at a time."""
    u = w @ r + q
    error = 0.0
    for ic in range(mu.size):
        z, v, m = r[3 * ic : 3 * ic + 3], u[3 * ic : 3 * ic + 3], mu[ic]
        t = [z[0] - v[0] - m * math.sqrt(v[1] * v[1] + v[2] * v[2]), z[1] - v[1], z[2] - v[2]]
        norm_t = math.sqrt(t[1] * t[1] + t[2] * t[2])
        if m * norm_t <= -t[0]:
            t = [0.0, 0.0, 0.0]
        elif norm_t <= m * t[0]:
            pass
        else:
            t[0] = (m * norm_t + t[0]) / (m * m + 1.0)
            t[1] = m * t[0] * t[1] / norm_t
            t[2] = m * t[0] * t[2] / norm_t
        error += sum((z[i] - t[i]) ** 2 for i in range(3))
    error = math.sqrt(error)
    scaling = max(np.linalg.norm(q), np.linalg.norm(r), np.linalg.norm(u))
    return error / scaling if scaling > 2.220446049250313e-16 else error


def test_fc3d_error_equals_the_c_loop_on_every_branch() -> None:
    rng = np.random.default_rng(7)
    nc = 40
    a = rng.standard_normal((3 * nc, 3 * nc))
    w = a @ a.T / (3 * nc)
    q = rng.standard_normal(3 * nc)
    mu = rng.uniform(0.0, 1.0, nc)
    mu[:3] = 0.0
    for scale in (0.0, 0.1, 1.0, 10.0):
        r = scale * rng.standard_normal(3 * nc)
        r[::3] = np.abs(r[::3])
        assert fc3d_error(w, q, mu, r) == pytest.approx(_c_loop_error(w, q, mu, r), rel=1e-13)
        assert fc3d_error(sp.csr_array(w), q, mu, r) == pytest.approx(
            fc3d_error(w, q, mu, r), rel=1e-14
        )


def test_fc3d_error_zero_at_exact_solutions() -> None:
    w, mu = np.eye(3), np.array([0.5])
    # sticking: r_n = 1, u = 0
    assert fc3d_error(w, np.array([-1.0, 0.0, 0.0]), mu, np.array([1.0, 0.0, 0.0])) == 0.0
    # sliding: r = (1, -0.5, 0) on the cone, u = (0, 1.5, 0), u_hat = (0.75, 1.5, 0) _|_ r
    assert fc3d_error(w, np.array([-1.0, 2.0, 0.0]), mu, np.array([1.0, -0.5, 0.0])) == 0.0
    # separating: r = 0, u = q = (1, 0.2, 0) with u_hat in the dual cone
    assert fc3d_error(w, np.array([1.0, 0.2, 0.0]), mu, np.zeros(3)) == 0.0
    # two contacts at once, block diagonal
    w2 = np.eye(6)
    q2 = np.array([-1.0, 2.0, 0.0, 1.0, 0.2, 0.0])
    r2 = np.array([1.0, -0.5, 0.0, 0.0, 0.0, 0.0])
    assert fc3d_error(w2, q2, np.array([0.5, 0.5]), r2) == 0.0


def test_fc3d_error_positive_off_a_solution() -> None:
    w, q, mu = np.eye(3), np.array([-1.0, 2.0, 0.0]), np.array([0.5])
    r = np.array([1.0, -0.5, 0.0])
    for delta in ([1e-6, 0, 0], [0, 1e-6, 0], [0, 0, 1e-6], [-0.5, 0, 0]):
        assert fc3d_error(w, q, mu, r + np.array(delta)) > 0.0


def test_fc3d_error_by_hand() -> None:
    # FrictionContact3D_1c at r = 0: u = q = (-1, 2, 3), mu = 0.1, |u_t| = sqrt(13);
    # r - u_hat = (1 - 0.1 sqrt 13, -2, -3) projects on the boundary to p with
    # p_n = 1 / 1.01, |p_t| = 0.1 p_n, so |e| = |p| = 1 / sqrt(1.01); over ||q|| = sqrt(14).
    problem = read_siconos_fc(DATA / "FrictionContact3D_1c.dat")
    expected = 1.0 / math.sqrt(1.01) / math.sqrt(14.0)
    assert problem.error(np.zeros(3)) == pytest.approx(expected, rel=1e-15)
    # stick with r_n 10 % too large: e = (0.1, 0, 0), scaling max(1, 1.1, 0.1)
    e = fc3d_error(np.eye(3), np.array([-1.0, 0, 0]), np.array([0.5]), np.array([1.1, 0, 0]))
    assert e == pytest.approx(0.1 / 1.1, rel=1e-14)
    # all zero: no division (scaling below DBL_EPSILON)
    assert fc3d_error(np.eye(3), np.zeros(3), np.array([0.5]), np.zeros(3)) == 0.0


def test_fc2d_error() -> None:
    w, q, mu = np.eye(2), np.array([-1.0, 2.0]), np.array([0.5])
    assert fc2d_error(w, q, mu, np.array([1.0, -0.5])) == 0.0
    assert fc2d_error(w, q, mu, np.array([1.0, 0.0])) > 0.0
    # the 2D error is the 3D one with a zero second tangent
    rng = np.random.default_rng(3)
    for _ in range(20):
        r2, q2 = rng.standard_normal(2), rng.standard_normal(2)
        a = rng.standard_normal((2, 2))
        w2 = a @ a.T
        w3 = np.zeros((3, 3))
        w3[:2, :2] = w2
        w3[2, 2] = 1.0
        e3 = fc3d_error(w3, np.append(q2, 0.0), mu, np.append(r2, 0.0))
        assert fc2d_error(w2, q2, mu, r2) == pytest.approx(e3, rel=1e-14, abs=1e-300)
    problem = read_siconos_fc(DATA / "FrictionContactProblem00394.dat")
    assert problem.error(np.zeros(problem.size)) > 0.0


@pytest.mark.parametrize(
    ("args", "field"),
    [
        ((np.eye(3), np.zeros(3), np.array([0.5]), np.zeros(6)), "r"),
        ((np.eye(3), np.zeros(6), np.array([0.5]), np.zeros(3)), "q"),
        ((np.eye(6), np.zeros(3), np.array([0.5]), np.zeros(3)), "W"),
        ((np.eye(3), np.zeros(3), np.array([-0.5]), np.zeros(3)), "mu"),
    ],
)
def test_fc3d_error_refuses_bad_shapes(args: tuple[np.ndarray, ...], field: str) -> None:
    with pytest.raises(InputError) as caught:
        fc3d_error(*args)
    assert caught.value.field == field


ONE = "3 1 0 3 3 3 3  15 -1 -2 -1 14 1 -2 1 16  -1 2 3  0.1"


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("", "x.dat: dimension: missing"),
        ("4 1", "x.dat: dimension: must be <= 3, got 4"),
        ("3 -1", "x.dat: contacts: must be >= 0, got -1"),
        ("3 1.5", "x.dat: contacts: must be an integer, got '1.5'"),
        ("3 1 2 3 3", "x.dat: W storage: is 2 (a CSparse matrix"),
        ("3 1 7 3 3", "x.dat: W storage: must be 0 (dense) or 1 (sparse block), got 7"),
        ("3 1 0 6 6", "x.dat: W size: must be 3 x 3 (dimension 3 x 1 contacts), got '6 x 6'"),
        ("3 1 0 3 3 3 4", "x.dat: W (dense) size: must repeat 3 x 3, got '3 x 4'"),
        (ONE[:30], "x.dat: W (dense): ends after 5 of its 9 entries"),
        (ONE.replace("14", "abc"), "x.dat: W (dense)[4]: must be a finite number, got 'abc'"),
        (ONE.replace("14", "nan"), "x.dat: W (dense)[4]: must be a finite number, got 'nan'"),
        (ONE.replace("14", "1_4"), "x.dat: W (dense)[4]: must be a finite number, got '1_4'"),
        (ONE.replace("14", "1e"), "x.dat: W (dense)[4]: must be a finite number, got '1e'"),
        (ONE.replace(" 0.1", ""), "x.dat: mu: ends after 0 of its 1 entries"),
        (ONE.replace("0.1", "-0.1"), "x.dat: mu[0]: must be >= 0, got -0.1"),
        (ONE + " 1 2", "x.dat: after mu: 2 more numbers, where a local problem ends"),
        (ONE + " 0.5", "x.dat: after mu: 1 more numbers"),
        ("3 1 1 3 3 1 1 1 2 3 2 1 0 1 0 0 1 0 0 0 1 0 0 0 1 0 0 0 0.1",
         "x.dat: W (sparse block) blocksize0: must increase strictly from above 0 to 3"),
        ("3 1 1 3 3 1 1 1 3 3 2 1 0 1 5 0 1 0 0 0 1 0 0 0 1 0 0 0 0.1",
         "x.dat: W (sparse block) index2_data: must lie in 0..0"),
        ("3 1 1 3 3 1 1 1 3 3 3 1 0 1 0 0 1 0 0 0 1 0 0 0 1 0 0 0 0.1",
         "x.dat: W (sparse block) filled1: must be blocknumber0 + 1 = 2, got 3"),
        ("3 1 1 3 3 1 1 1 3 3 2 1 0 1 0 4 1 0 0 0 1 0 0 0 1 0 0 0 0.1",
         "x.dat: W (sparse block) block 0 number: must be 0, got 4.0"),
        ("3 1 1 3 3 1 1 1 3 3 2 1 0 1 0 0 1 0 0 0 1 0 0 0",
         "x.dat: W (sparse block) blocks: ends after 9 of its 10 entries"),
    ],
)  # fmt: skip
def test_malformed_files_are_refused_by_name(text: str, message: str) -> None:
    with pytest.raises(InputError) as caught:
        parse_siconos_fc(text, "x.dat")
    assert str(caught.value).startswith(message)


def test_an_empty_sparse_block_matrix_is_zero() -> None:
    problem = parse_siconos_fc("3 1 1 3 3 0  -1 0 0  0.3", "zero.dat")
    assert problem.dense_delassus().tolist() == np.zeros((3, 3)).tolist()


def test_global_and_csparse_files_of_siconos_are_refused(tmp_path: Path) -> None:
    # the head of GFC3D_Example00.dat: M (3 x 3), H, q, b, mu; and of a CSparse fc2d file
    gfc = "3 1 0 3 3 3 3 1 0 0 0 1 0 0 0 1 0 3 3 3 3 1 0 0 0 1 0 0 0 1 -1 -1 -1 0 0 0 0.5"
    with pytest.raises(InputError, match=r"after mu: \d+ more numbers"):
        parse_siconos_fc(gfc, "GFC3D.dat")
    with pytest.raises(InputError, match="W storage: is 2"):
        parse_siconos_fc("2 667 2 1334 1334 2 CSparse Version 3.1.9", "fc2d.dat")


def test_file_errors(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    with pytest.raises(InputError, match="cannot read the file"):
        read_siconos_fc(tmp_path / "missing.dat")
    binary = tmp_path / "binary.dat"
    binary.write_bytes(b"3 1 \xff")
    with pytest.raises(InputError, match=r"binary.dat: is not a text file of numbers \(byte 4\)"):
        read_siconos_fc(binary)
    big = tmp_path / "big.dat"
    big.write_text(ONE)
    monkeypatch.setattr(siconos, "MAX_FILE_BYTES", 10)
    with pytest.raises(InputError, match="is larger than 10 bytes"):
        read_siconos_fc(big)
