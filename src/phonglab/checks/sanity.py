r"""Check 6, ``sanity``: reciprocity, non-negativity/finiteness, weight = eval/pdf and χ², per plugin.

The rows come from the validator (:func:`phonglab.validate.validate_bsdf`, the project's one
BSDF test harness), run on each case -- ``lambert`` and ``diffuse`` (ρ = 0.7), ``phong``
(k_d = 0.4, k_s = 0.5) at p = 0, 30, 300; ``Config.lambert``/``Config.phong`` name the plugins
-- on its topics ``finite``, ``weight``, ``reciprocity`` and ``chi2`` with its quick grid
(incidence cells cos θ_i ∈ {1, 0.6, 0.2, 1e-4, 0} × φ_i ∈ {0, 2.1}; χ² at
cos θ_i ∈ {0.8, 0.5, 0.2}, φ_i = 0, 61 × 122 bins) and the check's χ² sample count
``Config.chi2_samples``.  Each case gives four rows:

* ``reciprocity`` (topic ``reciprocity``): f(ω_i, ω_o) = f(ω_o, ω_i) over random and grid pairs
  on the upper hemisphere; measured = the worst lane's relative difference over its tolerance
  2⁻¹⁰ + the lane's sensitivity to an 8-ulp move of both directions
  (:mod:`phonglab.validate.roundoff`), passes at ≤ 1.
* ``non-negative, finite`` (topic ``finite``): the number of lanes with a negative or
  non-finite eval, pdf, eval_pdf or sample result over random, mirror, grazing and
  below-horizon directions (the sum of the topic's four rows), must be 0.
* ``weight = eval/pdf`` (topic ``weight``): every non-delta sample's weight against eval/pdf at
  its direction, measured as for reciprocity (≤ 1).
* ``χ² sampling`` (topic ``chi2``): the minimum p-value of Pearson's χ² of sample() against
  pdf() over the three incidences, which must all pass at the level below; an empty histogram
  with a non-zero pdf fails.  ``histogram_min_sum`` is the smallest histogram's sample count.

No tolerance is this check's own: each row's is the validator's sensitivity model.

Family-wise α.  The validator tests each χ² cell of one BSDF at the Šidák level of its m
cells, so a correct BSDF fails by chance with probability α = :data:`phonglab.stats.ALPHA`.
This check judges its five cases as one family: it passes ``family=5``, so every cell is at
the Šidák level of 5 × 3 = 15 tests, 1 − (1 − α)^(1/15) ≈ 6.7e-4, and correct plugins fail
the sanity check by chance with probability α (the cases draw independent numbers:
case k runs the validator with seed 5·``Config.seed`` + k).  The other rows are
deterministic identities, not tests at a level.
"""

from __future__ import annotations

from ..validate import validate_bsdf
from ..verdict import Report, Row
from .common import Config, gray, phong_dict

#: The validator's topics the rows come from.
TOPICS = ("finite", "weight", "reciprocity", "chi2")


def check_sanity(cfg: Config) -> list[Row]:
    """Reciprocity, non-negativity/finiteness, weight = eval/pdf and χ² for every case."""
    cases = _sanity_cases(cfg)
    rows: list[Row] = []
    for k, (label, spec) in enumerate(cases):
        cfg.note(f"sanity: {label}")
        report = validate_bsdf(spec, topics=TOPICS, seed=cfg.seed * len(cases) + k, quick=True,
                               family=len(cases), sizes={"chi2_samples": cfg.chi2_samples})
        rows += _case_rows(label, report, cfg.chi2_samples)
    return rows


def _sanity_cases(cfg: Config) -> list[tuple[str, dict]]:
    """(label, plugin dict)."""
    cases = [(f"{cfg.lambert}", gray(cfg.lambert, reflectance=0.7)),
             ("diffuse", gray("diffuse", reflectance=0.7))]
    for p in (0.0, 30.0, 300.0):
        cases.append((f"{cfg.phong} p={p:g}", phong_dict(cfg.phong, 0.4, 0.5, p)))
    return cases


def _case_rows(label: str, report: Report, samples: int) -> list[Row]:
    """The four rows of one case from its validation report."""
    by = {t: [r for r in report.rows if r.topic == t] for t in TOPICS}
    m = report.meta["statistical_tests"]
    rec, fin, wgt, chi = by["reciprocity"], by["finite"], by["weight"], by["chi2"]
    cells = [c for r in chi for c in r.details.get("cells", [])]
    # A tested cell's hist_sum is the fraction of samples histogrammed; an empty one's is 0.
    hist_min = min((c["hist_sum"] * samples for c in cells), default=0.0)
    level = chi[0].expected if chi else None
    return [
        _row(label, "reciprocity", rec, _worst(rec), 0.0, 1.0,
             "max relative |f(ωi,ωo) − f(ωo,ωi)| over its float32 tolerance (validate "
             "topic reciprocity, random and grid pairs)",
             "Helmholtz reciprocity; tolerance 2^-10 + each pair's sensitivity"),
        _row(label, "non-negative, finite", fin, _total(fin), 0.0, 0.0,
             "negative or non-finite eval/pdf/eval_pdf/sample lanes (validate topic finite: "
             "random, mirror, grazing and below-horizon directions)", "f_r >= 0, pdf >= 0"),
        _row(label, "weight = eval/pdf", wgt, _worst(wgt), 0.0, 1.0,
             "max relative |weight − eval/pdf| at sampled directions over its float32 "
             "tolerance (validate topic weight)",
             "sample() must agree with eval() and pdf(); tolerance 2^-10 + each lane's "
             "sensitivity"),
        _row(label, "χ² sampling", chi, chi[0].measured if chi else None, level, 0.0,
             "min χ² p-value of sample() vs pdf() (validate topic chi2, θ_i "
             + "/".join(f"{c['theta_deg']:.1f}" for c in cells) + "°)",
             f"Pearson χ²; Šidák level over {m} tests", relation=">=",
             histogram_min_sum=hist_min),
    ]


def _row(label, what, vrows: list[Row], measured, expected, tolerance, compared, source,
         relation="==", **details) -> Row:
    """A check row standing for the validator rows ``vrows`` (kept in ``details["validate"]``)."""
    statuses = {r.status for r in vrows}
    status = ("fail" if "fail" in statuses or not vrows else
              "KNOWN" if "KNOWN" in statuses else
              "skipped" if statuses == {"skipped"} else "pass")
    why = next((r.reason for r in vrows if r.status == "fail" and r.measured is None), None)
    return Row("sanity", f"{label}: {what}", measured, expected, 0.0, tolerance, status,
               f"{label}: {compared}" + (f"; nothing measured: {why}" if why else ""),
               {"source": source, "relation": relation, **details,
                "validate": [r.to_dict() for r in vrows]})


def _worst(rows: list[Row]) -> float | None:
    """The largest measured value of ``rows`` (None when none was measured)."""
    values = [r.measured for r in rows if r.measured is not None]
    return max(values) if values else None


def _total(rows: list[Row]) -> float | None:
    """The sum of the rows' counts (None when one of them was not measured)."""
    values = [r.measured for r in rows]
    return float(sum(values)) if values and None not in values else None
