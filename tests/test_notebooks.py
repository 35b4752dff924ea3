"""The notebooks run top to bottom on a fresh kernel without an error.

Each is executed with nbclient in the ``python3`` kernel (``make setup`` installs the venv's
ipykernel under that name with ``--sys-prefix``), with the working directory set to
``notebooks/``, as a reader would open it.  The notebooks are stored without outputs; this
test does not write them back.  Budget (STYLE: notebooks run in the suite at small sample
counts): each under two minutes, and in practice ~10-20 s on two busy cores, most of it kernel
start-up and Mitsuba's first JIT compilation.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import pytest

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")
from jupyter_client.kernelspec import KernelSpecManager  # noqa: E402  (nbclient's dependency)

NOTEBOOKS = Path(__file__).resolve().parents[1] / "notebooks"
#: Every notebook in notebooks/.
OWNED = ["01_radiometry.ipynb", "02_lambert_and_phong.ipynb", "03_refraction.ipynb",
         "04_speed_vs_accuracy.ipynb", "05_fitting.ipynb", "06_plugin_authors.ipynb"]
#: The issue's limit for one notebook at its default sample counts.
LIMIT_S = 120


def _kernel_name() -> str:
    """``python3`` when it is the venv's kernel; otherwise fail with the fix."""
    spec = KernelSpecManager().get_kernel_spec("python3")
    exe = spec.argv[0]
    if exe not in ("python", "python3") and Path(exe).resolve() != Path(sys.executable).resolve():
        pytest.fail(f"the python3 kernel runs {exe}, not this venv's {sys.executable}; "
                    f"run `make setup` (python -m ipykernel install --sys-prefix)")
    return "python3"


#: The two that take ~7 s each run in the slow tier (CI runs it); the default tier stays fast.
SLOW = {"04_speed_vs_accuracy.ipynb", "05_fitting.ipynb"}


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.slow) if n in SLOW else n
                                  for n in OWNED])
def test_notebook_runs(name, monkeypatch):
    path = NOTEBOOKS / name
    book = nbformat.read(path, as_version=4)
    assert all(not c.get("outputs") for c in book.cells if c.cell_type == "code"), \
        f"{name} is stored with outputs; clear them (Kernel > Restart & Clear Output) to keep the repo small"
    # The kernel inherits the environment: plots render to PNG without a display.
    monkeypatch.setenv("MPLBACKEND", "module://matplotlib_inline.backend_inline")
    client = nbclient.NotebookClient(book, kernel_name=_kernel_name(), timeout=LIMIT_S,
                                     resources={"metadata": {"path": str(NOTEBOOKS)}})
    t0 = time.perf_counter()
    client.execute()   # raises CellExecutionError (with the cell and its traceback) on any error
    seconds = time.perf_counter() - t0
    assert seconds < LIMIT_S, f"{name} took {seconds:.0f} s, over the {LIMIT_S} s budget"
    images = sum(1 for c in book.cells if c.cell_type == "code" for o in c.get("outputs", [])
                 if "image/png" in o.get("data", {}))
    assert images >= 3, f"{name} displayed only {images} figures"


def test_notebooks_are_the_ones_documented():
    doc = (NOTEBOOKS.parent / "docs" / "notebooks.md").read_text()
    for name in OWNED:
        assert name in doc, f"docs/notebooks.md does not describe {name}"
