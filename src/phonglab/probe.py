r"""The numpy <-> Dr.Jit bridge for probing a Mitsuba BSDF over arrays of directions.

Any BSDF works: a built-in (``diffuse``, ``dielectric``, ``roughconductor``, ``plastic``, ...)
or one of phonglab's Python plugins (``lambert``, ``phong``)::

    import phonglab
    phonglab.register("llvm_ad_rgb")
    import mitsuba as mi
    from phonglab import probe

    bsdf = mi.load_dict({"type": "diffuse"})
    wi = probe.direction(0.3)                          # (3,), shared by every lane
    wo = probe.direction(np.linspace(0, 1.5, 8), 2.0)  # (8, 3)
    f_cos = probe.eval(bsdf, wi, wo)                   # (8, 3): f_r cos θ_o per RGB channel
    s = probe.sample_random(bsdf, wi, 10_000, seed=1)  # s.wo, s.weight, s.pdf, ...

Conventions (Mitsuba's):

* Directions are unit vectors in the LOCAL shading frame (normal +z, tangents +x, +y), both
  pointing away from the surface.  ``wi`` is the incident / viewer side (``si.wi``), ``wo``
  the other direction (the light in a radiance computation).
* :func:`eval` returns f_r(wi, wo) · cos θ_o (the cosine is included), :func:`pdf` the
  solid-angle density of :func:`sample`'s ``wo``, and a sample's ``weight`` is
  f_r · cos θ_o / pdf (0 for an invalid sample).  For a delta lobe (mirror, glass) eval
  and pdf of a given direction are 0 and only :func:`sample` sees the lobe.
* Every result has one row per lane: the lane count N is the broadcast width of ``wi``
  (3,) or (N, 3) and the other arguments ((3,)/(N, 3) directions, scalar/(N,) sample1,
  (2,)/(N, 2) sample2).  Spectral quantities are (N, C) float64 with ALL channels:
  C = 3 in RGB variants, 1 in mono, 4 in spectral ones (one column per wavelength of
  :func:`default_wavelengths`, unless :func:`interaction` is given others).  Callers that
  want one channel take ``[:, 0]``.  Scalars (pdf, eta) are (N,), and the sampled type /
  component are (N,) int64.
* Polarized variants return Mueller matrices; the probe reports their unpolarized
  intensity (``mi.unpolarized_spectrum``, the [0, 0] entry), which is what an
  unpolarized light and sensor would see; :func:`mueller_eval`, :func:`mueller_eval_pdf`
  and :func:`mueller_sample` read the matrices back whole, (N, C, 4, 4), entry [i, j] = row
  i, column j.

Variants: in JIT variants (``llvm_ad_*``, ``cuda_ad_*``) all N lanes are one Dr.Jit
array and every call is traced and evaluated in a single kernel launch (``dr.eval`` of all
outputs at once) unless the BSDF itself forces an evaluation.  In scalar variants
(``scalar_rgb``, ``scalar_spectral``, ...) a Dr.Jit type holds ONE value, so the probe
loops over the N lanes in Python, one interaction and one BSDF call per lane: the results
are the same, but this is thousands of times slower; keep N small there (tens to hundreds).
Inputs are rounded to float32 (Mitsuba's ``Float``) in every variant; outputs are float64.

Sampling versus pdf: the probe only exposes the numbers.  To test statistically that a
BSDF's ``sample`` draws directions with the density its ``pdf`` reports, run ``phonglab
validate`` (its ``chi2`` topic: a Pearson χ² over the sphere with a lobe-adaptive pdf
integral, in every variant, and its ``normalization`` topic for the density's scale);
Mitsuba's own ``mi.chi2.ChiSquareTest`` checks sampling against pdf only, not that eval / pdf
equals the sample weight, nor that eval is right (the ``weight`` topic compares
``sample(...).weight`` with ``eval / pdf`` at ``sample(...).wo``), and does not run in scalar
variants.
"""

from __future__ import annotations

from dataclasses import dataclass

import drjit as dr
import mitsuba as mi
import numpy as np

from . import dispatch, runtime

__all__ = ["METHODS", "Sample", "context", "default_wavelengths", "direction", "eval",
           "eval_diffuse_reflectance", "eval_null_transmission", "eval_pdf", "interaction",
           "mueller_eval", "mueller_eval_pdf", "mueller_sample", "pdf", "sample",
           "sample_random", "to_numpy", "to_vectors", "view"]


@dataclass(frozen=True, eq=False)
class Sample:
    """The result of :func:`sample` for N lanes, as numpy arrays."""

    wo: np.ndarray                  #: (N, 3) sampled directions, local frame
    weight: np.ndarray              #: (N, C) f_r cos θ_o / pdf (0 where invalid)
    pdf: np.ndarray                 #: (N,) density of wo (1 for a delta lobe's discrete choice)
    eta: np.ndarray                 #: (N,) relative IOR of the sampled event (1 for reflection)
    sampled_type: np.ndarray        #: (N,) int64 mi.BSDFFlags bits of the sampled lobe
    sampled_component: np.ndarray   #: (N,) int64 component index of the sampled lobe

    @property
    def n(self) -> int:
        """Number of lanes N."""
        return len(self.pdf)


# ----------------------------------------------------------------------------- numpy side
def direction(theta, phi=0.0) -> np.ndarray:
    """Unit vector(s) (sin θ cos φ, sin θ sin φ, cos θ): polar angle θ from the normal +z.

    θ and φ (radians) broadcast; scalars give shape (3,), arrays shape (..., 3).
    """
    theta, phi = np.broadcast_arrays(np.asarray(theta, np.float64), np.asarray(phi, np.float64))
    s = np.sin(theta)
    return np.stack([s * np.cos(phi), s * np.sin(phi), np.cos(theta)], axis=-1)


def default_wavelengths() -> np.ndarray:
    """The wavelengths (nm) every lane carries in spectral variants unless told otherwise.

    The centres of equal bins of [MI_CIE_MIN, MI_CIE_MAX] = [360, 830] nm, one per
    wavelength a spectrum holds (4: 418.75, 536.25, 653.75, 771.25 nm), fixed so that
    spectral results are deterministic.
    """
    k = dr.size_v(mi.UnpolarizedSpectrum)
    lo, hi = float(mi.MI_CIE_MIN), float(mi.MI_CIE_MAX)
    return lo + (np.arange(k) + 0.5) * (hi - lo) / k


def _rows(a, width: int, name: str) -> np.ndarray:
    """``a`` as float64 rows: (k, width), or (k,) for width 0; one item gives k = 1."""
    a = np.asarray(a, dtype=np.float64)
    if width == 0:
        if a.ndim > 1:
            raise ValueError(f"{name}: expected a number or shape (N,), got {a.shape}")
        return a.reshape(-1)
    if a.ndim not in (1, 2) or a.shape[-1] != width:
        raise ValueError(f"{name}: expected shape ({width},) or (N, {width}), got {a.shape}")
    return a.reshape(-1, width)


def _broadcast(arrays: dict[str, np.ndarray], n: int | None = None) -> tuple[int, list]:
    """The common lane count of row arrays (rows of 1 broadcast) and the broadcast arrays."""
    counts = {len(a) for a in arrays.values()} - {1}
    if n is not None:
        counts |= {n}
    if len(counts) > 1:
        shapes = ", ".join(f"{k} {a.shape}" for k, a in arrays.items())
        raise ValueError(f"lane counts do not broadcast: {shapes}" + (f", n={n}" if n else ""))
    n = counts.pop() if counts else 1
    if n == 0:
        raise ValueError("nothing to probe: zero lanes")
    return n, [np.broadcast_to(a, (n,) + a.shape[1:]) for a in arrays.values()]


# ----------------------------------------------------------------------------- Dr.Jit side
def _is_jit() -> bool:
    if mi.variant() is None:
        raise RuntimeError("no Mitsuba variant is set: call phonglab.register(variant) first")
    return dr.is_jit_v(mi.Float)


#: The byte alignment of every column handed to Dr.Jit (:func:`aligned`).
ALIGN = 64


def aligned(c: np.ndarray) -> np.ndarray:
    """A float32 copy of the 1-D array ``c`` whose data starts on an :data:`ALIGN`-byte
    boundary.  Dr.Jit's LLVM backend uses a host array's memory in place and compiles an
    aligned or an unaligned vector load into the kernel depending on where that memory starts
    (numpy's allocations start anywhere 16 bytes apart), so the same query on arrays that
    happen to lie differently is a different kernel, compiled again; aligned columns make one
    kernel per query."""
    buf = np.empty(len(c) + ALIGN // 4, dtype=np.float32)
    start = (-buf.ctypes.data % ALIGN) // 4
    out = buf[start:start + len(c)]
    out[:] = c
    return out


def _dr(cls, a: np.ndarray):
    """numpy -> Dr.Jit ``cls`` (float32).  JIT: (N,) -> Float, (N, k) -> k Float columns
    (each :func:`aligned`).  Scalar variants: one lane, a number or a (k,) row."""
    a = np.asarray(a, dtype=np.float32)
    if dr.is_jit_v(mi.Float):
        cols = [a] if a.ndim == 1 else [a[:, j] for j in range(a.shape[1])]
        return cls(*(mi.Float(aligned(c)) for c in cols))
    return cls(*(float(x) for x in a.reshape(-1)))


def to_vectors(a) -> mi.Vector3f:
    """Directions (3,) or (N, 3) -> ``mi.Vector3f`` (float32); width 1 for (3,).

    In scalar variants a Vector3f holds one vector, so only (3,) or (1, 3) is accepted.
    """
    a = _rows(a, 3, "vectors")
    if _is_jit():
        return _dr(mi.Vector3f, a)
    if len(a) != 1:
        raise ValueError(f"{mi.variant()} holds one vector per Vector3f, got {len(a)}")
    return _dr(mi.Vector3f, a[0])


def _intensity(x):
    """A polarized ``mi.Spectrum`` (a Mueller matrix) -> its unpolarized intensity (M00);
    anything else as it is."""
    if mi.is_polarized and isinstance(x, mi.Spectrum):
        return mi.unpolarized_spectrum(x)
    return x


def to_numpy(x, n: int | None = None) -> np.ndarray:
    """A Dr.Jit value -> float64 numpy with the lanes first.

    Float -> (N,); Vector3f / Color / Spectrum -> (N, C); a polarized Spectrum (Mueller
    matrix) -> its unpolarized intensity (N, C).  A scalar variant's value is one lane
    (N = 1).  With ``n``, a width-1 result (a Dr.Jit literal, e.g. a constant pdf) is
    broadcast to n lanes.
    """
    x = _intensity(x)
    if n is not None and dr.is_jit_v(x) and dr.width(x) not in (1, n):
        # checked before numpy copies it: a return of another width is a plugin's defect, and
        # broadcasting it against n lanes can grow a probe past 20 GB
        raise ValueError(f"the plugin returned {dr.width(x)} lanes where {n} were queried; "
                         f"Mitsuba expects one value per lane (or one for all lanes)")
    if not dr.is_jit_v(x):
        a = np.array(x, dtype=np.float64)
        a = a.reshape((1,) + a.shape)
    elif dr.depth_v(x) > 1:
        # Column by column: each is an evaluated Float, viewed in place and converted once
        # into its column of the result, whereas np.array(x) would launch a kernel to
        # interleave them.  Columns may be width-1 literals.
        cols = [np.asarray(c) for c in x]
        a = np.empty((max(len(c) for c in cols), len(cols)))
        for j, c in enumerate(cols):
            a[:, j] = c
    else:
        # viewed in place, then converted: a copy (Dr.Jit's buffer is not numpy's to keep);
        # np.array(x, dtype=float64) converts on Dr.Jit's side, ~6x slower
        a = np.asarray(x).astype(np.float64)
    if n is not None and len(a) != n:
        if len(a) != 1:
            raise ValueError(f"expected {n} lanes or 1, got {len(a)}")
        a = np.array(np.broadcast_to(a, (n,) + a.shape[1:]))   # a writable copy
    return a


def interaction(wi, n: int | None = None, wavelengths=None) -> mi.SurfaceInteraction3f:
    """A ``mi.SurfaceInteraction3f`` of n lanes on a surface whose local frame is the world's.

    ``n = (0, 0, 1)``, ``sh_frame = Frame3f(n)`` (tangents +x, +y), ``uv = (0.5, 0.5)``,
    ``dp_du = (1, 0, 0)`` and ``dp_dv = (0, 1, 0)`` (a unit square's parametrization, which
    ``bumpmap`` needs to build its perturbed frame),
    ``wi`` from (3,) (broadcast) or (N, 3); n defaults to the rows of wi.  In spectral
    variants ``wavelengths`` (nm, (C,) or (N, C)) defaults to :func:`default_wavelengths`;
    other variants ignore it.  Scalar variants build one lane only (n = 1).
    """
    jit = _is_jit()
    arrays = {"wi": _rows(wi, 3, "wi")}
    if mi.is_spectral:
        lam = default_wavelengths() if wavelengths is None else wavelengths
        arrays["wavelengths"] = _rows(lam, dr.size_v(mi.UnpolarizedSpectrum), "wavelengths")
    n, rows = _broadcast(arrays, n)
    if not jit and n != 1:
        raise ValueError(f"{mi.variant()} is a scalar variant: one lane per interaction, not {n}")
    si = dr.zeros(mi.SurfaceInteraction3f, n) if jit else dr.zeros(mi.SurfaceInteraction3f)
    si.n = mi.Normal3f(0.0, 0.0, 1.0)
    si.sh_frame = mi.Frame3f(si.n)
    si.uv = mi.Point2f(0.5, 0.5)
    si.dp_du = mi.Vector3f(1.0, 0.0, 0.0)
    si.dp_dv = mi.Vector3f(0.0, 1.0, 0.0)
    si.wi = _dr(mi.Vector3f, rows[0] if jit else rows[0][0])
    if mi.is_spectral:
        si.wavelengths = _dr(mi.UnpolarizedSpectrum, rows[1] if jit else rows[1][0])
    return si


def context(mode=None, component: int | None = None, type_mask=None) -> mi.BSDFContext:
    """A ``mi.BSDFContext``: ``TransportMode.Radiance`` unless told otherwise, all lobes.

    ``component`` restricts it to one component index (``bsdf.flags(i)``), ``type_mask``
    to the lobes whose ``mi.BSDFFlags`` it contains.
    """
    mode = mi.TransportMode.Radiance if mode is None else mode
    type_mask = mi.BSDFFlags.All if type_mask is None else type_mask
    return mi.BSDFContext(mode, type_mask, component)


def _mueller(x, n: int) -> np.ndarray:
    """A polarized ``mi.Spectrum`` -> (n, C, 4, 4) float64 (entry [i, j] = row i, column j)."""
    c = dr.size_v(mi.UnpolarizedSpectrum)
    if not dr.is_jit_v(mi.Float):
        a = np.array(x, dtype=np.float64).reshape(4, 4, c)
        return np.broadcast_to(a.transpose(2, 0, 1)[None], (n, c, 4, 4)).copy()
    out = np.empty((n, c, 4, 4))
    for i in range(4):
        for j in range(4):
            e = x[i][j]
            for k in range(c):
                out[:, k, i, j] = np.broadcast_to(np.array(e[k], dtype=np.float64), (n,))
    return out


def _read(x, n: int | None, matrices: bool) -> np.ndarray:
    """One output as numpy: a Mueller matrix whole (``matrices``) or as its intensity."""
    if matrices and mi.is_polarized and isinstance(x, mi.Spectrum):
        return _mueller(x, 1 if n is None else n)
    return to_numpy(x, n)


#: The most memory one probe query's results may take (Dr.Jit's float32 arrays and the float64
#: numpy copies), checked before the kernel runs (:func:`_within_budget`).
QUERY_BUDGET = 2 * 2 ** 30
#: Below this many bytes a query is held against :data:`QUERY_BUDGET` alone: the memory
#: available is read (``/proc/meminfo``, ~0.1 ms) only for queries that could exhaust it.
READ_AVAILABLE_ABOVE = 64 << 20


def _nbytes(x) -> int:
    """Bytes of ``x``'s evaluated arrays: its float leaves times its width, 4 bytes each."""
    shape = dr.shape(x) if dr.is_jit_v(x) else None
    if not shape:
        return 4 * max(1, dr.width(x)) if dr.is_jit_v(x) else 0
    return 4 * int(np.prod(shape))


def _within_budget(out, n: int) -> None:
    """Refuse, in one sentence and before Dr.Jit evaluates anything, a query whose results
    would take more than :data:`QUERY_BUDGET` (or the memory available): the float32 results
    and their float64 numpy copies (three times as much again)."""
    need = sum(_nbytes(x) for x in out) * 4
    have = runtime.available_memory() if need > READ_AVAILABLE_ABOVE else None
    runtime.require_memory(need, f"one probe query of {n} lanes",
                           "query fewer lanes at once (or fix a plugin that returns more "
                           "values per lane than Mitsuba's types hold)",
                           why=f" (its results; phonglab's budget for one query is "
                               f"{QUERY_BUDGET / 2**30:g} GiB)",
                           have=QUERY_BUDGET if have is None else min(have, QUERY_BUDGET),
                           error=MemoryError)


def _probe(call, wi, matrices: bool = False, **args) -> list[np.ndarray]:
    """Run ``call(si, *dr_args)`` (returning a tuple of Dr.Jit values) over the broadcast lanes.

    ``args`` maps a name to (Dr.Jit type, array, item width) -- width 0 for scalars.
    JIT: one traced call, all outputs evaluated together.  Scalar: a loop over lanes.
    ``matrices``: a polarized variant's Mueller matrices are read back whole, (N, C, 4, 4),
    instead of as their intensity.
    """
    arrays = {"wi": _rows(wi, 3, "wi")}
    arrays.update({k: _rows(a, w, k) for k, (_, a, w) in args.items()})
    n, rows = _broadcast(arrays)
    types = [t for t, _, _ in args.values()]
    if _is_jit():
        out = call(interaction(rows[0]), *(_dr(t, r) for t, r in zip(types, rows[1:])))
        if not matrices:
            # a Mueller matrix's intensity taken before the kernel runs: it computes M00 alone
            out = [_intensity(x) for x in out]
        _within_budget(out, n)
        dr.eval(*out)
        return [_read(x, n, matrices) for x in out]
    lanes = [[_read(x, None, matrices) for x in call(interaction(rows[0][i]),
                                                     *(_dr(t, r[i]) for t, r in zip(types, rows[1:])))]
             for i in range(n)]
    return [np.concatenate(column) for column in zip(*lanes)]


# ----------------------------------------------------------------------------- BSDF queries
#: The query methods ``mi.BSDF``'s trampoline forwards to a Python BSDF (``PyBSDF``,
#: src/render/python/bsdf_v.cpp:35-77 at v3.9.1), called through the binding by :func:`view`.
METHODS = ("eval", "pdf", "eval_pdf", "eval_pdf_sample", "sample", "eval_null_transmission",
           "eval_diffuse_reflectance")


def view(bsdf) -> dispatch.Dispatched:
    """``bsdf`` as Mitsuba's integrators call it (:func:`phonglab.dispatch.view`)."""
    return dispatch.view(bsdf, mi.BSDF, METHODS)


def eval(bsdf, wi, wo, ctx=None) -> np.ndarray:
    """``bsdf.eval`` = f_r(wi, wo) cos θ_o, all channels: (N, C)."""
    bsdf = view(bsdf)  # called as Mitsuba calls it
    ctx = context() if ctx is None else ctx
    (value,) = _probe(lambda si, v: (bsdf.eval(ctx, si, v),), wi, wo=(mi.Vector3f, wo, 3))
    return value


def pdf(bsdf, wi, wo, ctx=None) -> np.ndarray:
    """``bsdf.pdf``: the solid-angle density with which :func:`sample` picks wo, (N,)."""
    bsdf = view(bsdf)  # called as Mitsuba calls it
    ctx = context() if ctx is None else ctx
    (p,) = _probe(lambda si, v: (bsdf.pdf(ctx, si, v),), wi, wo=(mi.Vector3f, wo, 3))
    return p


def eval_pdf(bsdf, wi, wo, ctx=None) -> tuple[np.ndarray, np.ndarray]:
    """``bsdf.eval_pdf``: (eval (N, C), pdf (N,)) in one call."""
    bsdf = view(bsdf)  # called as Mitsuba calls it
    ctx = context() if ctx is None else ctx
    value, p = _probe(lambda si, v: tuple(bsdf.eval_pdf(ctx, si, v)), wi, wo=(mi.Vector3f, wo, 3))
    return value, p


def eval_null_transmission(bsdf, wi) -> np.ndarray:
    """``bsdf.eval_null_transmission``: the un-scattered transmission (the ``Null`` lobe's
    weight along −wi) for light arriving along wi, all channels: (N, C)."""
    bsdf = view(bsdf)  # called as Mitsuba calls it
    (value,) = _probe(lambda si: (bsdf.eval_null_transmission(si),), wi)
    return value


def eval_diffuse_reflectance(bsdf, wi) -> np.ndarray:
    """``bsdf.eval_diffuse_reflectance``: the BSDF's diffuse reflectance at incidence wi, all
    channels: (N, C)."""
    bsdf = view(bsdf)  # called as Mitsuba calls it
    (value,) = _probe(lambda si: (bsdf.eval_diffuse_reflectance(si),), wi)
    return value


def sample(bsdf, wi, sample1, sample2, ctx=None) -> Sample:
    """``bsdf.sample`` with given uniform numbers: sample1 scalar or (N,), sample2 (2,) or (N, 2).

    sample1 usually picks the lobe, sample2 the direction within it.
    """
    bsdf = view(bsdf)  # called as Mitsuba calls it
    ctx = context() if ctx is None else ctx

    def call(si, u1, u2):
        bs, weight = bsdf.sample(ctx, si, u1, u2)
        return bs.wo, weight, bs.pdf, bs.eta, bs.sampled_type, bs.sampled_component

    wo, weight, p, eta, stype, comp = _probe(call, wi, sample1=(mi.Float, sample1, 0),
                                            sample2=(mi.Point2f, sample2, 2))
    return Sample(wo, weight, p, eta, stype.astype(np.int64), comp.astype(np.int64))


def sample_random(bsdf, wi, n: int, seed: int = 0, ctx=None) -> Sample:
    """:func:`sample` with n uniform random sample pairs from ``np.random.default_rng(seed)``.

    Draw order (fixed, so results are reproducible): first ``u1 = rng.random(n)``, then
    ``u2 = rng.random((n, 2))``.  wi is (3,) or (n, 3).
    """
    rng = np.random.default_rng(seed)
    u1 = rng.random(n)
    u2 = rng.random((n, 2))
    return sample(bsdf, wi, u1, u2, ctx)


# ----------------------------------------------------------------------------- Mueller matrices
def mueller_eval(bsdf, wi, wo, ctx=None) -> np.ndarray:
    """:func:`eval` in a polarized variant, the Mueller matrices whole: (N, C, 4, 4)."""
    bsdf = view(bsdf)  # called as Mitsuba calls it
    ctx = context() if ctx is None else ctx
    (value,) = _probe(lambda si, v: (bsdf.eval(ctx, si, v),), wi, matrices=True,
                      wo=(mi.Vector3f, wo, 3))
    return value


def mueller_eval_pdf(bsdf, wi, wo, ctx=None) -> tuple[np.ndarray, np.ndarray]:
    """:func:`eval_pdf` with the matrices whole: ((N, C, 4, 4), (N,))."""
    bsdf = view(bsdf)  # called as Mitsuba calls it
    ctx = context() if ctx is None else ctx
    value, p = _probe(lambda si, v: tuple(bsdf.eval_pdf(ctx, si, v)), wi, matrices=True,
                      wo=(mi.Vector3f, wo, 3))
    return value, p


def mueller_sample(bsdf, wi, sample1, sample2, ctx=None):
    """:func:`sample` with the weight's matrices whole: (wo (N, 3), weight (N, C, 4, 4),
    pdf (N,), sampled_type (N,) int64)."""
    bsdf = view(bsdf)  # called as Mitsuba calls it
    ctx = context() if ctx is None else ctx

    def call(si, u1, u2):
        bs, weight = bsdf.sample(ctx, si, u1, u2)
        return bs.wo, weight, bs.pdf, bs.sampled_type

    wo, weight, p, stype = _probe(call, wi, matrices=True, sample1=(mi.Float, sample1, 0),
                                  sample2=(mi.Point2f, sample2, 2))
    return wo, weight, p, stype.astype(np.int64)
