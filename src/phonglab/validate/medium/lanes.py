r"""The calls into a medium, lane by lane, as numpy arrays, and the probe every topic shares.

Every call goes through ``mi.Medium``'s bindings (:func:`phonglab.dispatch.view`): the three
virtual methods reach a Python plugin's code through the trampoline (``PyMedium``,
src/render/python/medium_v.cpp:22-33 at v3.9.1), the non-virtual ones
(``sample_interaction``, ``transmittance_eval_pdf``, the flag getters) run Mitsuba's base-class
code whatever the plugin defines (include/mitsuba/render/medium.h:53-90): what an integrator
gets.

The interaction a coefficient is queried with is built as ``Medium::sample_interaction``
builds it (src/render/medium.cpp:47-51, 73-76): wi = −ray.d, sh_frame = Frame3f(wi), the
ray's time and wavelengths, then t, p = ray(t), mint.  The majorant is queried as that
function queries it (line 62): with the interaction *before* t and p are set, so p = (0, 0, 0)
and t = 0 whatever the ray: :func:`majorant`.

The probe (:class:`Probe`, :func:`probe`): rays with uniform directions and origins uniform in
the box [−box, box]³ (:attr:`~.config.Options.box`; a quarter of them) or in the part of the box
around where those met the medium's bounds (the rest), each clipped to where it leaves the
box; ``intersect_aabb`` of each ray, with the rule ``sample_interaction`` applies (line 54: a
ray whose two bounds are both infinite misses); one point uniform on the part of the ray
inside the medium's bounds, one uniform on the part outside them (both inside the box), and
the interaction ``sample_interaction`` itself samples on the ray.
"""

from __future__ import annotations

from dataclasses import dataclass

import drjit as dr
import mitsuba as mi
import numpy as np

from ... import dispatch, probe as probe_
from ..directions import ONE_MINUS, sphere
from .config import rng

__all__ = ["Probe", "channels", "coefficients", "flags", "intersect", "majorant", "probe",
           "sample", "view"]


#: The methods called through ``mi.Medium``'s binding by :func:`view`: the three rendering
#: methods the trampoline ``PyMedium`` forwards to Python (src/render/python/medium_v.cpp:23-32
#: at v3.9.1) and the non-virtual base-class code and getters an integrator calls on the
#: object (the package docstring).
METHODS = ("intersect_aabb", "get_majorant", "get_scattering_coefficients",
           "sample_interaction", "transmittance_eval_pdf", "phase_function",
           "is_homogeneous", "has_spectral_extinction", "use_emitter_sampling")


def view(medium) -> dispatch.Dispatched:
    """The medium as Mitsuba's integrators call it (:func:`phonglab.dispatch.view`)."""
    return dispatch.view(medium, mi.Medium, METHODS)


def channels() -> int:
    """The channels of an ``UnpolarizedSpectrum`` in the active variant (3 in RGB)."""
    return dr.size_v(mi.UnpolarizedSpectrum)


def floats(a) -> mi.Float:
    return mi.Float(probe_.aligned(np.ascontiguousarray(a, np.float64).ravel()))


def _points(a) -> mi.Point3f:
    a = np.asarray(a, np.float64)
    return mi.Point3f(*(floats(a[:, j]) for j in range(3)))


def spectrum(x, n: int) -> np.ndarray:
    """An UnpolarizedSpectrum (or a number) -> (n, C) float64."""
    a = probe_.to_numpy(x, n)
    return a if a.ndim == 2 else np.repeat(a[:, None], channels(), axis=1)


def ray(o, d, maxt=None) -> mi.Ray3f:
    """Rays from o along d (N, 3) each; maxt (N,) or infinite."""
    r = mi.Ray3f(_points(o), probe_.to_vectors(d))
    if maxt is not None:
        r.maxt = floats(maxt)
    if mi.is_spectral:
        lam = probe_.default_wavelengths()
        r.wavelengths = mi.UnpolarizedSpectrum(*(mi.Float(float(x)) for x in lam))
    return r


def interaction(o, d, t=None, mint=None) -> mi.MediumInteraction3f:
    """The MediumInteraction3f of the rays (o, d) as ``sample_interaction`` builds it; with
    t, at p = o + t d (module docstring)."""
    n = len(o)
    mei = dr.zeros(mi.MediumInteraction3f, n)
    mei.wi = probe_.to_vectors(-np.asarray(d, np.float64))
    mei.sh_frame = mi.Frame3f(mei.wi)
    if mi.is_spectral:
        lam = probe_.default_wavelengths()
        mei.wavelengths = mi.UnpolarizedSpectrum(*(mi.Float(float(x)) for x in lam))
    if t is not None:
        t = np.asarray(t, np.float64)
        mei.t = floats(t)
        mei.p = _points(np.asarray(o) + t[:, None] * np.asarray(d))
        mei.mint = floats(np.zeros(n) if mint is None else mint)
    return mei


def intersect(medium, o, d) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(hit, mint, maxt) of ``intersect_aabb`` (N,) each, hit as ``sample_interaction`` takes
    it: the mask and one finite bound (src/render/medium.cpp:53-54)."""
    n = len(o)
    out = view(medium).intersect_aabb(ray(o, d))
    hit = probe_.to_numpy(out[0], n).astype(bool)
    mint, maxt = probe_.to_numpy(out[1], n), probe_.to_numpy(out[2], n)
    hit &= np.isfinite(mint) | np.isfinite(maxt)
    return hit, mint, maxt


def majorant(medium, d) -> np.ndarray:
    """(N, C): the majorant of rays along d as ``sample_interaction`` queries it (p = 0)."""
    n = len(d)
    return spectrum(view(medium).get_majorant(interaction(np.zeros((n, 3)), d), mi.Bool(True)), n)


def coefficients(medium, o, d, t, mint=None):
    """(σ_s, σ_n, σ_t), (N, C) each, at p = o + t d of the rays (o, d)."""
    n = len(o)
    if n == 0:
        z = np.zeros((0, channels()))
        return z, z, z
    out = view(medium).get_scattering_coefficients(interaction(o, d, t, mint), mi.Bool(True))
    return tuple(spectrum(x, n) for x in out)


def sample(medium, o, d, maxt, u, channel, active=None) -> mi.MediumInteraction3f:
    """``Medium::sample_interaction`` (the base class's, as every integrator calls it) on the
    rays (o, d) with maxt, sample values u and channels (N,) each."""
    n = len(o)
    act = mi.Bool(np.ones(n, bool) if active is None else np.asarray(active, bool))
    u = np.minimum(np.asarray(u, np.float64), ONE_MINUS)
    return view(medium).sample_interaction(ray(o, d, maxt), floats(u),
                                           mi.UInt32(np.asarray(channel, np.uint32)), act)


def flags(medium) -> dict:
    """The fields the integrators branch on, read as they read them (the base class's getters,
    include/mitsuba/render/medium.h:82-90): never a Python override of the getter."""
    v = view(medium)
    return {"is_homogeneous": bool(v.is_homogeneous()),
            "has_spectral_extinction": bool(v.has_spectral_extinction()),
            "use_emitter_sampling": bool(v.use_emitter_sampling())}


def box_exit(o, d, box: float) -> np.ndarray:
    """The distance along d at which a ray from o (inside [−box, box]³) leaves the box."""
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(d > 0, (box - o) / d, np.where(d < 0, (-box - o) / d, np.inf))
    return np.min(t, axis=1)


def _uniform_on(r, lo, hi) -> np.ndarray:
    return lo + (hi - lo) * r.random(len(lo))


@dataclass
class Probe:
    """The probe rays of one run and what the medium returns along them (module docstring)."""

    o: np.ndarray           #: (N, 3) origins
    d: np.ndarray           #: (N, 3) directions
    exit: np.ndarray        #: (N,) where each leaves the box
    hit: np.ndarray         #: (N,) intersect_aabb's mask as sample_interaction takes it
    mint: np.ndarray        #: (N,) its bounds, as returned
    maxt: np.ndarray
    a: np.ndarray           #: (N,) the part of the ray inside the bounds and the box: [a, b]
    b: np.ndarray
    inside: np.ndarray      #: (N,) b > a
    majorant: np.ndarray    #: (N, C) as sample_interaction queries it
    t_in: np.ndarray        #: (N,) a point uniform on [a, b] (rays inside)
    coef_in: tuple          #: (σ_s, σ_n, σ_t) at t_in of the rays inside, (n_in, C) each
    outside: np.ndarray     #: (N,) the ray has a part outside the bounds within the box
    t_out: np.ndarray       #: (N,) a point uniform on that part
    coef_out: tuple         #: (σ_s, σ_n, σ_t) there, of the rays with such a part
    sampled: dict           #: sample_interaction's valid interactions: t, coefficients, ...

    def points(self) -> dict:
        """Every in-bounds point: the uniform ones and those sample_interaction chose, with
        the majorant of their ray (arrays of equal length)."""
        s = self.sampled
        i = np.flatnonzero(self.inside)
        return {"o": np.concatenate([self.o[i], self.o[s["ray"]]]),
                "d": np.concatenate([self.d[i], self.d[s["ray"]]]),
                "t": np.concatenate([self.t_in[i], s["t"]]),
                "sigma_s": np.concatenate([self.coef_in[0], s["sigma_s"]]),
                "sigma_n": np.concatenate([self.coef_in[1], s["sigma_n"]]),
                "sigma_t": np.concatenate([self.coef_in[2], s["sigma_t"]]),
                "majorant": np.concatenate([self.majorant[i], s["combined"]]),
                "source": np.array(["uniform"] * len(i) + ["sampled"] * len(s["t"]))}


_CACHE: dict = {}


def probe(medium, opts) -> Probe:
    """The probe of ``medium`` at ``opts``' seed and sizes (built once per run and shared by
    the topics; the last one is kept, with its medium, so an id is never reused)."""
    key = (opts.seed, opts.n_rays, opts.box, mi.variant())
    if _CACHE.get("medium") is medium and _CACHE.get("key") == key:
        return _CACHE["probe"]
    p = _build(medium, opts)
    _CACHE.update(medium=medium, key=key, probe=p)
    return p


def _focused(medium, r, n: int, box: float):
    """n rays: a quarter with origins uniform in the box, the rest with origins uniform in
    the box around what the first quarter found inside the bounds (grown by half its size on
    each side, within the box), all with uniform directions."""
    n1 = max(1, n // 4)
    o = (2.0 * r.random((n1, 3)) - 1.0) * box
    d = sphere(r, n1)
    exit_ = box_exit(o, d, box)
    hit, mint, maxt = intersect(medium, o, d)
    a = np.clip(np.nan_to_num(mint, nan=0.0), 0.0, exit_)
    b = np.clip(np.nan_to_num(maxt, nan=0.0), 0.0, exit_)
    inside = hit & (b > a)
    lo, hi = np.full(3, -box), np.full(3, box)
    if inside.any():
        ends = np.concatenate([o[inside] + a[inside, None] * d[inside],
                               o[inside] + b[inside, None] * d[inside]])
        lo, hi = ends.min(axis=0), ends.max(axis=0)
        grow = 0.5 * (hi - lo)
        lo, hi = np.maximum(lo - grow, -box), np.minimum(hi + grow, box)
    o2 = lo + (hi - lo) * r.random((n - n1, 3))
    return np.concatenate([o, o2]), np.concatenate([d, sphere(r, n - n1)])


def _build(medium, opts) -> Probe:
    r = rng(opts.seed, "probe")
    n, box = opts.n_rays, opts.box
    o, d = _focused(medium, r, n, box)
    exit_ = box_exit(o, d, box)
    hit, mint, maxt = intersect(medium, o, d)
    a = np.where(hit, np.clip(np.nan_to_num(mint, nan=0.0), 0.0, exit_), 0.0)
    b = np.where(hit, np.clip(np.nan_to_num(maxt, nan=0.0), 0.0, exit_), 0.0)
    inside = hit & (b > a)
    maj = majorant(medium, d)
    t_in = np.where(inside, _uniform_on(r, a, np.maximum(a, b)), 0.0)
    i = np.flatnonzero(inside)
    coef_in = coefficients(medium, o[i], d[i], t_in[i], a[i])
    # outside the bounds, inside the box: [0, a) and (b, exit] of a hit, all of a miss
    before = np.where(inside, a, np.where(hit, 0.0, exit_))
    after = np.where(inside, exit_ - b, 0.0)
    total = before + after
    outside = total > 1e-6 * box
    pick = r.random(n) * total
    t_out = np.where(pick < before, pick, np.where(inside, b, 0.0) + (pick - before))
    j = np.flatnonzero(outside)
    coef_out = coefficients(medium, o[j], d[j], t_out[j])
    mei = sample(medium, o, d, exit_, r.random(n), r.integers(0, channels(), n))
    valid = probe_.to_numpy(mei.is_valid(), n).astype(bool)
    k = np.flatnonzero(valid)
    sampled = {"ray": k, "t": probe_.to_numpy(mei.t, n)[k]}
    for name, x in (("sigma_s", mei.sigma_s), ("sigma_n", mei.sigma_n),
                    ("sigma_t", mei.sigma_t), ("combined", mei.combined_extinction)):
        sampled[name] = spectrum(x, n)[k]
    return Probe(o, d, exit_, hit, mint, maxt, a, b, inside, maj, t_in, coef_in, outside,
                 t_out, coef_out, sampled)
