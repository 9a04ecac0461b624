"""Pictures of a sweep (matplotlib): the dissipated energy over the first one or two varied
keys, and the regime of the (first) contact.

* One key: ``E_d`` against it, coloured by the regime. Where several rows share a value
  (further keys varied, Monte Carlo samples) the mean is drawn with the 5-95 % band; Monte
  Carlo values of the key are binned (a sample of the points is drawn beside).
* Two keys: a map of ``E_d`` (the mean of the rows in each cell: a grid's cells, or hexagons
  for Monte Carlo values) and, when the regime changes over it, a map of the regime (the most
  common one per cell).

A sweep of periodic orbits (a ``[model]`` scenario, the ``cycle`` route) is drawn as a
bifurcation diagram instead (:func:`plot_orbits`): the orbit's first coordinate on the
section, the largest Floquet multiplier's modulus against 1, and the energy per period, over
the first varied key, stable orbits filled and unstable ones hollow.

The varied keys are the file's first columns (those before the first result column). Uses
matplotlib's object-oriented API (no display); imported only when a picture is asked for.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.colors import BoundaryNorm, ListedColormap
from matplotlib.figure import Figure

from carnot.errors import InputError

_RESULT = re.compile(r"(contacts|constraints)\.\d+\.impulse_x$|bodies\..*\.velocity_after_x$"
                     r"|energy_before$|period$")  # fmt: skip
_REGIME_COLOURS = ("#1f4e9c", "#c0392b", "#2e8b57", "#e69f00", "#8e44ad", "#7f7f7f",
                   "#56b4e9", "#d55e00")  # fmt: skip
_GRID_LIMIT = 2000  # more distinct values than this: treated as continuous (Monte Carlo)


def check_plot_path(path: str | Path) -> Path:
    """A picture path matplotlib can write (by its suffix), checked before a sweep runs.

    >>> check_plot_path("out.docx")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: --plot: must end in a picture suffix (...), got 'out.docx'
    """
    p = Path(path)
    formats = Figure().canvas.get_supported_filetypes()
    if p.suffix.lower().lstrip(".") not in formats:
        raise InputError("--plot", f"must end in a picture suffix ({', '.join(sorted(formats))})",
                         str(path))  # fmt: skip
    if not p.parent.is_dir():
        raise InputError("--plot", "its folder does not exist", str(path))
    return p


def save_figure(fig: Figure, path: str | Path | None) -> Figure:
    """Write ``fig`` to ``path`` (150 dpi) when given; an unwritable path is an InputError
    on ``--plot``. Returns ``fig``."""
    if path is not None:
        try:
            fig.savefig(path, dpi=150)
        except OSError as err:
            raise InputError("--plot", f"cannot write the picture ({err.strerror})",
                             str(path)) from None  # fmt: skip
    return fig


def varied_keys(names: list[str]) -> list[str]:
    """The varied keys of a sweep file: its columns before the first result column.

    >>> varied_keys(["contacts.0.restitution", "contacts.0.impulse_x", "energy_before"])
    ['contacts.0.restitution']
    """
    out = []
    for name in names:
        if _RESULT.match(name):
            break
        out.append(name)
    return out


def _codes(column: Any) -> tuple[np.ndarray, list[str]]:
    """Integer codes and their names for a regime column (Arrow dictionary or strings)."""
    import pyarrow as pa

    if pa.types.is_dictionary(column.type):
        column = column.cast(pa.string())
    names, codes = np.unique(np.asarray(column.to_numpy(zero_copy_only=False), dtype=str),
                             return_inverse=True)  # fmt: skip
    return codes.ravel(), [str(n) for n in names]


def plot_sweep(source: Any, path: str | Path | None = None, *,
               keys: list[str] | None = None) -> Figure:  # fmt: skip
    """Draw a sweep's dissipated energy over its first one or two varied keys (see the module
    docstring); ``source`` is a sweep file or an Arrow table; save to ``path`` when given.

    >>> import pyarrow as pa
    >>> table = pa.table({"contacts.0.restitution": np.linspace(0, 1, 5),
    ...                   "contacts.0.impulse_x": np.zeros(5),
    ...                   "contacts.0.regime": ["frictionless"] * 5,
    ...                   "dissipated": 1.44 * (1 - np.linspace(0, 1, 5) ** 2)})
    >>> len(plot_sweep(table).axes)
    1
    """
    if path is not None:
        check_plot_path(path)
    if isinstance(source, (str, Path)):
        import pyarrow.parquet as pq

        from carnot.io.sweep_files import read_sweep

        names = (pq.read_schema(source).names if str(source).lower().endswith(".parquet")
                 else read_sweep(source).column_names)  # fmt: skip
        if "max_multiplier" in names:
            return plot_orbits(read_sweep(source), path)
        keys = keys or varied_keys(names)[:2]
        regime_col = next((n for n in names if n.endswith(".regime")), None)
        table = read_sweep(source, [*keys, "dissipated", *([regime_col] if regime_col else [])])
    else:
        table = source
        if "max_multiplier" in table.column_names:
            return plot_orbits(table, path)
        keys = keys or varied_keys(table.column_names)[:2]
        regime_col = next((n for n in table.column_names if n.endswith(".regime")), None)
    if not keys:
        raise InputError("plot", "the sweep file has no varied key to draw against",
                         table.column_names)  # fmt: skip
    dissipated = np.asarray(table.column("dissipated").to_numpy(), dtype=float)
    if regime_col:
        codes, regimes = _codes(table.column(regime_col))
    else:
        codes, regimes = np.zeros(len(dissipated), dtype=np.int64), ["(no contact)"]
    x = np.asarray(table.column(keys[0]).to_numpy(), dtype=float)
    if len(keys) == 1:
        fig = Figure(figsize=(8.0, 5.0), layout="constrained")
        _draw_one(fig.add_subplot(), x, dissipated, codes, regimes, keys[0])
    else:
        y = np.asarray(table.column(keys[1]).to_numpy(), dtype=float)
        several = len(np.unique(codes)) > 1
        fig = Figure(figsize=(13.0, 5.5) if several else (8.0, 6.0), layout="constrained")
        axes = fig.subplots(1, 2) if several else [fig.add_subplot()]
        _draw_two(fig, axes, x, y, dissipated, codes, regimes, keys)
    only = "" if len(np.unique(codes)) > 1 else f"; regime: {regimes[int(codes[0])]}"
    fig.suptitle(f"Dissipated energy $E_d = E' - E''$ over {len(dissipated):,} impacts{only}",
                 fontsize=12)  # fmt: skip
    return save_figure(fig, path)


def _cells(x: np.ndarray) -> tuple[np.ndarray, np.ndarray, bool]:
    """Grid values and each row's index among them; or, for Monte Carlo values, 60 bins."""
    values, index = np.unique(x, return_inverse=True)
    if len(values) <= _GRID_LIMIT:
        return values, index.ravel(), True
    edges = np.linspace(x.min(), x.max(), 61)
    index = np.clip(np.searchsorted(edges, x, side="right") - 1, 0, 59)
    return 0.5 * (edges[1:] + edges[:-1]), index, False


def _mode(cell: np.ndarray, codes: np.ndarray, n_cells: int, n_codes: int) -> np.ndarray:
    counts = np.bincount(cell * n_codes + codes, minlength=n_cells * n_codes)
    return np.argmax(counts.reshape(n_cells, n_codes), axis=1)


def _draw_one(ax: Any, x: np.ndarray, e_d: np.ndarray, codes: np.ndarray, regimes: list[str],
              key: str) -> None:  # fmt: skip
    centres, cell, grid = _cells(x)
    n = len(centres)
    count = np.bincount(cell, minlength=n)
    mean = np.bincount(cell, weights=e_d, minlength=n) / np.maximum(count, 1)
    mode = _mode(cell, codes, n, len(regimes))
    if not grid or count.max() > 1:  # several rows per value: spread, and a sample of points
        order = np.argsort(cell, kind="stable")
        bounds = np.concatenate([[0], np.cumsum(count)])
        low = np.array([np.percentile(e_d[order[a:b]], 5) if b > a else np.nan
                        for a, b in zip(bounds[:-1], bounds[1:], strict=True)])  # fmt: skip
        high = np.array([np.percentile(e_d[order[a:b]], 95) if b > a else np.nan
                         for a, b in zip(bounds[:-1], bounds[1:], strict=True)])  # fmt: skip
        ax.fill_between(centres, low, high, color="0.85", label="5-95 % of the rows")
        if not grid:
            pick = np.random.default_rng(0).permutation(len(x))[:5000]
            ax.scatter(x[pick], e_d[pick], s=3, color="0.55", alpha=0.35, linewidths=0,
                       label="rows (a sample)", rasterized=True)  # fmt: skip
    for r, name in enumerate(regimes):
        if np.any(mode == r):
            ax.plot(
                centres,
                np.where(mode == r, mean, np.nan),
                linewidth=2.2,
                color=_REGIME_COLOURS[r % len(_REGIME_COLOURS)],
                marker="o" if n <= 40 else None,
                markersize=4,
                label=f"{'mean, ' if count.max() > 1 or not grid else ''}{name}",
            )
    ax.set_xlabel(key)
    ax.set_ylabel("dissipated energy $E_d$ (J)")
    ax.grid(True, color="0.9", linewidth=0.6)
    ax.legend(loc="best", fontsize=9, title="regime" if len(regimes) > 1 else None)


def _draw_two(fig: Figure, axes: Any, x: np.ndarray, y: np.ndarray, e_d: np.ndarray,
              codes: np.ndarray, regimes: list[str], keys: list[str]) -> None:  # fmt: skip
    cx, ix, grid_x = _cells(x)
    cy, iy, grid_y = _cells(y)
    cell = ix * len(cy) + iy
    n = len(cx) * len(cy)
    count = np.bincount(cell, minlength=n)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = (np.bincount(cell, weights=e_d, minlength=n) / count).reshape(len(cx), len(cy))
    ax = axes[0]
    shading = "nearest" if len(cx) > 1 and len(cy) > 1 else "auto"
    mesh = ax.pcolormesh(cx, cy, mean.T, shading=shading, cmap="viridis", rasterized=True)
    fig.colorbar(mesh, ax=ax, label="mean $E_d$ (J)" if count.max() > 1 else "$E_d$ (J)")
    if len(cx) > 2 and len(cy) > 2 and np.isfinite(mean).all():
        lines = ax.contour(cx, cy, mean.T, levels=8, colors="white", linewidths=0.6, alpha=0.8)
        ax.clabel(lines, fontsize=7, fmt="%.3g")
    ax.set_xlabel(keys[0])
    ax.set_ylabel(keys[1])
    ax.set_title("dissipated energy" + ("" if grid_x and grid_y else " (binned samples)"),
                 fontsize=10)  # fmt: skip
    if len(axes) > 1:
        mode = _mode(cell, codes, n, len(regimes)).astype(float)
        mode[count == 0] = np.nan
        cmap = ListedColormap([_REGIME_COLOURS[r % len(_REGIME_COLOURS)]
                               for r in range(len(regimes))])  # fmt: skip
        norm = BoundaryNorm(np.arange(len(regimes) + 1) - 0.5, cmap.N)
        reg = axes[1].pcolormesh(cx, cy, mode.reshape(len(cx), len(cy)).T, shading=shading,
                                 cmap=cmap, norm=norm, rasterized=True)  # fmt: skip
        bar = fig.colorbar(reg, ax=axes[1], ticks=np.arange(len(regimes)))
        bar.ax.set_yticklabels(regimes, fontsize=8)
        axes[1].set_xlabel(keys[0])
        axes[1].set_ylabel(keys[1])
        axes[1].set_title("regime (the most common per cell)", fontsize=10)


def plot_orbits(table: Any, path: str | Path | None = None) -> Figure:
    """A bifurcation diagram of a sweep of periodic orbits (an Arrow table with the ``cycle``
    route's columns): over the first varied key, the first coordinate on the section, the
    largest multiplier's modulus (stable below 1) and the energy the strikes take per period.

    >>> import pyarrow as pa
    >>> t = pa.table({"model.parameters.slope": [0.01, 0.02], "period": [1.0, 1.1],
    ...               "converged": [True, True], "stable": [True, False],
    ...               "q.stance": [-0.1, -0.2], "max_multiplier": [0.5, 1.2],
    ...               "energy_impacts": [1.0, 2.0]})
    >>> len(plot_orbits(t).axes)
    3
    """
    key = varied_keys(table.column_names)[0]
    x = np.asarray(table.column(key).to_numpy(), dtype=float)
    first = next((n for n in table.column_names if n.startswith("q.")), "period")
    q = np.asarray(table.column(first).to_numpy(), dtype=float)
    mult = np.asarray(table.column("max_multiplier").to_numpy(), dtype=float)
    energy = np.asarray(table.column("energy_impacts").to_numpy(), dtype=float)
    stable = np.asarray(table.column("stable").to_numpy(zero_copy_only=False), dtype=bool)
    fig = Figure(figsize=(8.0, 9.0), layout="constrained")
    axes = fig.subplots(3, 1, sharex=True)
    top = f"{first[2:]} after the strike (rad)" if first != "period" else "period (s)"
    for ax, y, label in ((axes[0], q, top),
                         (axes[1], mult, "largest |multiplier|"),
                         (axes[2], energy, "energy the strikes take per period (J)")):
        ax.plot(x, y, color="0.6", linewidth=0.8)
        ax.scatter(x[stable], y[stable], s=14, color="#1f4e9c", label="stable")
        ax.scatter(x[~stable], y[~stable], s=14, facecolors="none", edgecolors="#c0392b",
                   label="unstable")  # fmt: skip
        ax.set_ylabel(label)
        ax.grid(True, color="0.9", linewidth=0.6)
    axes[1].axhline(1.0, color="k", linewidth=0.8, linestyle="--")
    axes[0].legend(loc="best", fontsize=9)
    axes[2].set_xlabel(key)
    found = int(np.count_nonzero(np.isfinite(q)))
    fig.suptitle(f"Periodic orbits over {key} ({found} of {len(x)} found)", fontsize=12)
    return save_figure(fig, path)
