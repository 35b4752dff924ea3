"""Fitting the classic models to physically based BSDFs with Dr.Jit's automatic differentiation.

* :mod:`.objective`   the norm (f cos θ_i cos θ_o over both hemispheres, relative L2), the
  quadrature nodes, the models' box parametrization, loss and AD gradient through the plugin;
* :mod:`.optimize`    folk rules, the start, L-BFGS-B, :class:`~.optimize.FitResult` and its report
  (``phonglab fit``);
* :mod:`.table`       the table of docs/fitting.md (``make fitting-table``);
* :mod:`.render_fit`  the same fit from images, by differentiable rendering (``prb``).

``phonglab fit roughconductor --set alpha=0.2`` is timed for ``make bench`` by
:mod:`phonglab.bench.fit_timing`.

The submodules import Mitsuba; import them after :func:`phonglab.registration.register`.
"""
