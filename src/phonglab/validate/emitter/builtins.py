r"""Mitsuba 3.9.1's built-in emitters as validation cases, and the findings that explain
their failing rows (matched by signature, :mod:`.signatures`).

Finding ``sphere_emitter_inside`` (src/shapes/sphere.cpp at 478e193a, ``sample_direction``
lines 256-259 and ``pdf_direction`` lines 330-336): sample_direction treats a reference point
as outside when |p − c|² > (r(1 ∓ RayEpsilon))² (− without, + with flip_normals) and then
samples the cone of directions to the sphere (pdf 1/(2π(1 − cos θ_max))), else it samples by
area (pdf = dist²/(A |cos θ'|)); pdf_direction treats it as outside when r/|p − c| <
1 − 2⁻²⁴.  The two thresholds differ by ~RayEpsilon = 8.9e-5 relative, and points on the
sphere as a float32 ray intersection computes them fall between them: there ds.pdf ≠
pdf_direction(ds) (with flip_normals, as in a camera inside an emitting sphere, area pdf
against the cone's ≈ 1/2π; without, the cone's against the area pdf of a sample at
distance ≈ 0), and the MIS weights of next-event estimation and BSDF sampling do not sum to
one: +0.25 % of Le per bounce in ``phonglab check``'s enclosure (docs/checks.md).
Reproducer: tests/repro/sphere_emitter_inside.py.
"""

from __future__ import annotations

from ..core import Known
from .signatures import SphereSurfaceBand

SPHERE_INSIDE = Known(
    "Mitsuba 3.9.1 sphere.cpp decides 'inside' differently in sample_direction "
    "(|p − c| vs r(1 ∓ RayEpsilon), lines 256-259) and pdf_direction (r/|p − c| vs 1 − 2^-24, "
    "lines 330-336): at points on the sphere ds.pdf ≠ pdf_direction (finding "
    "sphere_emitter_inside; tests/repro/sphere_emitter_inside.py)",
    rows=("ds.pdf = pdf_direction(ds)", "direction sampling matches pdf_direction (min p-value)"),
    region=SphereSurfaceBand(), key="sphere_emitter_inside")

#: A 4 x 8 RGB environment (a sky-like gradient with one bright texel), written by
#: :func:`envmap_file` for the envmap case.
ENVMAP_SIZE = (4, 8)


def envmap_file(path) -> str:
    """Write a small EXR environment map to ``path`` (numpy, fixed values); its path."""
    import mitsuba as mi
    import numpy as np

    h, w = ENVMAP_SIZE
    y = (np.arange(h) + 0.5) / h
    img = np.zeros((h, w, 3), np.float32)
    img[...] = (0.2 + 0.8 * (1.0 - y))[:, None, None] * np.array([0.6, 0.8, 1.0], np.float32)
    img[1, 5] = [8.0, 7.0, 5.0]
    mi.Bitmap(img).write(str(path))
    return str(path)


def cases(envmap_path=None) -> dict[str, tuple[dict, dict | None, dict]]:
    """label -> (emitter spec, shape spec or None, known) for Mitsuba's built-in emitters."""
    known_sphere = {"pdf": [SPHERE_INSIDE], "chi2": [SPHERE_INSIDE]}
    out = {
        "point": ({"type": "point", "position": [0.2, -0.1, 0.5], "intensity": 3.0}, None, {}),
        "spot": ({"type": "spot", "cutoff_angle": 25.0, "beam_width": 15.0, "intensity": 2.0,
                  "to_world": _look_at()}, None, {}),
        "directional": ({"type": "directional", "direction": [0.3, -0.2, -1.0],
                         "irradiance": 2.0}, None, {}),
        "area (rectangle)": ({"type": "area", "radiance": 2.0}, {"type": "rectangle"}, {}),
        "area (disk)": ({"type": "area", "radiance": 2.0}, {"type": "disk"}, {}),
        "area (cube)": ({"type": "area", "radiance": 2.0}, {"type": "cube"}, {}),
        "area (cylinder)": ({"type": "area", "radiance": 2.0}, {"type": "cylinder"}, {}),
        "area (sphere)": ({"type": "area", "radiance": 2.0}, {"type": "sphere"}, known_sphere),
        "area (sphere, flip_normals)": ({"type": "area", "radiance": 2.0},
                                        {"type": "sphere", "flip_normals": True}, known_sphere),
        "constant": ({"type": "constant", "radiance": 1.5}, None, {}),
    }
    if envmap_path is not None:
        out["envmap"] = ({"type": "envmap", "filename": str(envmap_path)}, None, {})
    return out


def _look_at():
    import mitsuba as mi

    return mi.ScalarTransform4f().look_at(origin=[0.0, 0.0, 1.0], target=[0.3, 0.1, 0.0],
                                          up=[0.0, 1.0, 0.0])
