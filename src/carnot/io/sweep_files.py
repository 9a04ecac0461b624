"""Sweep result files: Parquet or CSV, one row per impact, written chunk by chunk.

A chunk (:class:`carnot.sweep.Chunk`) becomes one Arrow record batch: float64 columns,
booleans, and the string columns (``contacts.K.regime``, ``warnings``) as dictionary arrays
(int32 codes into a few names, so ten million rows of ``"frictionless"`` cost 40 MB, not
half a gigabyte). In Parquet each chunk is a row group; in CSV the names are written out.

The file is written to ``NAME.partial`` beside the target and renamed when complete: a
failed or interrupted sweep leaves no file that looks finished.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from types import TracebackType
from typing import Any

from carnot.errors import InputError

SUFFIXES = (".parquet", ".csv")


def check_output_path(out: str | Path) -> Path:
    """The output path, checked: a ``.parquet`` or ``.csv`` suffix and an existing folder.

    >>> check_output_path("results.xlsx")
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: --out: must end in .parquet or .csv, got 'results.xlsx'
    """
    path = Path(out)
    if path.suffix.lower() not in SUFFIXES:
        raise InputError("--out", "must end in .parquet or .csv", str(out))
    if not path.parent.is_dir():
        raise InputError("--out", "its folder does not exist", str(out))
    return path


def _pyarrow() -> Any:
    try:
        import pyarrow
    except ImportError:  # pragma: no cover - an extra: carnot[sweep]
        raise InputError("--out", "writing sweeps needs pyarrow (pip install carnot[sweep])",
                         show_value=False) from None  # fmt: skip
    return pyarrow


def arrow_schema(columns: Sequence[Any]) -> Any:
    """The Arrow schema of sweep columns (:class:`carnot.sweep.Column`)."""
    pa = _pyarrow()
    types = {"float": pa.float64(), "bool": pa.bool_(),
             "category": pa.dictionary(pa.int32(), pa.string())}  # fmt: skip
    return pa.schema([(c.name, types[c.kind]) for c in columns])


def chunk_to_table(chunk: Any, schema: Any) -> Any:
    """A chunk as an Arrow table of ``schema`` (numeric columns without a copy)."""
    pa = _pyarrow()
    arrays = []
    for fld in schema:
        values = chunk.columns[fld.name]
        if pa.types.is_dictionary(fld.type):
            arrays.append(pa.DictionaryArray.from_arrays(
                pa.array(values, type=pa.int32()),
                pa.array(list(chunk.categories[fld.name]), type=pa.string())))  # fmt: skip
        else:
            arrays.append(pa.array(values, type=fld.type))
    return pa.Table.from_arrays(arrays, schema=schema)


class SweepWriter:
    """Writes chunks in order to a Parquet or CSV file (use as a context manager)."""

    def __init__(self, path: Path, columns: Sequence[Any]):
        self.path = path
        self.partial = path.with_name(path.name + ".partial")
        self.schema = arrow_schema(columns)
        self.rows = 0
        try:
            if path.suffix.lower() == ".parquet":
                import pyarrow.parquet as pq

                self._writer: Any = pq.ParquetWriter(self.partial, self.schema,
                                                     compression="snappy")  # fmt: skip
            else:
                import pyarrow.csv as pcsv

                self._writer = pcsv.CSVWriter(self.partial, self.schema)
        except OSError as err:
            raise InputError("--out", f"cannot write the file ({err})", str(path)) from None

    def write(self, chunk: Any) -> None:
        self._writer.write_table(chunk_to_table(chunk, self.schema))
        self.rows += chunk.stop - chunk.start

    def __enter__(self) -> SweepWriter:
        return self

    def __exit__(self, kind: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:  # fmt: skip
        self._writer.close()
        if kind is None:
            os.replace(self.partial, self.path)
        else:
            self.partial.unlink(missing_ok=True)


def open_writer(path: str | Path, columns: Sequence[Any]) -> SweepWriter:
    """A :class:`SweepWriter` for ``path`` (checked by :func:`check_output_path`)."""
    return SweepWriter(check_output_path(path), columns)


def read_sweep(path: str | Path, columns: Sequence[str] | None = None) -> Any:
    """A sweep file read back as an Arrow table (``columns``: only these). CSV columns come
    back as Arrow infers them (floats, booleans, strings).

    >>> read_sweep("no/such.parquet")
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: no/such.parquet: cannot read the sweep file (no such file)
    """  # noqa: E501
    _pyarrow()
    p = Path(path)
    if not p.is_file():
        raise InputError(str(path), "cannot read the sweep file (no such file)", show_value=False)
    if p.suffix.lower() == ".csv":
        import pyarrow.csv as pcsv

        opts = pcsv.ConvertOptions(include_columns=list(columns) if columns else None)
        return pcsv.read_csv(p, convert_options=opts)
    import pyarrow.parquet as pq

    return pq.read_table(p, columns=list(columns) if columns else None)
