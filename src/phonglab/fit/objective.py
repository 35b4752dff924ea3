r"""The fit objective: how far a model BSDF's reflected radiance is from a target's, with its AD gradient.

The norm.  With g = f_r cos θ_o (what a Mitsuba BSDF's ``eval`` returns: the radiance
reflected towards ω_i per unit radiance arriving from ω_o) reduced to luminance
(:data:`phonglab.engine.metrics.LUMINANCE`, Rec. 709), the squared distance of a model g_m from a
target g_t is the cosine-weighted L2 norm over incidence and outgoing directions

    E² = ∫_{H+} ∫_{H+} (Δf_r cos θ_i cos θ_o)² dω_o dω_i = ∫_{H+} cos² θ_i ∫_{H+} Δg² dω_o dω_i,

and the objective is the relative residual E² / T² with T² the same integral of g_t².
f_r cos θ_i cos θ_o is the throughput of the scattering: the flux carried from a beam of unit
radiance in dω_o into dω_i per unit area and solid angle; it is symmetric in (ω_i, ω_o)
for a reciprocal BSDF, so the norm does not depend on which direction is called incident.
Both BSDFs are isotropic, so the ω_i integral reduces to θ_i: Gauss–Legendre in
μ = cos θ_i on [0, 1] with weights 2π μ_j² w_j.  The inner integral is
:func:`phonglab.physics.quadrature.lobe_quadrature` around the mirror direction of each θ_i,
refined for the lobe width of the expected exponent.  The same nodes give the directional
albedo a(θ_i) = ∫ g dω_o of both BSDFs (the furnace test).

Per incidence angle, r(θ_i) = (∫ Δg² dω_o / ∫ g_t² dω_o)^½ is the residual a viewer at θ_i
sees (reported at normal and grazing incidence).

Colour: the target's three RGB channels are reduced to luminance and a grey model is fitted
to it (one k_d, k_s, p for all channels); a coloured Fresnel term is thereby averaged.

Gradients: the model is the registered plugin itself (``phong`` or ``lambert``), loaded with
``mi.load_dict``; its parameters are written through ``mi.traverse`` as opaque ``mi.Float``
values that depend on the optimizer's variables x with Dr.Jit's AD enabled, the plugin's
``eval`` is traced over all nodes in one kernel, the loss is summed in float64 and
``dr.backward`` gives ∂loss/∂x.  No finite differences and no copy of the Phong formula.

Parametrization (the energy-conserving region k_d, k_s ≥ 0, k_d + k_s ≤ 1, p > 0 is the image
of a box, so a bounded optimizer never leaves it):

    phong:   x = (t, s, q) ∈ [0, 1] × [0, 1] × [ln p_min, ln p_max]
             k_d = t (1 − s),  k_s = t s,  p = exp(q)
    lambert: x = (k_d,) ∈ [0, 1]
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import drjit as dr
import mitsuba as mi
import numpy as np

from .. import probe
from ..engine.metrics import LUMINANCE
from ..physics.quadrature import lobe_quadrature

#: Exponent bounds of the phong model (p = exp(q)).
P_MIN, P_MAX = 1e-2, 1e4
#: Gauss–Legendre nodes in μ = cos θ_i of the objective, and per panel of lobe_quadrature.
N_INCIDENCE = 8
N_PANEL = 10


# ----------------------------------------------------------------------------- directions
@dataclass(frozen=True)
class Directions:
    """Quadrature nodes (ω_i, ω_o) of the objective, flattened over incidence angles."""

    theta_i: np.ndarray     #: (J,) incidence angles [rad], ω_i = (sin θ_i, 0, cos θ_i)
    weight_i: np.ndarray    #: (J,) weights of the θ_i integral (2π μ_j² w_j; 1 for a report set)
    wi: np.ndarray          #: (N, 3)
    wo: np.ndarray          #: (N, 3)
    w_o: np.ndarray         #: (N,) weights of the ω_o integral (lobe_quadrature)
    row: np.ndarray         #: (N,) index j of each node's θ_i

    @property
    def weight(self) -> np.ndarray:
        """(N,) weights of the double integral."""
        return self.weight_i[self.row] * self.w_o

    def per_incidence(self, values: np.ndarray) -> np.ndarray:
        """Σ_k w_k values over the ω_o nodes of each θ_i: (J,)."""
        return np.bincount(self.row, weights=self.w_o * values, minlength=len(self.theta_i))


def directions(theta_i, weight_i, width: float, n: int = N_PANEL) -> Directions:
    """The nodes of lobe_quadrature(θ_i, width, n) for each incidence angle, stacked."""
    theta_i = np.asarray(theta_i, dtype=np.float64)
    wi, wo, w, row = [], [], [], []
    for j, t in enumerate(theta_i):
        d, wk = lobe_quadrature(float(t), width, n)
        wo.append(d / np.linalg.norm(d, axis=1, keepdims=True))
        wi.append(np.broadcast_to(probe.direction(t), d.shape))
        w.append(wk)
        row.append(np.full(len(wk), j))
    return Directions(theta_i, np.asarray(weight_i, dtype=np.float64), np.concatenate(wi),
                      np.concatenate(wo), np.concatenate(w), np.concatenate(row))


def fit_directions(width: float, n_incidence: int = N_INCIDENCE, n: int = N_PANEL) -> Directions:
    """The objective's nodes: Gauss–Legendre in μ = cos θ_i, weights 2π μ² w (the cos² θ_i dω_i
    of the norm)."""
    x, w = np.polynomial.legendre.leggauss(n_incidence)
    mu = 0.5 * (x + 1.0)
    return directions(np.arccos(mu), 2.0 * math.pi * mu ** 2 * 0.5 * w, width, n)


def report_directions(theta_deg, width: float, n: int = N_PANEL) -> Directions:
    """Nodes at the given incidence angles (degrees), each weighted 1 (per-angle reports)."""
    t = np.radians(np.asarray(theta_deg, dtype=np.float64))
    return directions(t, np.ones_like(t), width, n)


def luminance_eval(bsdf, dirs: Directions, ctx=None) -> np.ndarray:
    """(N,) luminance of ``eval`` = f_r cos θ_o at every node, through :mod:`phonglab.probe`."""
    values = probe.eval(bsdf, dirs.wi, dirs.wo, ctx)
    return values @ LUMINANCE if values.shape[1] == 3 else values[:, 0]


# ----------------------------------------------------------------------------- models
@dataclass(frozen=True)
class Model:
    """A fittable plugin: its parameters as functions of the box-bounded variables x."""

    name: str                       #: plugin name in Mitsuba ("phong" or "lambert")
    labels: tuple[str, ...]         #: names of the physical parameters
    bounds: tuple[tuple[float, float], ...]   #: box of x

    def physical(self, x):
        """(k_d, k_s, p) or (k_d,) from x (numbers or Dr.Jit Floats)."""
        if self.name == "lambert":
            return (x[0],)
        t, s, q = x
        exp = dr.exp if isinstance(q, mi.Float) else math.exp
        return (t * (1.0 - s), t * s, exp(q))

    def variables(self, values) -> np.ndarray:
        """x from the physical parameters (inverse of :meth:`physical`), clipped to the box."""
        if self.name == "lambert":
            x = [values[0]]
        else:
            kd, ks, p = values
            t = kd + ks
            x = [t, ks / t if t > 0 else 0.0, math.log(max(p, P_MIN))]
        lo, hi = np.array(self.bounds).T
        return np.clip(np.array(x, dtype=np.float64), lo, hi)

    def keys(self) -> tuple[str, ...]:
        """The ``mi.traverse`` keys the physical parameters are written to."""
        if self.name == "lambert":
            return ("reflectance.value",)
        return ("diffuse_reflectance.value", "specular_reflectance.value", "exponent")

    def load(self):
        """A fresh instance of the plugin (values are overwritten by every evaluation)."""
        if self.name == "lambert":
            return mi.load_dict({"type": "lambert", "reflectance": 0.5})
        return mi.load_dict({"type": "phong", "diffuse_reflectance": 0.5,
                             "specular_reflectance": 0.2, "exponent": 10.0})


PHONG = Model("phong", ("k_d", "k_s", "p"),
              ((0.0, 1.0), (0.0, 1.0), (math.log(P_MIN), math.log(P_MAX))))
LAMBERT = Model("lambert", ("k_d",), ((0.0, 1.0),))
MODELS = {"phong": PHONG, "lambert": LAMBERT}


# ----------------------------------------------------------------------------- objective
class Objective:
    """loss(x) = Σ w (g_m − g_t)² / Σ w g_t² over a :class:`Directions` set, with its AD gradient."""

    def __init__(self, model: Model, dirs: Directions, target: np.ndarray):
        self.model = model
        self.dirs = dirs
        self.target = np.asarray(target, dtype=np.float64)
        weight = dirs.weight
        self.norm = float(np.sum(weight * self.target ** 2))
        if not self.norm > 0:
            raise ValueError("the target reflects nothing at the objective's directions")
        self.bsdf = model.load()
        self.params = mi.traverse(self.bsdf)
        self.ctx = probe.context()
        self.si = probe.interaction(dirs.wi)
        self.wo = probe.to_vectors(dirs.wo)
        self._target = mi.Float64(self.target)
        self._weight = mi.Float64(weight / self.norm)

    def _model_values(self, x_dr) -> mi.Float:
        """Luminance of the plugin's eval at every node, for parameters x (Dr.Jit Floats)."""
        for key, value in zip(self.model.keys(), self.model.physical(x_dr)):
            self.params[key] = value
        self.params.update()
        g = self.bsdf.eval(self.ctx, self.si, self.wo)
        if dr.size_v(g) != 3:   # mono
            return g[0]
        return sum(float(c) * g[k] for k, c in enumerate(LUMINANCE))

    def _variables(self, x, grad: bool) -> list:
        lo, hi = np.array(self.model.bounds).T
        x = np.clip(np.asarray(x, dtype=np.float64), lo, hi)
        out = [dr.opaque(mi.Float, float(v)) for v in x]
        if grad:
            for v in out:
                dr.enable_grad(v)
        return out

    def loss_and_grad(self, x) -> tuple[float, np.ndarray]:
        """The relative squared residual at x and its gradient ∂/∂x by reverse-mode AD."""
        xs = self._variables(x, grad=True)
        diff = mi.Float64(self._model_values(xs)) - self._target
        loss = dr.sum(self._weight * diff * diff)
        dr.backward(loss)
        grad = np.array([float(dr.grad(v)[0]) for v in xs])
        return float(loss[0]), grad

    def loss(self, x) -> float:
        """The relative squared residual at x (no AD)."""
        with dr.suspend_grad():
            diff = mi.Float64(self._model_values(self._variables(x, grad=False))) - self._target
            return float(dr.sum(self._weight * diff * diff)[0])

    def values(self, x) -> np.ndarray:
        """(N,) the model's luminance g_m at every node for parameters x."""
        with dr.suspend_grad():
            return np.array(self._model_values(self._variables(x, grad=False)), dtype=np.float64)
