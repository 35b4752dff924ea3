"""CSV logs that resume: every bench row reaches the disk the moment it is finished.

A :class:`CsvLog` appends (and fsyncs) one row at a time and knows the keys of the rows it
already holds, so a sweep asks :meth:`CsvLog.has` before computing a row and an
interrupted bench continues where it stopped.  Values are written as ``repr`` of floats
(round-trip exact) and read back as strings; :func:`number` turns a cell into a float.
"""

from __future__ import annotations

import csv
import math
import os
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import PhonglabError
from ..engine.exr import atomic_path
from .config import LOGS


class CsvLog:
    """A CSV file written row by row (flushed), that knows which keys it already holds."""

    def __init__(self, path: Path, fields: list[str], key: tuple[str, ...]):
        self.path, self.fields, self.key = Path(path), fields, key
        self.rows: list[dict[str, str]] = []
        if self.path.is_file():
            with self.path.open(newline="") as f:
                reader = csv.DictReader(f)
                if reader.fieldnames != fields:
                    raise PhonglabError(f"{self.path} has columns {reader.fieldnames}, expected "
                                        f"{fields}; delete it or run with --fresh")
                self.rows = list(reader)
        self._keys = {self.key_of(r) for r in self.rows}

    def key_of(self, row: dict) -> tuple[str, ...]:
        """The key columns of ``row``, as written."""
        return tuple(fmt_value(row[k]) for k in self.key)

    def has(self, **key) -> bool:
        return tuple(fmt_value(key[k]) for k in self.key) in self._keys

    def add(self, row: dict[str, Any]) -> None:
        row = {k: fmt_value(row.get(k, "")) for k in self.fields}
        new = not self.path.is_file()
        self.path.parent.mkdir(parents=True, exist_ok=True)
        with self.path.open("a", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=self.fields)
            if new:
                writer.writeheader()
            writer.writerow(row)
            f.flush()
            os.fsync(f.fileno())
        self.rows.append(row)
        self._keys.add(self.key_of(row))

    def rewrite(self) -> None:
        """Write :attr:`rows` (changed in place) back over the file (atomically: an interrupted
        rewrite leaves the old file)."""
        with atomic_path(self.path, ".csv") as tmp, open(tmp, "w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=self.fields)
            writer.writeheader()
            writer.writerows(self.rows)


def open_log(out: Path, name: str) -> CsvLog:
    """The log ``name`` of :data:`phonglab.bench.config.LOGS` in the folder ``out``."""
    filename, fields, key = LOGS[name]
    return CsvLog(Path(out) / filename, fields, key)


def fmt_value(value: Any) -> str:
    """A cell's text: floats as their repr (exact round trip), numpy scalars as Python ones."""
    if isinstance(value, float):
        return repr(value) if math.isfinite(value) else str(value)
    if isinstance(value, (np.floating,)):
        return fmt_value(float(value))
    if isinstance(value, (np.integer,)):
        return str(int(value))
    return str(value)


def number(row: dict, key: str) -> float:
    """``row[key]`` as a float; NaN when missing or empty."""
    try:
        return float(row[key])
    except (KeyError, TypeError, ValueError):
        return float("nan")

