r"""Speed against accuracy: the sweeps behind ``phonglab bench`` and BENCHMARKS.md.

What is measured (every row is written to CSV the moment it is finished; a re-run skips
rows already present, so an interrupted bench resumes — :mod:`.csvlog`):

* ``estimators`` — the five reflection-equation estimators of
  :mod:`phonglab.physics.estimators` on two problems (modified Phong k_d = 0.5, k_s = 0.3,
  p = 100, θ_i = 30°, under a constant light and under a 3° disk light at the mirror
  direction): for each N, the RMSE against the exact value over S seeds, the pooled
  per-sample variance, and the steady-state wall time of one N-sample estimate
  (:mod:`.estimator_sweeps`).
* ``stability`` — every estimator × exponent p ∈ {0, 1, 10, 10², 10³, 10⁴, 10⁵} ×
  θ_i ∈ {0°, 30°, 60°, 80°, 89°, 89.9°} × {constant, 1° disk} light, pure specular
  lobe (k_d = 0, k_s = 1), at a fixed budget of N = 2¹⁴ samples per estimate.
  Verdict "breaks down" when NaN/Inf appear, the relative RMSE exceeds
  :data:`BREAKDOWN_REL_RMSE`, or an error of more than :data:`BIAS_FLOOR` is not
  explained by the estimator's own standard error (|z| > z_crit at
  :data:`phonglab.stats.ALPHA`, Šidák over all cells: bias, or a "silent" failure where no
  sample found the light and the reported standard error is 0) — :mod:`.analysis`.
* ``renders`` — the Cornell box (``phonglab/scenes_xml/cornell_phong.xml``, 32 px): RMSE
  against a cached high-sample reference (:mod:`phonglab.engine.references`, the scene's own
  integrator) versus spp and time for ``lambert`` vs ``diffuse`` (every surface of that
  BSDF) and ``phong`` vs ``plastic`` vs ``roughplastic`` boxes (walls ``diffuse``; the
  look match is in :mod:`.cornell`) — :mod:`.render_sweeps`.
* ``variants`` — ``llvm_ad_rgb`` against ``scalar_rgb`` on a 16 px Cornell box
  (``cuda_ad_rgb`` when Dr.Jit finds a CUDA device; skipped with a note otherwise).
* ``ratios`` — render-time ratios lambert/diffuse, phong/plastic, phong/roughplastic on
  the same scene, spp and variant: A/B pairs in alternating order (ABBA), the median
  of the per-pair ratios (drift and other processes cancel within a pair).
* ``jit`` — JIT compile time separately from steady state: the first call's wall time,
  Dr.Jit's own codegen + LLVM backend time of that call (kernel history), and a cold
  compile measured in a subprocess whose kernel cache (``$HOME/.drjit``) is empty
  (:mod:`.cold_compile`).

Each sweep is a list of independent jobs that carry their seeds (:mod:`.jobs`), run
serially or on a Dask cluster by :mod:`phonglab.parallel` (``--workers``, ``--scheduler``;
docs/cluster.md) with the same rows.  Steady state = median of repeats after a warm-up call.  Charts (:mod:`.charts`,
matplotlib, Agg): error against time on log-log axes, one curve per method, the Pareto
front marked; the stability heatmaps.  :func:`write_markdown` (:mod:`.report`) turns the
CSVs into BENCHMARKS.md; :func:`run_bench` (:mod:`.run`) runs it all.  Sizes and
constants: :mod:`.config`.

Whole commands (``phonglab fit``, ``validate``, ``render``; ``make bench``'s fit, validate,
planner and cluster records) are timed as fresh processes by the one driver :mod:`.timing`;
:mod:`.fit_timing` is the ``phonglab fit`` record.
"""

from ..lazy import lazy_exports

#: The public API, by the module of this package that defines it, re-exported on first use
#: (phonglab.lazy says why).
_EXPORTS = {
    "analysis": ("efficiency_ratios", "loglog_slope", "mis_cell_table", "mis_ratios", "pareto_front",
                 "ratio_summary", "stability_verdict", "stability_z_crit"),
    "charts": ("chart_error_time", "chart_mis", "chart_stability"),
    "config": ("BIAS_FLOOR", "BREAKDOWN_REL_RMSE", "Config", "DEFAULT_OUT", "ESTIMATOR_SCENES",
               "NEAR_ZERO_REL_SD", "PARTS", "RATIO_COMPARISONS", "STABILITY_ANGLES",
               "STABILITY_EXPONENTS", "STABILITY_LIGHTS", "STABILITY_N"),
    "cornell": ("BOX_TYPES", "CornellSpec", "cornell_xml", "render_setups"),
    "csvlog": ("CsvLog",),
    "report": ("stability_explanations", "write_markdown"),
    "run": ("machine_info", "run_bench"),
}
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
__all__ = sorted(name for names in _EXPORTS.values() for name in names)
