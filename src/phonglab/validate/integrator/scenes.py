r"""The integrator kind's scenes (``mi.load_dict`` dicts, box reconstruction filter) and their
analytic values.

Every film uses the ``box`` filter of radius ½: each sample lands in its own pixel only, so
pixels are independent and a pixel's value is the mean of the radiance over its footprint.

**Closed furnace enclosure** (:func:`enclosure`; the geometry of
phonglab/scenes_xml/check_furnace_enclosure.xml, which ``phonglab check`` renders): the camera inside
a closed ``cube`` (normals flipped inwards) whose walls are ``diffuse`` of albedo ρ and emit
Le.  Every wall point sees only walls, so L is the same everywhere and the rendering equation
L = Le + ρL is truncated by the path length: with ``max_depth`` D (D vertices, Mitsuba's
convention: D = 1 the emission seen, path.cpp:225 ``depth + 1 < max_depth``)
L_D = Le Σ_{k<D} ρ^k = Le (1 − ρ^D)/(1 − ρ).  A cube, not a sphere: Mitsuba 3.9.1's sphere
emitter biases MIS from inside (:data:`phonglab.checks.energy.SPHERE_BIAS_NOTE`).

**A Lambertian plane under a point light** (:func:`plane`): the plane z = 0 of albedo ρ, a
point light of intensity I at height h above the origin, and a perspective camera at height
H looking straight down (film parallel to the plane, so film coordinates map linearly onto
the plane: a uniform sample of a pixel is a uniform point of its footprint rectangle).
L(x) = ρ/π · E(x), E = I cos θ / r² = I h / r³; the integral of h/r³ over a rectangle
[x₁, x₂] × [y₁, y₂] is the solid angle it subtends from the light,
Ω = Σ ± atan(x y / (h √(x² + y² + h²))) over its corners (+ at (x₂, y₂) and (x₁, y₁)), so a
pixel's exact value is ρ I Ω_pixel / (π A_pixel) and the image mean ρ I Ω / (π A)
(:func:`plane_pixels`).  Nothing else is in the scene, so every depth ≥ 2 gives the same value.

**Dielectric sphere in a white furnace** (:func:`glass`): a smooth ``dielectric`` sphere (η =
1.5) in a constant environment Le.  Radiance is conserved along every path (a refraction
scales radiance by 1/η² going in and η² coming out: the Fresnel weights sum to one), so every
pixel is Le in the limit.  A path that enters at incidence θ and leaves after n internal
vertices carries (1 − F)² Fⁿ⁻¹ (F = F(θ), the same inside: the internal angle is the
refraction angle); with max_depth D the paths longer than D − 1 vertices are missing, a
deficit (1 − F(θ)) F(θ)^{D−2} per camera sample (:func:`glass_deficit`, integrated over the
sphere's disk as seen orthographically, sin θ = b/R; at D = 64 it is ~1e-6 of Le).

**A grazing plane** (:func:`grazing`, ``finite`` only): a camera 1 mm above a large plane
looking at its horizon (fov 0.2°), so half of the samples hit the plane at cos θ < 2·10⁻³,
down to 10⁻⁶: where a careless 1/cos θ or √(cos θ − ε) is not finite.

**Cornell-like box** (:func:`box`, ``agreement`` and ``cost``): no closed form; white, red and
green diffuse walls, an area light in the ceiling, a ``roughplastic`` sphere (glossy + diffuse).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

#: The enclosure's emitted radiance.
LE = 2.0
#: Plane: albedo, light intensity, light height, camera height and field of view (degrees).
PLANE_RHO, PLANE_I, PLANE_H, CAMERA_H, PLANE_FOV = 0.5, 4.0, 1.0, 2.0, 40.0
#: Glass: index of refraction, environment radiance.
GLASS_ETA, GLASS_LE = 1.5, 1.0


def _film(res: int) -> dict:
    return {"type": "hdrfilm", "width": int(res), "height": int(res), "rfilter": {"type": "box"},
            "pixel_format": "rgb"}


def _camera(res, origin, target, up, fov) -> dict:
    import mitsuba as mi   # lazy: this module's math runs without Mitsuba
    return {"type": "perspective", "fov": float(fov),
            "to_world": mi.ScalarTransform4f().look_at(origin=origin, target=target, up=up),
            "sampler": {"type": "independent"}, "film": _film(res)}


def _gray(v) -> dict:
    return {"type": "rgb", "value": float(v)}


def enclosure(res: int, rho: float, le: float = LE) -> dict:
    """The closed emitting cube ([-1, 1]³, walls of albedo ``rho`` emitting ``le``)."""
    return {"type": "scene",
            "sensor": _camera(res, [0.1, 0.2, 0.05], [0.1, 0.2, 1.0], [0, 1, 0], 60.0),
            "enclosure": {"type": "cube", "flip_normals": True,
                          "bsdf": {"type": "diffuse", "reflectance": _gray(rho)},
                          "emitter": {"type": "area", "radiance": _gray(le)}}}


def enclosure_value(rho: float, depth: int, le: float = LE) -> float:
    """L_D = Le (1 − ρ^D)/(1 − ρ) (D Le at ρ = 1)."""
    return le * depth if rho == 1.0 else le * (1.0 - rho ** depth) / (1.0 - rho)


def plane(res: int, rho: float = PLANE_RHO) -> dict:
    """The plane z = 0 (a 4 × 4 rectangle) under the point light, seen from straight above."""
    import mitsuba as mi
    return {"type": "scene",
            "sensor": _camera(res, [0, 0, CAMERA_H], [0, 0, 0], [0, 1, 0], PLANE_FOV),
            "plane": {"type": "rectangle", "to_world": mi.ScalarTransform4f().scale(2.0),
                      "bsdf": {"type": "diffuse", "reflectance": _gray(rho)}},
            "light": {"type": "point", "position": [0.0, 0.0, PLANE_H],
                      "intensity": _gray(PLANE_I)}}


def _solid_angle(x1, x2, y1, y2, h) -> np.ndarray:
    def f(x, y):
        return np.arctan(x * y / (h * np.sqrt(x * x + y * y + h * h)))
    return f(x2, y2) - f(x1, y2) - f(x2, y1) + f(x1, y1)


def plane_pixels(res: int, rho: float = PLANE_RHO) -> np.ndarray:
    """(res, res) exact pixel values ρ I Ω_pixel/(π A_pixel) of :func:`plane` (symmetric in
    both axes and their swap: the light is above the footprint's centre)."""
    w = CAMERA_H * math.tan(math.radians(PLANE_FOV) / 2.0)
    edges = np.linspace(-w, w, res + 1)
    lo, hi = edges[:-1], edges[1:]
    X1, Y1 = np.meshgrid(lo, lo, indexing="xy")
    X2, Y2 = np.meshgrid(hi, hi, indexing="xy")
    omega = _solid_angle(X1, X2, Y1, Y2, PLANE_H)
    area = (hi[0] - lo[0]) ** 2
    return rho * PLANE_I * omega / (math.pi * area)


def plane_value(rho: float = PLANE_RHO) -> float:
    """The image mean ρ I Ω/(π A) of :func:`plane`."""
    w = CAMERA_H * math.tan(math.radians(PLANE_FOV) / 2.0)
    return float(rho * PLANE_I * _solid_angle(-w, w, -w, w, PLANE_H) / (math.pi * 4 * w * w))


def glass(res: int) -> dict:
    """A dielectric unit sphere (η = 1.5) in a constant environment, seen from z = 4."""
    return {"type": "scene",
            "sensor": _camera(res, [0, 0, 4.0], [0, 0, 0], [0, 1, 0], 40.0),
            "sphere": {"type": "sphere", "bsdf": {"type": "dielectric", "int_ior": GLASS_ETA,
                                                  "ext_ior": 1.0}},
            "env": {"type": "constant", "radiance": _gray(GLASS_LE)}}


def fresnel(cos_i: np.ndarray, eta: float = GLASS_ETA) -> np.ndarray:
    """Unpolarized Fresnel reflectance of a smooth interface from outside (relative index η)."""
    cos_i = np.clip(cos_i, 0.0, 1.0)
    sin_t2 = (1.0 - cos_i ** 2) / eta ** 2
    cos_t = np.sqrt(np.maximum(0.0, 1.0 - sin_t2))
    rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    return 0.5 * (rs * rs + rp * rp)


def glass_deficit(depth: int, res: int) -> float:
    """The image-mean radiance (in units of Le) the paths beyond ``depth`` vertices carry:
    the sphere's share of the image times the mean over its disk of (1 − F) F^{D−2}."""
    s = (np.arange(200_000) + 0.5) / 200_000          # b/R = sin θ, weight 2s ds
    f = fresnel(np.sqrt(1.0 - s * s))
    per_sample = np.sum((1.0 - f) * f ** max(depth - 2, 0) * 2.0 * s) / s.size
    share = math.tan(math.asin(1.0 / 4.0)) ** 2 * math.pi / (2 * math.tan(math.radians(20))) ** 2
    return float(per_sample * min(1.0, share))


def grazing(res: int) -> dict:
    """A large lit plane seen at its horizon from 1 mm above it (``finite``)."""
    import mitsuba as mi
    return {"type": "scene",
            "sensor": _camera(res, [0, 0, 1e-3], [1.0, 0, 1e-3], [0, 0, 1], 0.2),
            "plane": {"type": "rectangle", "to_world": mi.ScalarTransform4f().scale(1e3),
                      "bsdf": {"type": "diffuse", "reflectance": _gray(0.5)}},
            "light": {"type": "point", "position": [0.5, 0.0, 1.0], "intensity": _gray(1.0)},
            "env": {"type": "constant", "radiance": _gray(0.5)}}


def box(res: int) -> dict:
    """The Cornell-like box of ``agreement`` and ``cost`` (open at the front, camera at z = 3.5)."""
    import mitsuba as mi
    T = mi.ScalarTransform4f

    def wall(transform, rgb):
        return {"type": "rectangle", "to_world": transform,
                "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": rgb}}}

    white = [0.7, 0.7, 0.7]
    return {"type": "scene",
            "sensor": _camera(res, [0, 0, 3.5], [0, 0, 0], [0, 1, 0], 40.0),
            "floor": wall(T().translate([0, -1, 0]).rotate([1, 0, 0], -90), white),
            "ceiling": wall(T().translate([0, 1, 0]).rotate([1, 0, 0], 90), white),
            "back": wall(T().translate([0, 0, -1]), white),
            "left": wall(T().translate([-1, 0, 0]).rotate([0, 1, 0], 90), [0.6, 0.1, 0.1]),
            "right": wall(T().translate([1, 0, 0]).rotate([0, 1, 0], -90), [0.1, 0.6, 0.1]),
            "light": {"type": "rectangle",
                      "to_world": T().translate([0, 0.99, 0]).rotate([1, 0, 0], 90).scale(0.5),
                      "bsdf": {"type": "diffuse", "reflectance": _gray(0.0)},
                      "emitter": {"type": "area", "radiance": _gray(0.5)}},
            "ball": {"type": "sphere", "center": [-0.3, -0.6, -0.1], "radius": 0.4,
                     "bsdf": {"type": "roughplastic", "alpha": 0.2,
                              "diffuse_reflectance": {"type": "rgb", "value": [0.2, 0.3, 0.6]}}}}


@dataclass(frozen=True)
class Analytic:
    """One analytic scene of ``finite``, ``bias`` and ``convergence``."""

    name: str
    build: Callable[[int], dict]         #: res -> scene dict
    depth: int | None                    #: the max_depth its value holds at (None: any >= 2)
    expected: float                      #: the image mean (per channel, gray scenes)
    source: str                          #: the value's derivation, in one line
    specular: bool = False               #: seen through a delta BSDF (no light tracing)
    floor: float = 0.0                   #: a stated bound on the value's own error


#: The enclosure's (ρ, max_depth) pairs of the bias scenes.
ENCLOSURES = ((0.5, 1), (0.5, 2), (0.5, 3), (0.8, 64))
#: The two albedos the enclosure is judged at for an integrator of one depth of its own.
OWN_RHOS = (0.5, 0.8)


def analytic(res: int, own_depth: int | None = None) -> list[Analytic]:
    """The bias scenes, in table order: the enclosure at depths 1, 2, 3 (ρ = 0.5) and 64
    (ρ = 0.8, where Russian roulette acts) -- and, for an integrator of one depth D of its own
    (``own_depth``: declared, kept or measured), at D at both albedos of :data:`OWN_RHOS`
    where the list lacks it -- the plane under the point light, the glass sphere."""
    pairs = list(ENCLOSURES)
    if own_depth is not None:
        pairs += [(rho, own_depth) for rho in OWN_RHOS if (rho, own_depth) not in pairs]
        pairs.sort(key=lambda p: (p[1], p[0]))
    out = []
    for rho, depth in pairs:
        out.append(Analytic(f"enclosure ρ={rho} D={depth}",
                            lambda r, rho=rho: enclosure(r, rho), depth,
                            enclosure_value(rho, depth),
                            "closed emitting cube: Le (1 − ρ^D)/(1 − ρ)"))
    out.append(Analytic("plane under a point light", plane, None, plane_value(),
                        "ρ I Ω/(π A), Ω the footprint's solid angle from the light"))
    d = 64
    out.append(Analytic(f"glass sphere furnace D={d}", glass, d, GLASS_LE,
                        f"radiance conserved through glass: Le, minus paths beyond {d} vertices",
                        specular=True, floor=GLASS_LE * glass_deficit(d, res)))
    return out
