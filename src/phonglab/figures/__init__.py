r"""The charts behind the notebooks, one module per notebook (one call per notebook cell).

Every chart function returns a :class:`matplotlib.figure.Figure` built without pyplot (no
global state: safe in scripts, tests and notebooks; ``fig.savefig(path)`` or :func:`save`
writes it).  Data functions return plain numpy arrays or small dataclasses so that a notebook
can print the numbers it plots.  The physics lives in :mod:`phonglab.physics` and the
plugins, BSDF probing in :mod:`phonglab.probe`; these modules only arrange and plot it.

* :mod:`.common`      :func:`figure`, :func:`save`, :func:`load_bsdf`;
* :mod:`.radiometry`  notebook 01: :func:`fig_solid_angle`, :func:`fig_flux`,
  :func:`fig_radiance_constancy`, :func:`emitter_distance_series` +
  :func:`fig_emitter_distances`, :func:`fig_reflection_equation`;
* :mod:`.bsdfs`       notebook 02 (Lambert and Phong): :func:`fig_phong_lobes`,
  :func:`render_sphere_row` + :func:`fig_sphere_rows`, :func:`albedo_curves` +
  :func:`fig_albedo`, :func:`render_furnace` + :func:`fig_furnace`;
* :mod:`.refraction`  notebook 03: :func:`fig_snell`, :func:`fig_fresnel`,
  :func:`refraction_agreement` + :func:`fig_refraction_agreement`;
* :mod:`.speed`       notebook 04 (speed against accuracy): :func:`convergence_curves` +
  :func:`fig_convergence`, :func:`efficiency_table`, :func:`fig_plan_depths`;
* :mod:`.fitting`     notebook 05 (fitting Phong to physics; imported as
  ``phonglab.figures.fitting``, not re-exported: it loads :mod:`phonglab.fit` and scipy):
  :func:`~.fitting.fig_lobe_cuts`, :func:`~.fitting.fig_fit_albedo`,
  :func:`~.fitting.fig_image_fit`, :func:`~.fitting.fig_image_history`;
* :mod:`.docs`        :func:`write_doc_images`, the one figure per notebook that
  docs/notebooks.md shows (``python -m phonglab.figures DIR``).

Every public name is re-exported here, so a notebook writes ``figures.fig_flux()``.
"""

from .bsdfs import (METAL, PLASTIC, SEED_EXPONENTS, AlbedoCurves, albedo_curves, fig_albedo,
                    fig_furnace, fig_phong_lobes, fig_sphere_rows, furnace_profile,
                    phong_lobe_curves, render_furnace, render_sphere_row)
from .common import figure, load_bsdf, save
from .docs import write_doc_images
from .radiometry import (EmitterSeries, emitter_distance_series, fig_emitter_distances, fig_flux,
                         fig_radiance_constancy, fig_reflection_equation, fig_solid_angle)
from .refraction import (RefractionAgreement, fig_fresnel, fig_refraction_agreement, fig_snell,
                         refraction_agreement)
from .speed import (ConvergenceCurves, convergence_curves, efficiency_table, fig_convergence,
                    fig_plan_depths)

__all__ = [
    "METAL", "PLASTIC", "SEED_EXPONENTS", "AlbedoCurves", "ConvergenceCurves", "EmitterSeries",
    "RefractionAgreement", "albedo_curves", "convergence_curves", "efficiency_table",
    "emitter_distance_series", "fig_albedo", "fig_convergence", "fig_emitter_distances",
    "fig_flux", "fig_fresnel", "fig_furnace", "fig_phong_lobes", "fig_plan_depths",
    "fig_radiance_constancy", "fig_reflection_equation", "fig_refraction_agreement",
    "fig_snell", "fig_solid_angle", "fig_sphere_rows", "figure", "furnace_profile",
    "load_bsdf", "phong_lobe_curves", "refraction_agreement", "render_furnace",
    "render_sphere_row", "save", "write_doc_images",
]
