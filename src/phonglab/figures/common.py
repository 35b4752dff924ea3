"""What every figure module shares: a figure without pyplot, PNG output, a BSDF to probe.

Figures are :class:`matplotlib.figure.Figure` objects built without pyplot: no global state,
so they are safe in scripts, tests and notebooks (a notebook displays the returned figure;
``fig.savefig(path)`` or :func:`save` writes it).
"""

from __future__ import annotations

from pathlib import Path

import mitsuba as mi
from matplotlib.figure import Figure

from .. import registration
from ..settings import load_plugin


def figure(width: float, height: float, **kw) -> Figure:
    """A figure of ``width`` x ``height`` inches with constrained layout."""
    return Figure(figsize=(width, height), layout="constrained", **kw)


def save(fig: Figure, path: str | Path, dpi: int = 80) -> Path:
    """Write a figure as PNG (folders created)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi)
    return path


def load_bsdf(kind: str, **params):
    """A BSDF plugin instance, ``load_bsdf("phong", exponent=10)`` (registers phonglab first;
    loaded by :func:`phonglab.settings.load_plugin`, the one loader, so a bad name or value is
    one sentence)."""
    registration.register()
    return load_plugin(kind, params, kind=mi.BSDF, word="BSDF").plugin
