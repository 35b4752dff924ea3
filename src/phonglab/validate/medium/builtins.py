r"""Mitsuba 3.9.1's built-in media as validation cases, and the findings that explain their
failing rows (matched by signature).

:data:`CATALOGUE` is the medium conformance table: :func:`catalogue_cases`, :data:`FINDINGS`,
:data:`LEFT_OUT`.
"""

from __future__ import annotations

import numpy as np

from ..conformance import Catalogue, Finding, KindCase, ValidatorIssue, with_known
from .topics import TOPICS

#: Every Mitsuba 3.9.1 behaviour behind a failing row of the medium table.
FINDINGS: tuple[Finding, ...] = ()


def grid(values) -> dict:
    """A gridvolume holding ``values`` (z, y, x[, channels]) over [0, 1]³."""
    import mitsuba as mi

    a = np.asarray(values, np.float32)
    if a.ndim == 3:
        a = a[..., None]
    return {"type": "gridvolume", "grid": mi.VolumeGrid(a)}


def blob(res: int = 16, peak: float = 4.0) -> np.ndarray:
    """A smooth bump, 0 on the grid's outer voxels (so 0 outside its bounds under clamp)."""
    x = (np.arange(res) + 0.5) / res
    z, y, xx = np.meshgrid(x, x, x, indexing="ij")
    r2 = (xx - 0.5) ** 2 + (y - 0.45) ** 2 + (z - 0.55) ** 2
    v = peak * np.exp(-r2 / (2 * 0.15 ** 2))
    v[[0, -1], :, :] = v[:, [0, -1], :] = v[:, :, [0, -1]] = 0.0
    return v


def catalogue_cases() -> list[KindCase]:
    """Every case of the medium table, in table order (sets phonglab's default variant when
    none is active: the grid volumes need one)."""
    from ... import registration
    registration.register()

    out = [
        KindCase("homogeneous", {"type": "homogeneous"}, None, {},
                 "its defaults: σ_t = 1, albedo 0.75, isotropic phase"),
        KindCase("homogeneous (σ_t = 5, rgb albedo, hg 0.7)",
                 {"type": "homogeneous", "sigma_t": 5.0,
                  "albedo": {"type": "rgb", "value": [0.99, 0.9, 0.96]},
                  "phase": {"type": "hg", "g": 0.7}}, None, {},
                 "the plugin reference's example (src/media/homogeneous.cpp:82-102)"),
        KindCase("homogeneous (rgb σ_t)",
                 {"type": "homogeneous", "scale": 2.0,
                  "sigma_t": {"type": "rgb", "value": [0.2, 0.5, 0.9]}}, None, {},
                 "spectrally varying extinction"),
        KindCase("heterogeneous (constant grid)",
                 {"type": "heterogeneous", "sigma_t": grid(np.full((4, 4, 4), 2.0))}, None,
                 {}, "a 4³ grid of 2 over [0, 1]³: majorant = σ_t, σ_n = 0"),
        KindCase("heterogeneous (blob grid)",
                 {"type": "heterogeneous", "sigma_t": grid(blob()),
                  "albedo": 0.9, "phase": {"type": "hg", "g": 0.5}}, None, {},
                 "a 16³ smooth bump, peak 4, zero outer voxels"),
        KindCase("heterogeneous (rgb blob grid)",
                 {"type": "heterogeneous",
                  "sigma_t": grid(np.stack([blob(), 0.5 * blob(), 0.25 * blob()], -1))},
                 None, {}, "three channels of σ_t: spectral extinction"),
    ]
    return with_known(out, FINDINGS)


#: Mitsuba 3.9.1 medium plugins (src/media/*.cpp) not validated by the table, and why.
LEFT_OUT: dict[str, str] = {}

#: Rows of medium conformance runs that failed because of the validator.
VALIDATOR_ISSUES: tuple[ValidatorIssue, ...] = ()

CATALOGUE = Catalogue(
    "medium", "participating media", "medium", catalogue_cases, TOPICS, "validate_medium",
    "phonglab.validate.medium.builtins.catalogue_cases()", FINDINGS, VALIDATOR_ISSUES,
    LEFT_OUT, "docs/conformance-media.json", "docs/conformance-media.md", "make conformance",
    case_text="one medium at one setting")
