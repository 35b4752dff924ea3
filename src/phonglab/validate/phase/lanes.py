r"""The calls into a phase function, lane by lane, as numpy arrays.

Mitsuba 3.9.1's convention (src/phase/hg.cpp at 478e193a, line 97:
``eval_hg(dr::dot(wo, mi.wi))`` with ``temp = 1 + g² + 2 g cos θ``, line 65): ``mi.wi`` points
*away* from the scattering point, back along the incoming light (wi = −ray.d of the ray that
arrived), and wo is the direction the light leaves in.  The scattering angle θ of the physics
literature is the angle between the travel directions −wi and wo, cos θ = −wi·wo; hg with
g > 0 scatters forward: its lobe peaks at wo = −wi (hg.cpp line 87 builds wo from
(sin θ cos φ, sin θ sin φ, −cos θ) in the frame of mi.sh_frame, whose normal is wi; tabphase
and its "physics convention" comment, src/phase/tabphase.cpp lines 84-96 and 111-115, say the
same).  ``sample`` builds its direction in ``mi.sh_frame``, so every interaction here has
sh_frame = Frame3f(wi), as ``Medium::sample_interaction`` sets it (src/render/medium.cpp).

A Python phase function reports ``component_count() = 0`` and ``flags(0)`` then ends the
process: nothing here calls ``flags`` with an index.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np

from ... import dispatch, probe
from ..directions import ONE_MINUS, basis  # noqa: F401  (basis: the χ² and normalization frames)
from ..directions import sphere as _uniform

#: Incident directions of the χ² and normalization topics (unit, fixed): the pole, an oblique
#: direction and one near the xy plane; the histogram frame turns with each (sampling.py).
INCIDENCES = np.array([[0.0, 0.0, 1.0], [0.48, -0.36, 0.8], [-0.6, -0.78, -0.1732]])
INCIDENCES = INCIDENCES / np.linalg.norm(INCIDENCES, axis=1)[:, None]

#: The query methods ``mi.PhaseFunction``'s trampoline forwards to a Python phase function
#: (``PyPhaseFunction``, src/render/python/phase_v.cpp:27-35 at v3.9.1), called through the
#: binding by :func:`view`.
METHODS = ("eval_pdf", "sample")


def view(phase) -> dispatch.Dispatched:
    """The phase function as Mitsuba's volumetric integrators call it
    (:func:`phonglab.dispatch.view`)."""
    return dispatch.view(phase, mi.PhaseFunction, METHODS)


def interaction(wi: np.ndarray) -> mi.MediumInteraction3f:
    """A MediumInteraction3f per lane at the origin with incident direction wi (N, 3) and
    sh_frame = Frame3f(wi)."""
    wi = np.atleast_2d(np.asarray(wi, np.float64))
    mei = dr.zeros(mi.MediumInteraction3f, len(wi))
    mei.wi = probe.to_vectors(wi)
    mei.sh_frame = mi.Frame3f(mei.wi)
    mei.t = mi.Float(np.zeros(len(wi), np.float32))
    return mei


def context() -> mi.PhaseFunctionContext:
    return mi.PhaseFunctionContext(None)


def sample(phase, wi: np.ndarray, u1: np.ndarray, u2: np.ndarray):
    """(wo (N, 3), weight (N, C), pdf (N,)) of ``phase.sample`` at wi with sample values
    u1 (N,) and u2 (N, 2)."""
    n = len(wi)
    if n == 0:
        return np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0)
    u1 = mi.Float(np.ascontiguousarray(np.minimum(u1, ONE_MINUS), np.float32))
    u2 = np.ascontiguousarray(np.minimum(u2, ONE_MINUS), np.float32)
    wo, w, pdf = view(phase).sample(context(), interaction(wi), u1,
                                    mi.Point2f(u2[:, 0], u2[:, 1]))
    w = probe.to_numpy(w, n)
    return probe.to_numpy(wo, n), (w if w.ndim == 2 else w[:, None]), probe.to_numpy(pdf, n)


def eval_pdf(phase, wi: np.ndarray, wo: np.ndarray, read_value: bool = True):
    """(value (N, C), pdf (N,)) of ``phase.eval_pdf`` at (wi, wo) (N, 3) each.
    ``read_value=False``: the value is None, never read back, so Dr.Jit never computes it
    (half the work of a pdf-only query such as the χ² bins' integrals)."""
    n = len(wi)
    if n == 0:                      # no lanes (every sample dropped): Dr.Jit refuses width 0
        return (np.zeros((0, 3)) if read_value else None), np.zeros(0)
    v, p = view(phase).eval_pdf(context(), interaction(wi), probe.to_vectors(wo))
    if not read_value:
        return None, probe.to_numpy(p, n)
    v = probe.to_numpy(v, n)
    return (v if v.ndim == 2 else v[:, None]), probe.to_numpy(p, n)


def pdf(phase, wi, wo) -> np.ndarray:
    return eval_pdf(phase, wi, wo, read_value=False)[1]


def value(phase, wi, wo) -> np.ndarray:
    return eval_pdf(phase, wi, wo)[0]


def projected_area(phase, wi: np.ndarray) -> np.ndarray:
    """σ(wi): a microflake phase function's projected area (1 for the others)."""
    if len(wi) == 0:
        return np.zeros(0)
    return probe.to_numpy(phase.projected_area(interaction(wi)), len(wi))


def sphere(r: np.random.Generator, n: int) -> np.ndarray:
    """n uniform directions (bsdf.lanes.sphere), the six axis directions first."""
    v = _uniform(r, n)
    k = min(n, 6)
    v[:k] = np.concatenate([np.eye(3), -np.eye(3)])[:k]
    return v


def with_edges(u: np.ndarray) -> np.ndarray:
    """Uniform sample values (N, D) with every corner of {0, 1 − 2⁻²⁴}^D in the first lanes."""
    u = np.array(u, np.float64)
    d = u.shape[1]
    grid = np.stack(np.meshgrid(*([[0.0, ONE_MINUS]] * d), indexing="ij"), -1).reshape(-1, d)
    k = min(len(u), len(grid))
    u[:k] = grid[:k]
    return u
