"""Fixtures only: Mitsuba variants (phonglab's plugins registered in each) and paths.

The default variant is llvm_ad_rgb.  A machine where it cannot run does not skip
the suite: ``test_registration.py::test_llvm_variant_is_usable`` fails loudly and
the other tests run in the scalar fallback.  The significance level and the Šidák
correction the statistical tests use come from :mod:`phonglab.stats` (``ALPHA``, ``sidak``),
the same as the checks and the bench.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

os.environ.setdefault("MPLBACKEND", "Agg")

import phonglab  # noqa: E402
from phonglab import runtime  # noqa: E402
from phonglab.engine.scenes import SCENES_DIR  # noqa: E402


@pytest.fixture
def variant_llvm_rgb():
    return phonglab.register("llvm_ad_rgb" if runtime.configure().usable else "scalar_rgb")


@pytest.fixture
def variant_scalar_rgb():
    return phonglab.register("scalar_rgb")


@pytest.fixture(params=["llvm_ad_rgb", "llvm_ad_mono", "llvm_ad_spectral", "scalar_rgb"])
def any_variant(request):
    """Every variant the plugins promise to work in (llvm_* need a usable libLLVM)."""
    v = request.param
    if v.startswith("llvm") and not runtime.configure().usable:
        pytest.fail(f"{v} needs a usable libLLVM: {runtime.configure().reason}")
    return phonglab.register(v)


@pytest.fixture(scope="session")
def scenes_dir() -> Path:
    return SCENES_DIR
