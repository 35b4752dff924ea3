r"""The comparator: physics checks of phonglab's plugins and of Mitsuba's built-ins, side by side.

Each ``check_<name>(cfg)`` returns a list of :class:`phonglab.verdict.Row` records (topic = the
check's name): what is compared (``reason``), the measured value, the expected value and where
the expectation comes from (``details["source"]``), the Monte Carlo standard error, the
tolerance and the verdict (pass | fail | KNOWN).  :func:`run_checks` runs several of them;
``phonglab check`` prints the rows as a table (:mod:`phonglab.cli.check`).

The six checks, one module each (docs/checks.md has the table of a real run):

``energy``      white furnace: ρ at the BSDF level (zero variance), in a path-traced furnace
                (MIS: nonzero variance), and L = Le/(1 − ρ) inside a closed emitting enclosure.
``reflection``  the reflection equation L_r(ω_r) = ∫ f_r(ω_i, ω_r) L_i cos θ_i dω_i by
                deterministic quadrature of the plugins' ``eval``
                (:mod:`phonglab.physics.quadrature`), against Monte Carlo from their
                ``sample`` and against a render; Phong albedo = k_d + k_s at normal incidence, ≤ 1.
``scene``       a whole Cornell box rendered with ``lambert`` and with ``diffuse``: per-pixel
                Welch t tests (Holm correction) and the mean difference within its error.
``constancy``   radiance constant along rays (distances 1..1000), irradiance falling as 1/r²,
                radiance kept by a mirror and L/n² kept across a dielectric interface.
``snell``       refraction directions (seed formula, ``mi.refract``, built-in ``dielectric``),
                n₁ sin θ₁ = n₂ sin θ₂, total internal reflection, R + T = 1.
``sanity``      reciprocity, non-negativity and finiteness, weight = eval/pdf, χ² sampling test:
                the rows of :func:`phonglab.validate.validate_bsdf`'s topics on each plugin.

:mod:`.common` holds the row collector :class:`Rows`, :class:`Config` and the rendering
helpers; :mod:`.registry` the registry and :func:`run_checks`.  BSDFs are probed through
:mod:`phonglab.probe`.

Statistics (:mod:`phonglab.stats`): every statistical row has an analytic expectation μ and
an estimate x with standard error s (sample standard deviation / √n, or the per-pixel errors
of independent render passes); it passes when |x − μ| ≤ z s, with z the two-sided normal
quantile at the per-row level 1 − (1 − α)^(1/m): α = ALPHA = 0.01 and a Šidák correction
over the m statistical tests of that check [Šidák 1967] (the Student t quantile for a
standard error from few passes).  Deterministic rows compare against a float32 rounding
budget stated where they are built; the sanity rows carry the validator's tolerances and its
χ² levels, Šidák over the sanity check's cases (:mod:`.sanity`).  Seeds are fixed
(``Config.seed``), so a run is reproducible.
"""

from __future__ import annotations

from ..lazy import lazy_exports

#: Names accepted by ``--only``, in the order the table lists them.
CHECK_NAMES = ("energy", "reflection", "scene", "constancy", "snell", "sanity")

# The public API, re-exported from the submodules on first use (phonglab.lazy says why).
_EXPORTS = {
    "common": ("Config", "Rows", "EPS32", "gray", "phong_dict"),
    "registry": ("CHECKS", "run_checks"),
    "energy": ("check_energy", "SPHERE_BIAS_NOTE"),
    "reflection": ("check_reflection", "EXPONENTS", "INCIDENCE"),
    "scene": ("check_scene",),
    "constancy": ("check_constancy", "DISTANCES"),
    "snell": ("check_snell", "INDICES"),
    "sanity": ("check_sanity",),
}
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
__all__ = ["CHECK_NAMES", *(name for names in _EXPORTS.values() for name in names)]
