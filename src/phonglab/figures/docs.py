"""The figures docs/notebooks.md shows: one per notebook, ``docs/img/nb_*.png``.

:func:`write_doc_images` (``make notebook-figures``, ``python -m phonglab.figures DIR``) makes
the same calls, at the same default sample counts, as the notebooks.
"""

from __future__ import annotations

from pathlib import Path

from .. import registration
from ..fit import optimize
from .bsdfs import METAL, PLASTIC, albedo_curves, fig_albedo, fig_sphere_rows, render_sphere_row
from .common import save
from .fitting import fig_lobe_cuts
from .radiometry import emitter_distance_series, fig_emitter_distances, fig_reflection_equation
from .refraction import fig_refraction_agreement, refraction_agreement
from .speed import convergence_curves, fig_convergence


def write_doc_images(folder: str | Path = "docs/img", dpi: int = 72) -> list[Path]:
    """Write the one figure per notebook that docs/notebooks.md shows, as ``folder/nb_*.png``;
    returns their paths."""
    folder = Path(folder)
    registration.register()
    rows = {"plastic: red k_d, grey k_s": render_sphere_row(16, **PLASTIC),
            "metal: k_d ≈ 0, coloured k_s": render_sphere_row(16, **METAL)}
    figs = {
        "nb_01_radiance_constancy.png": fig_emitter_distances(emitter_distance_series(spp=4)),
        "nb_01_reflection_equation.png": fig_reflection_equation(),
        "nb_02_sphere_rows.png": fig_sphere_rows(rows),
        "nb_02_furnace.png": fig_albedo(albedo_curves(samples=20000)),
        "nb_03_refraction.png": fig_refraction_agreement(refraction_agreement()),
        "nb_04_convergence.png": fig_convergence(convergence_curves(seeds=8)),
        "nb_05_lobe_cuts.png": fig_lobe_cuts(optimize.fit("roughconductor", {"alpha": 0.2})),
    }
    return [save(fig, folder / name, dpi=dpi) for name, fig in figs.items()]
