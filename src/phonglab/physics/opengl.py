r"""OpenGL's fixed-function materials and lights, mapped to phonglab and Mitsuba.

OpenGL 2.1 (§2.14.1) lights a vertex of a material (GL_EMISSION e, GL_AMBIENT k_a,
GL_DIFFUSE k_d, GL_SPECULAR k_s, GL_SHININESS p ∈ [0, 128]) with a positional light
(GL_AMBIENT A_i, GL_DIFFUSE D_i, GL_SPECULAR S_i, attenuation a, b, c) and the global
GL_LIGHT_MODEL_AMBIENT A as::

    colour = e + k_a A + Σ_i att_i (k_a A_i + D_i k_d max(0, L·N) + S_i k_s f_i max(0, N·H)^p)
    att_i  = 1 / (a + b r + c r²),   f_i = [L·N > 0]

with the Blinn half vector H; the seed (and ``whitted``) use Phong's (L·R)^p, whose
exponent is about 4 × Blinn's for the same highlight width.  Three mappings:

* :func:`gl_to_whitted`: GL → ``whitted`` in graphics units + ``phong`` + ``point``.
  Exact, term for term with (L·R)^p, when D_i = S_i and the light's ambient A_i is 0 or
  unattenuated.  When k_d + k_s > 1 in a channel (GL allows it, ``phong`` refuses it),
  both are divided by s = max(k_d + k_s) and the light's intensity multiplied by s:
  the lit colour is linear in I_i, so this is still exact.
* :func:`gl_to_physical`: GL → ``phong`` in radiance units (``path``/``whitted``
  radiance).  ρ_d = k_d, ρ_s = 2 k_s / (p + 2) and I = π D / c when a = b = 0 (then the
  diffuse term is exact at every distance); otherwise I = π r0² D att(r0) is matched at
  one reference distance r0.  The specular term then matches only at normal incidence.
* :func:`physical_to_gl`: the inverse: k_d = ρ_d, k_s = ρ_s (p + 2)/2, p = exponent
  (<= 128), D = S = I/π with a = b = 0, c = 1 (GL's inverse-square law).

Where no exact mapping exists (:data:`NO_EXACT_MAPPING`, also in docs/classic_model.md):

============================  ==============================================================
GL term                        physics (radiance units)
============================  ==============================================================
k_s (L·R)^p                    ρ_s (p+2)/(2π) cos^p α · cos θ_i: GL lacks the cos θ_i, so
                               the ratio is cos θ_i (1 at normal incidence, → 0 at grazing)
k_d (L·N) D                    ρ_d/π · I/r² · cos θ_i: the π is a unit (I = π D), exact
(p+2)/(2π), π                  normalisations absent from GL: absorbed into ρ_s and I
1/(a + b r + c r²)             1/r²: exact only for a = b = 0 (I = π D / c); a = 1, b = c = 0
                               (GL's default) matches at one distance r0 only, ratio r0²/r²
k_a A (GL_AMBIENT)             no counterpart: light from every direction, unoccluded; a
                               ``constant`` emitter of radiance A gives ρ_d A on an open
                               Lambertian surface, less where occluded, plus a specular part
e (GL_EMISSION)                an ``area`` emitter of radiance e: the same pixel, but it also
                               lights other surfaces in a path tracer
GL_SHININESS ∈ [0, 128]        phong exponents > 128 have no GL material
S_i ≠ D_i                      one intensity per light in Mitsuba
k_d + k_s > 1                  not energy-conserving; rescaled into the light (exact in
                               graphics units, changes the light in radiance units)
spot: cos^e falloff, cutoff    Mitsuba's spot has a smooth step between beam_width and
                               cutoff_angle: no exact mapping
============================  ==============================================================

References: M. Segal, K. Akeley, *The OpenGL Graphics System: A Specification*, version
2.1, §2.14.1; D. Zorin, *Lighting* (2005), "OpenGL model"; E. Lafortune, Y. Willems,
KU Leuven CW197 (1994) for the (p+2)/(2π) normalisation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import PhonglabError

#: GL_SHININESS must lie in [0, GL_MAX_SHININESS] (OpenGL 2.1, glMaterial).
GL_MAX_SHININESS = 128.0

#: (GL term, physical counterpart, why no exact mapping exists): the table above.
NO_EXACT_MAPPING: list[tuple[str, str, str]] = [
    ("k_s (L·R)^p", "ρ_s (p+2)/(2π) cos^p α cos θ_i",
     "GL has no cos θ_i on the specular term: the ratio physics/GL is cos θ_i"),
    ("1/(a + b r + c r²)", "1/r²",
     "exact only for a = b = 0; GL's default a = 1, b = c = 0 matches at one distance"),
    ("k_a A (GL_AMBIENT)", "none",
     "uniform unoccluded light; a constant emitter gives ρ_d A only on open Lambertian surfaces"),
    ("GL_SHININESS", "exponent", "GL limits p to [0, 128]"),
    ("S_i ≠ D_i", "one intensity", "Mitsuba lights have one intensity"),
    ("k_d + k_s > 1", "ρ_d + ρ_s <= 1", "not energy-conserving; rescaled into the light"),
    ("spot cos^e falloff", "spot smooth step", "different falloff curves"),
]

RGB = tuple[float, float, float]


def _rgb(name: str, value) -> np.ndarray:
    a = np.broadcast_to(np.asarray(value, dtype=np.float64), (3,)).copy()
    if not np.all(np.isfinite(a)) or np.any(a < 0):
        raise PhonglabError(f"{name} must be three finite values >= 0, got {list(value)}; "
                            f"OpenGL colours here are linear RGB, not negative.")
    return a


@dataclass(frozen=True)
class GLMaterial:
    """glMaterial parameters (OpenGL's defaults)."""

    ambient: RGB = (0.2, 0.2, 0.2)     #: GL_AMBIENT k_a
    diffuse: RGB = (0.8, 0.8, 0.8)     #: GL_DIFFUSE k_d
    specular: RGB = (0.0, 0.0, 0.0)    #: GL_SPECULAR k_s
    shininess: float = 0.0             #: GL_SHININESS p in [0, 128]
    emission: RGB = (0.0, 0.0, 0.0)    #: GL_EMISSION e

    def __post_init__(self):
        for name in ("ambient", "diffuse", "specular", "emission"):
            _rgb(f"GL_{name.upper()}", getattr(self, name))
        p = float(self.shininess)
        if not (0.0 <= p <= GL_MAX_SHININESS):
            raise PhonglabError(f"GL_SHININESS must lie in [0, {GL_MAX_SHININESS:g}], got {p:g}; "
                                f"OpenGL rejects larger exponents (use phong directly).")


@dataclass(frozen=True)
class GLLight:
    """A positional glLight (w = 1), OpenGL's defaults for GL_LIGHT0."""

    position: tuple[float, float, float] = (0.0, 0.0, 1.0)
    diffuse: RGB = (1.0, 1.0, 1.0)     #: GL_DIFFUSE D_i
    specular: RGB = (1.0, 1.0, 1.0)    #: GL_SPECULAR S_i
    ambient: RGB = (0.0, 0.0, 0.0)     #: GL_AMBIENT A_i
    constant_attenuation: float = 1.0  #: a
    linear_attenuation: float = 0.0    #: b
    quadratic_attenuation: float = 0.0 #: c

    def __post_init__(self):
        for name in ("diffuse", "specular", "ambient"):
            _rgb(f"light GL_{name.upper()}", getattr(self, name))
        abc = (self.constant_attenuation, self.linear_attenuation, self.quadratic_attenuation)
        if any(not math.isfinite(x) or x < 0 for x in abc) or sum(abc) <= 0:
            raise PhonglabError(f"GL attenuation (a, b, c) must be >= 0 and not all 0, got "
                                f"{abc}; OpenGL's default is (1, 0, 0).")

    def attenuation(self, r) -> np.ndarray:
        """att(r) = 1 / (a + b r + c r²)."""
        r = np.asarray(r, dtype=np.float64)
        return 1.0 / (self.constant_attenuation + self.linear_attenuation * r
                      + self.quadratic_attenuation * r * r)


@dataclass
class Mapping:
    """Mitsuba dictionaries (for ``mi.load_dict``) and what the mapping could not keep."""

    bsdf: dict            #: the ``phong`` BSDF
    light: dict           #: the ``point`` emitter
    integrator: dict      #: the ``whitted`` (graphics) or ``path`` integrator
    shape_emitter: dict | None = None   #: an ``area`` emitter for GL_EMISSION, if any
    notes: list[str] = field(default_factory=list)  #: where the mapping is not exact

    @property
    def exact(self) -> bool:
        return not self.notes


def _rgb_dict(value) -> dict:
    return {"type": "rgb", "value": [float(x) for x in value]}


def _energy_scale(kd: np.ndarray, ks: np.ndarray) -> float:
    """s = max(1, max_channel(k_d + k_s)): dividing both by s makes phong accept them."""
    return float(max(1.0, np.max(kd + ks)))


def gl_to_whitted(material: GLMaterial, light: GLLight, global_ambient=(0.2, 0.2, 0.2),
                  bsdf_id: str = "gl_material", shadows: bool = False) -> Mapping:
    """The ``whitted`` (graphics units) scene pieces that reproduce OpenGL's lighting.

    Args:
        material, light: the GL state.
        global_ambient: GL_LIGHT_MODEL_AMBIENT A (OpenGL's default 0.2).
        bsdf_id: the id the returned BSDF must keep (the integrator's
            ``ambient_reflectance_<id>`` refers to it).
        shadows: False is OpenGL (every light visible); True is the ray-tracing case.

    Returns:
        a :class:`Mapping`; ``notes`` lists what is not exact (S_i ≠ D_i, attenuated
        light ambient, Blinn vs Phong is always left to the docstring).
    """
    kd, ks = _rgb("GL_DIFFUSE", material.diffuse), _rgb("GL_SPECULAR", material.specular)
    s = _energy_scale(kd, ks)
    notes = []
    D, S = _rgb("light GL_DIFFUSE", light.diffuse), _rgb("light GL_SPECULAR", light.specular)
    if not np.allclose(D, S):
        notes.append(f"light GL_SPECULAR {S.tolist()} differs from GL_DIFFUSE {D.tolist()}: "
                     f"whitted has one intensity, GL_DIFFUSE is used")
    A_i = _rgb("light GL_AMBIENT", light.ambient)
    attenuated = (light.constant_attenuation, light.linear_attenuation,
                  light.quadratic_attenuation) != (1.0, 0.0, 0.0)
    if np.any(A_i > 0) and attenuated:
        notes.append("the light's GL_AMBIENT is attenuated in OpenGL; whitted's ambient is not")
    ambient = _rgb("GL_LIGHT_MODEL_AMBIENT", global_ambient) + A_i
    bsdf = {"type": "phong", "id": bsdf_id, "diffuse_reflectance": _rgb_dict(kd / s),
            "specular_reflectance": _rgb_dict(ks / s), "exponent": float(material.shininess)}
    point = {"type": "point", "position": [float(x) for x in light.position],
             "intensity": _rgb_dict(D * s)}
    integrator = {"type": "whitted", "units": "graphics", "max_depth": 2, "shadows": shadows,
                  "ambient": _rgb_dict(ambient),
                  f"ambient_reflectance_{bsdf_id}": _rgb_dict(material.ambient),
                  "attenuation_constant": float(light.constant_attenuation),
                  "attenuation_linear": float(light.linear_attenuation),
                  "attenuation_quadratic": float(light.quadratic_attenuation)}
    e = _rgb("GL_EMISSION", material.emission)
    shape_emitter = {"type": "area", "radiance": _rgb_dict(e)} if np.any(e > 0) else None
    return Mapping(bsdf, point, integrator, shape_emitter, notes)


def gl_to_physical(material: GLMaterial, light: GLLight,
                   reference_distance: float | None = None) -> Mapping:
    """Radiance-unit ``phong`` + ``point`` matching GL's diffuse and peak specular terms.

    ρ_d = k_d, ρ_s = 2 k_s/(p + 2) (the GL highlight peak k_s D att equals ρ_s (p+2)/(2π)
    I/r² at L = R = N), I = π D / c for a = b = 0 (exact at every distance), else
    I = π r0² D att(r0) at ``reference_distance`` r0 (required then).  If ρ_d + ρ_s > 1 in
    a channel both are divided by s and I multiplied by s.  The ambient term is dropped.

    Raises:
        PhonglabError: a or b non-zero and no reference distance.
    """
    kd, ks = _rgb("GL_DIFFUSE", material.diffuse), _rgb("GL_SPECULAR", material.specular)
    p = float(material.shininess)
    rho_d, rho_s = kd, 2.0 * ks / (p + 2.0)
    s = _energy_scale(rho_d, rho_s)
    D = _rgb("light GL_DIFFUSE", light.diffuse)
    notes = ["the specular term gains cos θ_i (GL has none): ratio physics/GL = cos θ_i"]
    if light.constant_attenuation == 0 and light.linear_attenuation == 0:
        intensity = math.pi * D / light.quadratic_attenuation
    else:
        if reference_distance is None or not reference_distance > 0:
            raise PhonglabError(
                "GL attenuation with a or b non-zero has no inverse-square counterpart: give "
                "reference_distance (> 0), the distance at which both should agree.")
        r0 = float(reference_distance)
        intensity = math.pi * r0 * r0 * D * float(light.attenuation(r0))
        notes.append(f"GL attenuation 1/({light.constant_attenuation:g} + "
                     f"{light.linear_attenuation:g} r + {light.quadratic_attenuation:g} r²) "
                     f"vs 1/r²: equal at r = {r0:g} only")
    if s > 1.0:
        notes.append(f"ρ_d + ρ_s = {np.max(rho_d + rho_s):.4g} > 1: reflectances divided and the "
                     f"light multiplied by {s:.4g}")
    if np.any(_rgb("GL_AMBIENT", material.ambient) > 0):
        notes.append("GL_AMBIENT has no radiance-unit counterpart: dropped")
    if not np.allclose(D, _rgb("light GL_SPECULAR", light.specular)):
        notes.append("light GL_SPECULAR differs from GL_DIFFUSE: GL_DIFFUSE is used")
    bsdf = {"type": "phong", "diffuse_reflectance": _rgb_dict(rho_d / s),
            "specular_reflectance": _rgb_dict(rho_s / s), "exponent": p}
    point = {"type": "point", "position": [float(x) for x in light.position],
             "intensity": _rgb_dict(intensity * s)}
    e = _rgb("GL_EMISSION", material.emission)
    shape_emitter = {"type": "area", "radiance": _rgb_dict(e)} if np.any(e > 0) else None
    return Mapping(bsdf, point, {"type": "path", "max_depth": 2}, shape_emitter, notes)


def physical_to_gl(diffuse_reflectance, specular_reflectance, exponent: float, intensity,
                   position=(0.0, 0.0, 1.0)) -> tuple[GLMaterial, GLLight]:
    """The GL material and light closest to a radiance-unit ``phong`` under a ``point`` light.

    k_d = ρ_d, k_s = ρ_s (p+2)/2, GL_SHININESS = p, D = S = I/π, attenuation (0, 0, 1):
    the diffuse term is then exact at every distance, the specular one at normal incidence
    (GL lacks cos θ_i).  GL_AMBIENT = 0 (physics has no ambient term).

    Raises:
        PhonglabError: exponent > 128 (no GL material has it).
    """
    p = float(exponent)
    if not 0.0 <= p <= GL_MAX_SHININESS:
        raise PhonglabError(f"phong exponent {p:g} has no OpenGL counterpart: GL_SHININESS is "
                            f"limited to [0, {GL_MAX_SHININESS:g}].")
    rho_d = _rgb("diffuse_reflectance", diffuse_reflectance)
    rho_s = _rgb("specular_reflectance", specular_reflectance)
    I = _rgb("intensity", intensity)
    material = GLMaterial(ambient=(0.0, 0.0, 0.0), diffuse=tuple(rho_d),
                          specular=tuple(rho_s * (p + 2.0) / 2.0), shininess=p)
    light = GLLight(position=tuple(float(x) for x in position), diffuse=tuple(I / math.pi),
                    specular=tuple(I / math.pi), constant_attenuation=0.0,
                    linear_attenuation=0.0, quadratic_attenuation=1.0)
    return material, light


def gl_colour(material: GLMaterial, light: GLLight, point, normal, eye,
              global_ambient=(0.2, 0.2, 0.2), half_vector: bool = False) -> np.ndarray:
    """OpenGL 2.1's lighting equation at one point (float64, no clamping to [0, 1]).

    ``half_vector=False`` uses the seed's (L·R)^p, ``True`` GL's Blinn (N·H)^p.
    """
    point, normal, eye = (np.asarray(x, np.float64) for x in (point, normal, eye))
    n = normal / np.linalg.norm(normal)
    v = eye - point
    v /= np.linalg.norm(v)
    to_l = np.asarray(light.position, np.float64) - point
    r = np.linalg.norm(to_l)
    l_dir = to_l / r
    att = float(light.attenuation(r))
    ln = float(np.dot(l_dir, n))
    if half_vector:
        h = l_dir + v
        spec = max(float(np.dot(n, h / np.linalg.norm(h))), 0.0)
    else:
        spec = max(float(np.dot(l_dir, 2.0 * np.dot(n, v) * n - v)), 0.0)
    lobe = spec ** material.shininess if ln > 0 and spec > 0 else 0.0
    ka = np.asarray(material.ambient)
    colour = np.asarray(material.emission) + ka * np.asarray(global_ambient)
    colour = colour + att * (ka * np.asarray(light.ambient)
                             + np.asarray(light.diffuse) * np.asarray(material.diffuse) * max(ln, 0.0)
                             + np.asarray(light.specular) * np.asarray(material.specular) * lobe)
    return colour
