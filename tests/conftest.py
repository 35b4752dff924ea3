"""Shared fixtures: Mitsuba variants (phonglab's plugins registered in each), seeds, paths.

The default variant is llvm_ad_rgb.  A machine where it cannot run does not skip
the suite: ``test_registration.py::test_llvm_variant_is_usable`` fails loudly and
the other tests run in the scalar fallback.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

os.environ.setdefault("MPLBACKEND", "Agg")

import mitsuba as mi  # noqa: E402

import phonglab  # noqa: E402
from phonglab import llvm  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
SCENES = REPO / "scenes_xml"

#: Significance level of every statistical test (before a Šidák correction over its cases).
ALPHA = 0.01


def _jit_variant(color: str) -> str:
    return llvm.default_variant(color) if llvm.configure().usable else f"scalar_{color}"


@pytest.fixture
def variant_llvm_rgb():
    return phonglab.register("llvm_ad_rgb" if llvm.configure().usable else "scalar_rgb")


@pytest.fixture
def variant_scalar_rgb():
    return phonglab.register("scalar_rgb")


@pytest.fixture(params=["llvm_ad_rgb", "llvm_ad_mono", "llvm_ad_spectral", "scalar_rgb"])
def any_variant(request):
    """Every variant the plugins promise to work in (llvm_* need a usable libLLVM)."""
    v = request.param
    if v.startswith("llvm") and not llvm.configure().usable:
        pytest.fail(f"{v} needs a usable libLLVM: {llvm.configure().reason}")
    return phonglab.register(v)


def sidak(alpha: float, m: int) -> float:
    """Per-test level that keeps the family-wise error rate at alpha over m independent tests."""
    return 1.0 - (1.0 - alpha) ** (1.0 / m)


@pytest.fixture(scope="session")
def scenes_dir() -> Path:
    return SCENES
