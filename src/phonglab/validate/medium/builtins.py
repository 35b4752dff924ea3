r"""Mitsuba 3.9.1's built-in media as validation cases, and the findings that explain their
failing rows (matched by signature).

Finding ``heterogeneous-volume-outside-bounds`` (src/media/heterogeneous.cpp:200, by
design): ``intersect_aabb`` is the σ_t volume's box, where ``sample_interaction`` stops, but a
constvolume (heterogeneous's default σ_t) has its value everywhere and a gridvolume, under its
default ``clamp`` wrap (src/volumes/grid.cpp:175), its edge voxels' outside the box: the
medium reports σ_t > 0 where the integrators never sample it, i.e. it is cut at the box
(reproducer tests/repro/heterogeneous_volume_outside_bounds.py).

Finding ``heterogeneous-microflake-majorant`` (src/media/heterogeneous.cpp:163): the majorant
is scale·max σ_t, without the microflake projected area σ_t is multiplied by (190-191); with an
SGGX S whose largest eigenvalue exceeds 1 (sggx.cpp asks only for a positive definite S), σ_t
exceeds it and σ_n < 0 (reproducer tests/repro/heterogeneous_microflake_majorant.py).

Finding ``homogeneous-microflake-majorant-at-origin`` (src/media/homogeneous.cpp:164): the
majorant is σ_t times the projected area of the phase function at mi.p, and
``sample_interaction`` queries it before p is set (src/render/medium.cpp:47-62), so with an
SGGX S that varies in space the distances are drawn with σ_t at the origin while the
coefficients, with σ_n = 0 and the medium flagged homogeneous, are σ_t at the collision
(reproducer tests/repro/homogeneous_microflake_majorant_at_origin.py): three topics fail by it.

The SGGX cases' phase function fails its own findings of the phase kind
(``sggx-sample-frame-transposed``, ``sggx-eval-forward-nan``,
:mod:`phonglab.validate.phase.builtins`): reused here as they are, re-addressed to the ``phase``
topic's rows (:func:`through_medium`).

:data:`CATALOGUE` is the medium conformance table: :func:`catalogue_cases`, :data:`FINDINGS`,
:data:`LEFT_OUT`.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..conformance import Catalogue, Finding, KindCase, ValidatorIssue, with_known
from ..phase.builtins import FINDINGS as PHASE_FINDINGS

HOM_SGGX_VARYING = "homogeneous (sggx, S varying along x)"
HET_SGGX_LARGE = "heterogeneous (blob grid, sggx S = diag(1, 1, 4))"
SGGX_CASES = ("homogeneous (sggx, constant S)", HOM_SGGX_VARYING,
              "heterogeneous (blob grid, sggx, constant S)", HET_SGGX_LARGE)

_ORIGIN = ("the majorant is eval_sigmat(mi) = σ_t · projected_area(mi) (lines 153-157, 164), "
           "which SGGX evaluates with S at mi.p (src/phase/sggx.cpp:125); sample_interaction "
           "queries it before p is set (src/render/medium.cpp:47-62), so at p = 0, while "
           "get_scattering_coefficients evaluates S at the collision and returns σ_n = 0")


def through_medium(key: str, labels: tuple[str, ...]) -> Finding:
    """The phase kind's finding ``key`` as it shows in a medium's ``phase`` topic: its rows
    named as :mod:`.scattering` names them (``<phase topic>: <row>``)."""
    f = next(f for f in PHASE_FINDINGS if f.key == key)
    return replace(f, topic="phase", labels=labels, rows=tuple(f"{f.topic}: {r}" for r in f.rows))


#: Every Mitsuba 3.9.1 behaviour behind a failing row of the medium table.
FINDINGS: tuple[Finding, ...] = (
    Finding("heterogeneous-volume-outside-bounds", "bounds",
            ("heterogeneous", "heterogeneous (constant grid)"),
            "src/media/heterogeneous.cpp:200",
            "intersect_aabb returns the σ_t volume's bounding box (the unit cube mapped by its "
            "to_world, include/mitsuba/render/volume.h:99-107), where sample_interaction stops "
            "(src/render/medium.cpp:53-60), but the volume has values outside it: a "
            "constvolume everywhere, a gridvolume its edge voxels' under the default wrap mode "
            "clamp (src/volumes/grid.cpp:175); the medium rendered is the volume cut at its box",
            "σ_t = 1 (constvolume) or 2 (the grid's edge voxels) at points outside the unit "
            "cube, on rays intersect_aabb reports as missing it",
            "σ_t = 0 outside the bounds (a grid with zero outer voxels), or bounds that "
            "enclose every point with σ_t > 0",
            "tests/repro/heterogeneous_volume_outside_bounds.py", bug=False,
            rows=("σ_t = 0 outside intersect_aabb's bounds",),
            excerpt="return m_sigmat->bbox().ray_intersect(ray);"),
    Finding("heterogeneous-microflake-majorant", "majorant", (HET_SGGX_LARGE,),
            "src/media/heterogeneous.cpp:163",
            "m_max_density = m_scale · m_sigmat->max() is the majorant (line 181), but "
            "get_scattering_coefficients multiplies σ_t by the microflake projected area "
            "(lines 190-191), sqrt(wiᵀ S wi) for SGGX, above 1 where S has an eigenvalue above "
            "1; σ_n = m_max_density − σ_t (194) is then negative",
            "σ_n / majorant down to −0.74 with S = diag(1, 1, 4) (−1 at wi = ±z: σ_t = 4 "
            "against a majorant of 2 at a constant density 2)",
            "σ_n ≥ 0: a majorant scaled by the largest projected area (sqrt of S's largest "
            "eigenvalue)", "tests/repro/heterogeneous_microflake_majorant.py",
            rows=("σ_n ≥ 0",), excerpt="m_max_density = dr::opaque<Float>(m_scale * m_sigmat->max());"),
    Finding("heterogeneous-microflake-majorant-transmittance", "transmittance",
            (HET_SGGX_LARGE,), "src/media/heterogeneous.cpp:163",
            "the majorant leaves out the microflake projected area (see "
            "heterogeneous-microflake-majorant): where σ_t exceeds it, σ_n < 0, the null "
            "probability mean(σ_n/σ̄) (src/integrators/volpath.cpp:238) is below 0 and every "
            "collision is real, drawn at the majorant's rate, fewer than σ_t's",
            "delta tracking transmittance 0.296 ± 0.020 against exp(−∫σ_t) = 0.223 at default "
            "sizes (3 of 24 rays off)", "the tracking estimates within their standard error of "
            "exp(−∫σ_t)", "tests/repro/heterogeneous_microflake_majorant.py",
            rows=("delta tracking (volpath's free flight) = exp(−∫σ_t)",
                  "ratio tracking (volpath's shadow rays) = exp(−∫σ_t)"),
            excerpt="m_max_density = dr::opaque<Float>(m_scale * m_sigmat->max());"),
    Finding("homogeneous-microflake-majorant-at-origin", "majorant", (HOM_SGGX_VARYING,),
            "src/media/homogeneous.cpp:164", _ORIGIN,
            "σ_t + σ_n off the majorant by up to 68 % of it (σ_t 0.63 against the origin's "
            "2.0 at x = 1)", "σ_t + σ_n = the majorant of the ray at every point",
            "tests/repro/homogeneous_microflake_majorant_at_origin.py",
            rows=("σ_t + σ_n = majorant",), excerpt="return eval_sigmat(mi, active) & active;"),
    Finding("homogeneous-microflake-majorant-at-origin-transmittance", "transmittance",
            (HOM_SGGX_VARYING,), "src/media/homogeneous.cpp:164",
            _ORIGIN + "; every collision is real, at the origin's rate",
            "volpath's delta and ratio tracking give exp(−σ̄(origin) t), not exp(−∫σ_t)",
            "the tracking estimates within their standard error of exp(−∫σ_t)",
            "tests/repro/homogeneous_microflake_majorant_at_origin.py",
            rows=("delta tracking (volpath's free flight) = exp(−∫σ_t)",
                  "ratio tracking (volpath's shadow rays) = exp(−∫σ_t)"),
            excerpt="return eval_sigmat(mi, active) & active;"),
    Finding("homogeneous-microflake-majorant-at-origin-flags", "flags", (HOM_SGGX_VARYING,),
            "src/media/homogeneous.cpp:138",
            "m_is_homogeneous = true whatever the phase function, while σ_t = σ_t · "
            "projected_area(S(p)) varies with p for a spatially varying SGGX S (" + _ORIGIN
            + ")", "σ_t off the ray's majorant by up to 2.2 times the majorant",
            "is_homogeneous only where σ_t is the ray's majorant",
            "tests/repro/homogeneous_microflake_majorant_at_origin.py",
            rows=("is_homogeneous only where σ_n = 0 and σ_t = majorant",),
            excerpt="m_is_homogeneous = true;"),
    through_medium("sggx-sample-frame-transposed", SGGX_CASES),
    through_medium("sggx-eval-forward-nan", SGGX_CASES),
)


def grid(values) -> dict:
    """A gridvolume holding ``values`` (z, y, x[, channels]) over [0, 1]³."""
    import mitsuba as mi

    a = np.asarray(values, np.float32)
    if a.ndim == 3:
        a = a[..., None]
    return {"type": "gridvolume", "grid": mi.VolumeGrid(a)}


#: The SGGX matrix of the phase kind's sggx case (Sxx, Syy, Szz, Sxy, Sxz, Syz).
SGGX_S = (0.15, 1.0, 0.8, 0.0, 0.0, 0.0)


def sggx(s) -> dict:
    """An sggx phase function with S a constant tuple of six or a (z, y, x, 6) grid."""
    import mitsuba as mi

    a = np.asarray(s, np.float32)
    data = mi.TensorXf(a, (1, 1, 1, 6)) if a.ndim == 1 else mi.TensorXf(a)
    return {"type": "sggx", "S": {"type": "gridvolume", "data": data}}


def varying_s() -> np.ndarray:
    """A 1 × 1 × 4 SGGX grid over [0, 1]³: flakes facing z at x = 0 turning to flakes facing
    x at x = 1."""
    f = np.linspace(0.0, 1.0, 4)
    s = np.zeros((1, 1, 4, 6), np.float32)
    s[0, 0, :, 0], s[0, 0, :, 1], s[0, 0, :, 2] = 0.1 + 0.9 * f, 0.1, 1.0 - 0.9 * f
    return s


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
        KindCase("homogeneous (sggx, constant S)",
                 {"type": "homogeneous", "sigma_t": 2.0, "phase": sggx(SGGX_S)}, None, {},
                 "a microflake medium: σ_t = 2 · projected area, by direction"),
        KindCase(HOM_SGGX_VARYING,
                 {"type": "homogeneous", "sigma_t": 2.0, "phase": sggx(varying_s())}, None, {},
                 "SGGX S from flakes facing z at x = 0 to flakes facing x at x = 1"),
        KindCase("heterogeneous", {"type": "heterogeneous"}, None, {},
                 "its defaults: constvolume σ_t = 1 over the unit cube, albedo 0.75"),
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
        KindCase("heterogeneous (blob grid, sggx, constant S)",
                 {"type": "heterogeneous", "sigma_t": grid(blob()), "phase": sggx(SGGX_S)},
                 None, {}, "a microflake medium, S's eigenvalues ≤ 1"),
        KindCase(HET_SGGX_LARGE,
                 {"type": "heterogeneous", "sigma_t": grid(blob()),
                  "phase": sggx((1.0, 1.0, 4.0, 0.0, 0.0, 0.0))}, None, {},
                 "a positive definite S with an eigenvalue above 1 (projected area up to 2)"),
    ]
    return with_known(out, FINDINGS)


#: Mitsuba 3.9.1 medium plugins (src/media/*.cpp) not validated by the table, and why.
LEFT_OUT: dict[str, str] = {}

#: Rows of the medium table that fail because of the validator while its fix is open (the
#: fixed ones are told in docs/validator-fixes.md).
VALIDATOR_ISSUES: tuple[ValidatorIssue, ...] = ()

CATALOGUE = Catalogue(
    catalogue_cases, "phonglab.validate.medium.builtins.catalogue_cases()", FINDINGS,
    "phonglab.validate.medium.builtins.FINDINGS", VALIDATOR_ISSUES, LEFT_OUT,
    tests="tests/test_conformance_kinds.py", case_text="one medium at one setting")
