"""Siconos' frictional contact problems: the text files of its test corpus, and its error.

Siconos (https://github.com/siconos/siconos, Apache-2.0) ships, under
``numerics/src/FrictionContact/test/data``, some sixty frictional contact problems that its own
solvers are tested on. The local ones (``fc3d``, ``fc2d``) are::

    u = W r + q,    per contact r = (r_n, r_t...) in Coulomb's cone |r_t| <= mu r_n,
    u_hat = u + mu |u_t| e_n in the dual cone,    r . u_hat = 0,

with W the Delassus matrix (m x m, m = dimension x contacts). They are a ready corpus for the
many-contact solvers (:func:`carnot.solvers.solve_fc3d`), and this module reads them and
measures an answer the way Siconos does, independently of any solver.

**The format** (written by ``frictionContact_printInFile`` and read by
``frictionContact_newFromFile``, ``numerics/src/FrictionContact/FrictionContactProblem.c``),
whitespace-separated numbers::

    dimension            2 or 3
    contacts             nc
    W                    a NumericsMatrix (NM_write_in_file, numerics/src/linalg/NumericsMatrix.c)
    q                    m floats
    mu                   nc floats

The matrix starts with ``storage size0 size1``. Storage ``0`` (dense) repeats ``size0 size1``,
then holds the ``size0 * size1`` entries in column-major order (``matrix0[i + j * size0]``:
each written line of the file is a *column* of W). Storage ``1`` (sparse block,
``SBM_write_in_file``, ``numerics/src/linalg/SparseBlockMatrix.c``) holds ``nbblocks``, the
numbers of block rows and block columns, the cumulative row and column sizes of the blocks,
``filled1 filled2``, the block-row pointers (``filled1`` of them) and the block-column indices
(``filled2``), then each block as its number followed by its entries in column-major order.
Storage ``2`` (a CSparse matrix as ``cs_print`` shows it, six significant digits) occurs only
in two-dimensional granular-flow files and is refused here. After ``mu`` one integer may follow
(some files end with a leftover ``0`` or ``1``, which Siconos ignores); more numbers are
refused, as they mean another format (a global problem, ``GFC3D``, whose first matrix would
otherwise be read as W).

The file is parsed as data: numbers only, checked against the sizes they must have; a
malformed file raises :class:`carnot.errors.InputError` naming the file and the field. A file
may have at most :data:`MAX_FILE_BYTES` bytes.

**The error** (:func:`fc3d_error`, :func:`fc2d_error`) is ``fc3d_compute_error``
(``numerics/src/FrictionContact/fc3d_compute_error.c``) and ``fc2d_compute_error``
(``fc2d_compute_error.c``): per contact the natural map ``r - P_K(r - u_hat)``, with ``P_K``
the projection on Coulomb's cone (``projectionOnCone``, ``numerics/src/linalg/
projectionOnCone.c``), its norm over all contacts, divided by
``max(||q||, ||r||, ||u||)`` when that exceeds ``DBL_EPSILON`` (the solvers pass
``norm = ||q||``, e.g. ``fc3d_nsgs.c``). It is zero exactly at a solution. The sums run in
NumPy's order, not the C loop's, so the two agree to round-off, not to the bit.

>>> text = '''3
... 1
... 0 3 3
... 3 3
... 15 -1 -2
... -1 14 1
... -2 1 16
... -1 2 3
... 0.1'''
>>> problem = parse_siconos_fc(text, "FrictionContact3D_1c.dat")
>>> problem.size, problem.contacts, problem.storage, problem.mu.tolist()
(3, 1, 'dense', [0.1])
>>> problem.delassus[0].tolist()
[15.0, -1.0, -2.0]
>>> fc3d_error(problem.delassus, problem.q, problem.mu, np.zeros(3)) > 0
True
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from carnot.errors import InputError
from carnot.io.files import read_text

MAX_FILE_BYTES = 64 * 1024 * 1024
"""The largest file :func:`read_siconos_fc` reads (Siconos' largest local file has 4 MB)."""

DBL_EPSILON = float(np.finfo(np.float64).eps)

_STORAGES = {0: "dense", 1: "sparse-block"}
_INT = re.compile(r"[+-]?[0-9]+\Z")
_NUMBERS = re.compile(r"[0-9eE.+\- ]*\Z")  # no letters: no nan, inf, hex or 1_000
_FLOAT = re.compile(r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?\Z")


@dataclass(frozen=True)
class FrictionContactProblem:
    """A local frictional contact problem ``u = W r + q`` as Siconos stores it.

    ``delassus`` is W: an ``(m, m)`` float ndarray for a dense file, a
    ``scipy.sparse.csr_array`` for a sparse-block one (:meth:`dense_delassus` gives an array
    either way). ``q`` has ``m`` entries and ``mu`` one per contact; contact ``i`` owns the
    rows ``dimension * i`` (normal) to ``dimension * i + dimension - 1`` (tangents).
    """

    name: str
    dimension: int
    delassus: Any
    q: NDArray[np.float64]
    mu: NDArray[np.float64]
    storage: str

    @property
    def contacts(self) -> int:
        """The number of contacts, nc."""
        return int(self.mu.shape[0])

    @property
    def size(self) -> int:
        """The number of unknowns, m = dimension x nc."""
        return int(self.q.shape[0])

    def dense_delassus(self) -> NDArray[np.float64]:
        """W as a dense ``(m, m)`` array (a copy for a sparse W)."""
        if sp.issparse(self.delassus):
            return np.asarray(self.delassus.toarray(), dtype=np.float64)
        return np.asarray(self.delassus, dtype=np.float64)

    def error(self, r: Any) -> float:
        """Siconos' relative error of the reaction ``r`` (:func:`fc3d_error` or
        :func:`fc2d_error`, by dimension)."""
        check = fc3d_error if self.dimension == 3 else fc2d_error
        return check(self.delassus, self.q, self.mu, r)


def read_siconos_fc(path: str | Path) -> FrictionContactProblem:
    """The problem in a Siconos fc3d/fc2d text file (its name: the file's name)."""
    text = read_text(path, MAX_FILE_BYTES, "Siconos", "ascii", "a text file of numbers")
    return parse_siconos_fc(text, Path(path).name)


def parse_siconos_fc(text: str, name: str = "<siconos>") -> FrictionContactProblem:
    """The problem in the text of a Siconos fc3d/fc2d file; ``name`` labels errors.

    >>> parse_siconos_fc("3 1 0 3 3 3 3 1 0 0", "bad.dat")
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: bad.dat: W (dense): ends after 3 of its 9 entries
    """
    reader = _Reader(text.split(), name)
    dimension = reader.integer("dimension", low=2, high=3)
    contacts = reader.integer("contacts", low=0)
    m = dimension * contacts
    storage_code = reader.integer("W storage")
    if storage_code not in _STORAGES:
        problem = (
            "is 2 (a CSparse matrix, printed to six digits), which is not supported"
            if storage_code == 2
            else "must be 0 (dense) or 1 (sparse block)"
        )
        raise InputError(reader.field("W storage"), problem, storage_code)
    size0 = reader.integer("W size0", low=0)
    size1 = reader.integer("W size1", low=0)
    if size0 != m or size1 != m:
        raise InputError(
            reader.field("W size"),
            f"must be {m} x {m} (dimension {dimension} x {contacts} contacts)",
            f"{size0} x {size1}",
        )
    if storage_code == 0:
        delassus: Any = _dense(reader, m)
    else:
        delassus = _sparse_block(reader, m)
    q = reader.floats(m, "q")
    mu = reader.floats(contacts, "mu")
    if np.any(mu < 0.0):
        i = int(np.flatnonzero(mu < 0.0)[0])
        raise InputError(reader.field(f"mu[{i}]"), "must be >= 0", float(mu[i]))
    rest = reader.tokens[reader.at :]
    if len(rest) > 1 or (rest and not _INT.match(rest[0])):
        raise InputError(
            reader.field("after mu"),
            f"{len(rest)} more numbers, where a local problem ends (or leaves one integer);"
            " a global problem (GFC3D: M, H, q, b, mu) is not read here",
            show_value=False,
        )
    return FrictionContactProblem(name, dimension, delassus, q, mu, _STORAGES[storage_code])


class _Reader:
    """Tokens read in order, each checked as an integer or a finite float."""

    def __init__(self, tokens: list[str], name: str) -> None:
        self.tokens = tokens
        self.name = name
        self.at = 0

    def field(self, field: str) -> str:
        return f"{self.name}: {field}"

    def integer(self, field: str, *, low: int | None = None, high: int | None = None) -> int:
        if self.at >= len(self.tokens):
            raise InputError(self.field(field), "missing (the file ends before it)",
                             show_value=False)  # fmt: skip
        token = self.tokens[self.at]
        if not _INT.match(token):
            raise InputError(self.field(field), "must be an integer", token)
        self.at += 1
        value = int(token)
        if low is not None and value < low:
            raise InputError(self.field(field), f"must be >= {low}", value)
        if high is not None and value > high:
            raise InputError(self.field(field), f"must be <= {high}", value)
        return value

    def integers(self, n: int, field: str) -> NDArray[np.int64]:
        chunk = self._take(n, field)
        for k, token in enumerate(chunk):
            if not _INT.match(token):
                raise InputError(self.field(f"{field}[{k}]"), "must be an integer", token)
        return np.array([int(t) for t in chunk], dtype=np.int64)

    def floats(self, n: int, field: str) -> NDArray[np.float64]:
        chunk = self._take(n, field)
        if _NUMBERS.match(" ".join(chunk)):
            try:
                return np.array(chunk, dtype=np.float64) if chunk else np.zeros(0)
            except ValueError:
                pass
        for k, token in enumerate(chunk):  # the slow path, to name the bad entry
            if not _FLOAT.match(token):
                raise InputError(self.field(f"{field}[{k}]"), "must be a finite number", token)
        raise AssertionError("unreachable: every token matched")  # pragma: no cover

    def _take(self, n: int, field: str) -> list[str]:
        left = len(self.tokens) - self.at
        if n > left:
            raise InputError(self.field(field), f"ends after {left} of its {n} entries",
                             show_value=False)  # fmt: skip
        chunk = self.tokens[self.at : self.at + n]
        self.at += n
        return chunk


def _dense(reader: _Reader, m: int) -> NDArray[np.float64]:
    rows = reader.integer("W (dense) size0")
    cols = reader.integer("W (dense) size1")
    if rows != m or cols != m:
        raise InputError(reader.field("W (dense) size"), f"must repeat {m} x {m}",
                         f"{rows} x {cols}")  # fmt: skip
    values = reader.floats(m * m, "W (dense)")
    # column-major: Siconos' matrix0[i + j * size0] is W[i, j]
    return np.ascontiguousarray(values.reshape((m, m), order="F"))


def _sparse_block(reader: _Reader, m: int) -> Any:
    label = "W (sparse block)"
    nbblocks = reader.integer(f"{label} nbblocks", low=0)
    if nbblocks == 0:
        return sp.csr_array((m, m), dtype=np.float64)
    block_rows = reader.integer(f"{label} blocknumber0", low=1)
    block_cols = reader.integer(f"{label} blocknumber1", low=1)
    row_ends = reader.integers(block_rows, f"{label} blocksize0")
    col_ends = reader.integers(block_cols, f"{label} blocksize1")
    for ends, field in ((row_ends, "blocksize0"), (col_ends, "blocksize1")):
        if np.any(np.diff(ends, prepend=0) <= 0) or ends[-1] != m:
            raise InputError(
                reader.field(f"{label} {field}"),
                f"must increase strictly from above 0 to {m} (cumulative block sizes)",
                ends.tolist() if ends.size <= 20 else f"{ends.size} sizes ending {ends[-1]}",
            )
    filled1 = reader.integer(f"{label} filled1")
    if filled1 != block_rows + 1:
        raise InputError(reader.field(f"{label} filled1"),
                         f"must be blocknumber0 + 1 = {block_rows + 1}", filled1)  # fmt: skip
    filled2 = reader.integer(f"{label} filled2")
    if filled2 != nbblocks:
        raise InputError(reader.field(f"{label} filled2"), f"must be nbblocks = {nbblocks}",
                         filled2)  # fmt: skip
    row_start = reader.integers(filled1, f"{label} index1_data")
    if row_start[0] != 0 or row_start[-1] != nbblocks or np.any(np.diff(row_start) < 0):
        raise InputError(
            reader.field(f"{label} index1_data"),
            f"must rise from 0 to nbblocks = {nbblocks}",
            show_value=False,
        )
    col_index = reader.integers(filled2, f"{label} index2_data")
    if np.any(col_index < 0) or np.any(col_index >= block_cols):
        raise InputError(
            reader.field(f"{label} index2_data"),
            f"must lie in 0..{block_cols - 1} (block columns)",
            show_value=False,
        )
    block_row = np.repeat(np.arange(block_rows), np.diff(row_start))  # of each block
    same_row = block_row[1:] == block_row[:-1]
    if np.any(same_row & (np.diff(col_index) <= 0)):
        i = int(block_row[1:][same_row & (np.diff(col_index) <= 0)][0])
        raise InputError(reader.field(f"{label} index2_data, block row {i}"),
                         "must increase strictly (each block once)",
                         col_index[row_start[i] : row_start[i + 1]].tolist())  # fmt: skip
    # every block: its number, then its entries in column-major order
    row_first = np.concatenate(([0], row_ends[:-1]))
    col_first = np.concatenate(([0], col_ends[:-1]))
    n_rows = (row_ends - row_first)[block_row]
    n_cols = (col_ends - col_first)[col_index]
    sizes = n_rows * n_cols
    chunk = reader.floats(int(np.sum(sizes + 1)), f"{label} blocks")
    heads = np.concatenate(([0], np.cumsum(sizes + 1)[:-1]))
    wrong = np.flatnonzero(chunk[heads] != np.arange(nbblocks))
    if wrong.size:
        b = int(wrong[0])
        raise InputError(reader.field(f"{label} block {b} number"), f"must be {b}",
                         float(chunk[heads[b]]))  # fmt: skip
    is_entry = np.ones(chunk.size, dtype=bool)
    is_entry[heads] = False
    block = np.repeat(np.arange(nbblocks), sizes)  # of each entry
    k = np.arange(block.size) - np.repeat(np.cumsum(sizes) - sizes, sizes)
    rows = row_first[block_row][block] + k % n_rows[block]
    cols = col_first[col_index][block] + k // n_rows[block]
    return sp.coo_array((chunk[is_entry], (rows, cols)), shape=(m, m)).tocsr()


def fc3d_error(w: Any, q: Any, mu: Any, r: Any) -> float:
    """Siconos' relative error of a 3D reaction ``r``: ``fc3d_compute_error`` with
    ``norm = ||q||``.

    ``u = W r + q``; per contact ``e = r - P_K(r - u_hat)``, ``u_hat = (u_n + mu |u_t|, u_t)``;
    the result is ``||e|| / max(||q||, ||r||, ||u||)`` (undivided when that maximum is at most
    ``DBL_EPSILON``). ``W`` is an array or a scipy sparse matrix.

    >>> w, q, mu = np.eye(3), np.array([-1.0, 2.0, 0.0]), np.array([0.5])
    >>> fc3d_error(w, q, mu, np.array([1.0, -0.5, 0.0]))  # sliding: u = (0, 1.5, 0)
    0.0
    >>> e = fc3d_error(w, np.array([-1.0, 0.0, 0.0]), mu, np.array([1.1, 0.0, 0.0]))
    >>> round(e, 12), round(0.1 / 1.1, 12)  # |r - u_hat - r| = 0.1 over max(1, 1.1, 0.1)
    (0.090909090909, 0.090909090909)
    """
    return _natural_map_error(w, q, mu, r, 3)


def fc2d_error(w: Any, q: Any, mu: Any, r: Any) -> float:
    """Siconos' relative error of a 2D reaction ``r``: ``fc2d_compute_error`` with
    ``norm = ||q||`` (the 3D formula with one tangent).

    >>> fc2d_error(np.eye(2), np.array([-1.0, 2.0]), np.array([0.5]), np.array([1.0, -0.5]))
    0.0
    """
    return _natural_map_error(w, q, mu, r, 2)


def _natural_map_error(w: Any, q: Any, mu: Any, r: Any, dimension: int) -> float:
    q = np.asarray(q, dtype=np.float64)
    mu = np.asarray(mu, dtype=np.float64)
    r = np.asarray(r, dtype=np.float64)
    if mu.ndim != 1:
        raise InputError("mu", "must be a vector (one coefficient per contact)", mu.shape)
    if np.any(mu < 0.0):
        raise InputError("mu", "must be >= 0", mu)
    m = dimension * mu.shape[0]
    if q.shape != (m,):
        raise InputError("q", f"must have shape ({m},) ({dimension} x {mu.shape[0]} contacts)",
                         q.shape)  # fmt: skip
    if r.shape != (m,):
        raise InputError("r", f"must have shape ({m},)", r.shape)
    if tuple(w.shape) != (m, m):
        raise InputError("W", f"must have shape ({m}, {m})", tuple(w.shape))
    u = np.asarray(w @ r, dtype=np.float64).reshape(m) + q
    rc = r.reshape(-1, dimension)
    uc = u.reshape(-1, dimension)
    # worktmp = r - u_hat  (fc3d_unitary_compute_and_add_error)
    x = rc - uc
    x[:, 0] -= mu * np.sqrt(np.sum(uc[:, 1:] ** 2, axis=1))
    # projectionOnCone(worktmp, mu): three cases, in the C order
    norm_t = np.sqrt(np.sum(x[:, 1:] ** 2, axis=1))
    polar = mu * norm_t <= -x[:, 0]
    inside = ~polar & (norm_t <= mu * x[:, 0])
    boundary = ~polar & ~inside
    p = x.copy()
    p[polar] = 0.0
    if np.any(boundary):
        mb, tb, xb = mu[boundary], norm_t[boundary], x[boundary]
        p0 = (mb * tb + xb[:, 0]) / (mb * mb + 1.0)
        p[boundary, 0] = p0
        if dimension == 3:
            p[boundary, 1:] = (mb * p0)[:, None] * xb[:, 1:] / tb[:, None]
        else:
            p[boundary, 1] = mb * p0 * np.sign(xb[:, 1])
    error = float(np.sqrt(np.sum((rc - p) ** 2)))
    scaling = max(float(np.linalg.norm(q)), float(np.linalg.norm(r)), float(np.linalg.norm(u)))
    if abs(scaling) > DBL_EPSILON:
        error /= scaling
    return error
