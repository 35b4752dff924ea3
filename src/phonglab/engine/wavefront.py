r"""The adaptive renderer's wavefront: traces given per-pixel sample counts and estimates each
pixel's variance from the samples themselves.

Mitsuba's ``mi.render`` renders the whole film with one sample count.
:func:`phonglab.engine.adaptive.render_adaptive` runs this Dr.Jit wavefront instead: per pass, a numpy count ``n_p`` of new samples for each
pixel p becomes one index array (``np.repeat`` of the active pixel indices, one lane per sample;
pixels with ``n_p = 0`` cost nothing), and for those lanes it does what Mitsuba's
``SamplingIntegrator::render`` does per sample: a position ``p + U²`` in the pixel, a ray from
``sensor.sample_ray_differential`` (time, wavelength and aperture samples as Mitsuba draws
them), ``integrator.sample(scene, sampler, ray, medium, active)`` (``path``, ``direct``,
phonglab's ``whitted``, any sampling integrator), times the ray weight.  Spectral variants
convert each sample to linear sRGB (``mi.spectrum_to_srgb``, linear, so the mean commutes),
polarized ones keep the unpolarized part; mono films have one channel (alpha and AOVs are not
written).  Samples come from an ``independent`` sampler seeded per pass with
:func:`phonglab.engine.render.pass_seed` (seed, k) and the wavefront size, whatever sampler the scene
names: the samples of a pixel are then i.i.d., which the variance estimate below needs.

**Two accumulations per sample.**  (1) The image: ``mi.ImageBlock`` with the film's own
reconstruction filter (``put`` of the colour and a weight channel 1), so pixel p is
``x_p = Σ_s w_ps f_s / Σ_s w_ps`` exactly as the film develops it and the image is comparable
with ``mi.render``'s and with the cached references.  (2) Box moments per pixel (each sample to
its own pixel, ``dr.scatter_reduce``): ``N_q``, ``S1_q = Σ f``, ``S2_q = Σ f²`` (float64 on the
host across passes).

**Per-pixel error (honest, from the samples themselves).**  The filtered value is a ratio of
sums of i.i.d. terms, x_p = Σ_q (1/N_q) Σ_{s∈q} w_sp f_s / W_p, W_p = Σ_q (1/N_q) Σ_{s∈q} w_sp
(the image's weight), so by the delta method, with z_s = w_sp (f_s − x_p),

    Var x_p ≈ Σ_q t_qp,   t_qp = [Σ_{s∈q} z_s² − (Σ_{s∈q} z_s)²/N_q] / (N_q (N_q − 1) W_p²),
    Σ z² = Σ w² f² − 2 x_p Σ w² f + x_p² Σ w²,   Σ z = Σ w f − x_p Σ w,

the sums over the samples of source pixel q with the weight w_sp they give target pixel p
(:meth:`Wavefront.exact_variances`): the film's ``T`` table holds Σ w f and Σ w per source
pixel and filter offset; the **squared-weight table** ``Q`` holds Σ w², Σ w² f, Σ w² f².  The
position-free model replaces w_sp² by its mean over the pixel, b(d) = ∫₀¹ w(u − ½ − d)² du
(``B_d = b(d_x) b(d_y)``, ``A_d`` likewise with w, :func:`filter_integrals`), and the sums by
the box moments ``N_q, S1_q = Σ f, S2_q = Σ f²``:

    Var x_p ≈ Σ_q B_{q−p} · Σ_{s∈q} (f_s − x_p)² / (Σ_q A_{q−p} N_q)²

(:meth:`Wavefront.variance`: a device kernel over each pixel's filter window, the textbook
variance of the mean for a box filter).  It assumes a sample's value is independent of where
in its pixel it lies, and fails where that is most false: a pixel straddling a bright edge (an
area light seen against a dark ceiling) has samples of 15 on one side and 0.1 on the other,
and its neighbour p on the dark side takes the bright samples with the filter's far tail,
where w² is tiny, not with b's pixel average — the model puts their variance into p, and
overestimates it by orders of magnitude along such edges (docs/adaptive.md has the figures).
The exact table costs 2C + 1 scatters per offset and sample, so the pilot fills it for every
pixel and later passes only for the source pixels where the pilot found the two u (below) a
factor :data:`EXACT_RATIO` apart, and their 3×3 neighbours (:meth:`Wavefront.select_exact`;
masked scatters in the pass's own kernel); the rest use the model (:meth:`Wavefront.estimate`).
The relative error of pixel p is
``e_p² = mean_c Var x_pc / (max(x_pc² − Var x_pc, 0) + ε)`` (ε =
:data:`phonglab.engine.metrics.REL_EPS`, the project's relative MSE; E x² = r² + Var x, so
x² − Var is the unbiased estimate of r²).  Per-sample sums, not the spread of pass images:
passes of one pixel differ in size, and the sums give N − 1 degrees of freedom.

**Where the variance lives: source pixels.**  Summed over the image, P · mean_p e_p² =
Σ_q u_q / N_q with ``u_q = N_q Σ_p mean_c t_qpc / (x_pc² + ε)``: the relative variance one
sample of *source* pixel q adds, independent of N_q.  It is what a sample placed in q buys,
so the allocation works on u, not on the target pixels' e_p² N_p, which with a filter wider
than a pixel mixes the neighbours' counts into p's (the source of a runaway: a target pixel
whose variance comes from a neighbour's samples gains nothing from its own, its e_p² N_p
grows with N_p, and it asks for ever more).  The model's u is ``mean_c σ²_qc ·
Σ_p B_{p−q} / (D_p² (x_pc² + ε))`` (σ²_q the box sample variance, D_p = Σ A;
:meth:`Wavefront.source_variance`).  u is scaled by one factor so that Σ u/N equals the
stop's estimate P · mean e².

The allocation that uses these estimates, the guards and the stop are
:mod:`phonglab.engine.adaptive`.

Sources: Mitsuba 3 ``src/render/integrator.cpp`` (``SamplingIntegrator::render_sample``: ray
generation) and ``src/render/imageblock.cpp`` (``ImageBlock::put``); Pharr, Jakob & Humphreys,
*PBRT* 4th ed. §2.1.4 (variance of the mean) and §8.8 (filtering); Rousselle, Knaus & Zwicker
2011 (relative MSE).
"""

from __future__ import annotations

import math
from pathlib import Path

import drjit as dr
import mitsuba as mi
import numpy as np

from . import cost
from ..errors import PhonglabError
from .metrics import REL_EPS
from .render import film_channels, pass_seed, preflight
from ..runtime import require_memory

#: After the pilot, Q is kept for the pixels whose position-free u is off the exact one by
#: more than this factor (:meth:`Wavefront.select_exact`) ...
EXACT_RATIO = 3
#: ... where the larger of the two is at least this share of the image's mean u (a pixel
#: whose u hardly counts either way keeps the model).
EXACT_FLOOR = 0.1
#: Most samples one wavefront traces (larger passes are split into several launches).
MAX_WAVEFRONT = 1 << 24
#: Bytes per pixel and filter offset: float32 filter sums of C + 1 channels and the pilot's
#: squared-weight sums of 2C + 1, kept in the JIT backend's memory (host memory on LLVM),
#: with temporaries (25 offsets for the gaussian filter: about 1.7 KiB a pixel, 1.7 GiB at
#: 1024²).
HOST_BYTES_PER_PIXEL_OFFSET = 68


#: numpy dtype of each Dr.Jit element type :func:`jit_array` converts to
_DTYPES = {dr.VarType.Float32: np.float32, dr.VarType.Float64: np.float64,
           dr.VarType.UInt32: np.uint32, dr.VarType.Int32: np.int32, dr.VarType.Bool: np.bool_}
#: Alignment (bytes) of every host buffer :func:`jit_array` hands to Dr.Jit.
JIT_ALIGN = 64


def jit_array(cls, array: np.ndarray):
    """``cls(array)`` from a contiguous buffer aligned to :data:`JIT_ALIGN` bytes, copied there
    when it is not.

    Dr.Jit 1.5 compiles a different kernel for a host array that happens to be 64-byte aligned
    (its load is emitted ``align 64``, else ``align 1``), so the same pass got one of two
    kernel hashes depending on where numpy had put the index array, and a hash first seen
    cost a fresh LLVM compile (~1 s: cornell_phong 128², 3 of 8 renders in one process, and
    in fresh processes again).  Always aligned, each kernel has one hash, cached once."""
    a = np.ascontiguousarray(array, dtype=_DTYPES[dr.type_v(cls)]).ravel()
    if a.ctypes.data % JIT_ALIGN:
        buf = np.empty(a.nbytes + JIT_ALIGN, dtype=np.uint8)
        start = -buf.ctypes.data % JIT_ALIGN
        aligned = buf[start:start + a.nbytes].view(a.dtype)
        aligned[...] = a
        a = aligned
    return cls(a)


def filter_integrals(rfilter, samples: int = 64) -> tuple[np.ndarray, np.ndarray]:
    """(a, b) on offsets d = −R..R: ``a(d) = ∫₀¹ w(u − ½ − d) du`` and ``b(d) = ∫₀¹ w(...)² du``
    (midpoint rule, ``samples`` points), the mean weight (and squared weight) a sample
    anywhere in pixel q gives pixel p = q + d along one axis of a separable filter w."""
    radius = int(math.ceil(float(rfilter.radius()) + 0.5))
    d = np.arange(-radius, radius + 1, dtype=np.float64)
    u = (np.arange(samples) + 0.5) / samples
    x = (u[None, :] - 0.5 - d[:, None]).ravel()
    w = np.array(rfilter.eval(mi.Float(x)), dtype=np.float64).reshape(len(d), samples)
    return w.mean(axis=1), (w * w).mean(axis=1)


def filter_tables(rfilter, samples: int = 64) -> tuple[np.ndarray, np.ndarray]:
    """(A, B) = (a ⊗ a, b ⊗ b) of :func:`filter_integrals`, indexed [d_y + R, d_x + R]."""
    a, b = filter_integrals(rfilter, samples)
    return np.outer(a, a), np.outer(b, b)


def separable_filter(kernel: np.ndarray, a: np.ndarray) -> np.ndarray:
    """``a`` (H, W, ...) convolved with the separable kernel k ⊗ k over its first two axes,
    zero outside the image: one shifted, weighted slice per tap and axis.  (numpy alone, like
    ``scipy.ndimage.convolve1d`` with mode="constant" twice, which the tests compare it with:
    importing scipy.ndimage cost every planned command ~0.12 s, measured before and after.)"""
    kernel = np.asarray(kernel, dtype=np.float64)
    r = len(kernel) // 2
    for axis in (0, 1):
        size = a.shape[axis]
        pad = [(0, 0)] * a.ndim
        pad[axis] = (r, r)
        padded = np.pad(a, pad)
        out = np.zeros(a.shape, dtype=np.result_type(a, kernel))
        window = [slice(None)] * a.ndim
        for i, k in enumerate(kernel[::-1]):
            window[axis] = slice(i, i + size)
            out += k * padded[tuple(window)]
        a = out
    return a


def window_mean(v: np.ndarray, half: int) -> np.ndarray:
    """Mean of an (H, W) map over the (2·half + 1)² window, edges averaging what exists."""
    box = np.ones(2 * half + 1)
    return separable_filter(box, v) / separable_filter(box, np.ones_like(v))


class Wavefront:
    """Traces given per-pixel sample counts of one scene; accumulates filter sums and moments."""

    def __init__(self, scene, integrator=None, sensor: int = 0, path: str | Path = "the scene"):
        if not dr.is_jit_v(mi.Float):
            raise PhonglabError(f"adaptive sampling needs a JIT variant (llvm_* or cuda_*), "
                                f"not {mi.variant()}; pass e.g. --variant llvm_ad_rgb")
        self.scene = scene
        self.sensor = preflight(scene, path, sensor)
        self.integrator = integrator or scene.integrator()
        if not isinstance(self.integrator, mi.SamplingIntegrator):
            raise PhonglabError(f"{path}: its {self.integrator.class_name()} integrator is not "
                                f"sampled per pixel (a particle tracer splats light paths onto "
                                f"the film), so adaptive sampling cannot steer it; render it "
                                f"with a fixed --spp instead")
        names = film_channels(self.sensor, self.integrator, path)
        expected = ["Y"] if mi.is_monochromatic else ["R", "G", "B"]
        if names != expected:
            raise PhonglabError(f"{path}: adaptive sampling writes {', '.join(expected)} but the "
                                f"film's pixel_format gives {', '.join(names)}; set the film's "
                                f"pixel_format to {'luminance' if mi.is_monochromatic else 'rgb'}"
                                f" or render with a fixed --spp")
        film = self.sensor.film()
        self.width, self.height = (int(v) for v in film.crop_size())
        self.rfilter = film.rfilter()
        self.channels = 1 if mi.is_monochromatic else 3
        self.a, self.b = filter_integrals(self.rfilter)
        self.A, self.B = np.outer(self.a, self.a), np.outer(self.b, self.b)
        radius = self.A.shape[0] // 2
        #: offsets d = p − q (target pixel p, the sample's pixel q) the filter reaches
        self.offsets = [(iy - radius, ix - radius) for iy in range(self.A.shape[0])
                        for ix in range(self.A.shape[1]) if self.A[iy, ix] > 0]
        #: (d_y, d_x, A_d, B_d) of every offset d = p − q where A or B is non-zero: the window
        #: of the device kernels of :meth:`variance` and :meth:`source_variance`
        self.window = [(iy - radius, ix - radius, float(self.A[iy, ix]), float(self.B[iy, ix]))
                       for iy in range(self.A.shape[0]) for ix in range(self.A.shape[1])
                       if self.A[iy, ix] != 0 or self.B[iy, ix] != 0]
        npix = self.width * self.height
        require_memory(HOST_BYTES_PER_PIXEL_OFFSET * len(self.offsets) * npix,
                       f"{path}: adaptive sampling of a {self.width} x {self.height} film",
                       "lower the resolution", why=" for its per-pixel sums")
        self.n = np.zeros(npix, dtype=np.int64)
        self.s1 = np.zeros((npix, self.channels))
        self.s2 = np.zeros((npix, self.channels))
        #: T[q, k] = Σ_{s in q} w(x_s − centre of q + d_k) · (f_s, 1), on the device (float32;
        #: only the developed image comes back to the host each pass)
        self.splat = dr.zeros(mi.Float, npix * len(self.offsets) * (self.channels + 1))
        self.sampler = mi.load_dict({"type": "independent"})
        #: while on, :meth:`trace` also accumulates Q[q, k] = Σ_{s in q} w² · (1, f_s, f_s²)
        #: (the exact squared-weight sums of :meth:`exact_variances`; the pilot's)
        self.squares = False
        self.splat2 = None
        #: source pixels (flat bool) whose samples enter Q; None: every pixel
        self.exact = None

    @property
    def pixels(self) -> int:
        return self.width * self.height

    def trace(self, counts: np.ndarray, seed: int) -> int:
        """Trace ``counts[p]`` new samples in pixel p (flat index); returns the samples traced."""
        counts = np.asarray(counts, dtype=np.int64)
        total = int(counts.sum())
        if total == 0:
            return 0
        index = np.repeat(np.arange(self.pixels, dtype=np.uint32), counts)
        for k, start in enumerate(range(0, total, MAX_WAVEFRONT)):
            self._launch(index[start:start + MAX_WAVEFRONT], pass_seed(seed, k))
        # the counts themselves, not a bincount of the lanes: 0.1 s per 16.7M lanes, and a
        # fresh process's first one spent 1 s in page faults (its int64 copy of the index)
        self.n += counts
        return total

    def _camera_rays(self, idx):
        """Rays through a uniform point of each sample's pixel, as Mitsuba's film render makes
        them (integrator.cpp, render_sample); returns (ray, weight, position in the pixel)."""
        sampler, sensor = self.sampler, self.sensor
        x = idx % self.width
        pos = mi.Vector2f(mi.Float(x), mi.Float((idx - x) // self.width))
        wavelength = sampler.next_1d() if mi.is_spectral else mi.Float(0.5)
        time_ = dr.opaque(mi.Float, sensor.shutter_open())
        if sensor.shutter_open_time() > 0:
            time_ += sampler.next_1d() * sensor.shutter_open_time()
        u = sampler.next_2d()
        aperture = sampler.next_2d() if sensor.needs_aperture_sample() else mi.Point2f(0.5)
        scale = mi.ScalarVector2f(1.0 / self.width, 1.0 / self.height)
        ray, weight = sensor.sample_ray_differential(time_, wavelength, (pos + u) * scale,
                                                     aperture)
        return ray, weight, u

    def _launch(self, index: np.ndarray, seed: int) -> None:
        self.sampler.seed(dr.opaque(mi.UInt32, seed), len(index))
        idx = jit_array(mi.UInt32, index)
        ray, weight, u = self._camera_rays(idx)
        spec, _, _ = self.integrator.sample(self.scene, self.sampler, ray,
                                            self.sensor.get_medium(), mi.Bool(True))
        spec = mi.unpolarized_spectrum(weight * spec)
        color = mi.spectrum_to_srgb(spec, ray.wavelengths, mi.Bool(True)) if mi.is_spectral \
            else spec
        values = [color[c] for c in range(self.channels)]
        s1 = [dr.zeros(mi.Float, self.pixels) for _ in values]
        s2 = [dr.zeros(mi.Float, self.pixels) for _ in values]
        for c, v in enumerate(values):
            dr.scatter_reduce(dr.ReduceOp.Add, s1[c], v, idx)
            dr.scatter_reduce(dr.ReduceOp.Add, s2[c], v * v, idx)
        width = len(self.offsets) * (self.channels + 1)
        if self.squares:    # Q for the lanes of the pixels in `exact`: masked, in this kernel
            width2 = len(self.offsets) * (2 * self.channels + 1)
            if self.splat2 is None:
                self.splat2 = dr.zeros(mi.Float, self.pixels * width2)
            keep = mi.Bool(True) if self.exact is None else \
                dr.gather(mi.Bool, jit_array(mi.Bool, self.exact), idx)
            moments = [mi.Float(1.0)] + values + [v * v for v in values]
        for k, (dy, dx) in enumerate(self.offsets):
            # weight of target pixel q + d: filter at (sample position − target centre)
            w = (self.rfilter.eval(u.x - (dx + 0.5)) * self.rfilter.eval(u.y - (dy + 0.5)))
            base = idx * width + k * (self.channels + 1)
            for c, v in enumerate(values + [mi.Float(1.0)]):
                dr.scatter_reduce(dr.ReduceOp.Add, self.splat, w * v, base + c)
            if self.squares:
                base2 = idx * width2 + k * (2 * self.channels + 1)
                for c, v in enumerate(moments):
                    dr.scatter_reduce(dr.ReduceOp.Add, self.splat2, w * w * v, base2 + c, keep)
        # One kernel a pass, nothing per sample stored: a second launch over the Q lanes
        # needed every sample's values and position in memory (outdoor_envmap 128², a pass of
        # 5.2M samples, Q on 0.9 % of the pixels: 2.33 s; masked here 1.57 s; 1.19 s without
        # Q, whose pixels, the noisy ones, take many of the samples).
        dr.eval(s1, s2, self.splat, *([self.splat2] if self.squares else []))
        self.s1 += np.stack([np.array(a, dtype=np.float64) for a in s1], axis=1)
        self.s2 += np.stack([np.array(a, dtype=np.float64) for a in s2], axis=1)

    def cost_map(self, seed: int, spp: int = cost.PROBE_SPP) -> np.ndarray | None:
        """(H, W) c_q = a + s_q, the cost of one sample of pixel q in rays
        (:mod:`phonglab.engine.cost`): ``spp`` probe paths per pixel, s_q their mean ray
        count averaged over the 3×3 window; None when the integrator is not ``path``."""
        depths = cost.path_depths(self.integrator)
        if depths is None:
            return None
        index = np.repeat(np.arange(self.pixels, dtype=np.uint32), spp)
        self.sampler.seed(dr.opaque(mi.UInt32, seed), len(index))
        idx = jit_array(mi.UInt32, index)
        ray, _, _ = self._camera_rays(idx)
        casts = cost.path_casts(self.scene, self.sampler, ray, *depths)
        total = dr.zeros(mi.Float, self.pixels)
        dr.scatter_reduce(dr.ReduceOp.Add, total, mi.Float(casts), idx)
        rays = np.array(total, dtype=np.float64).reshape(self.height, self.width) / spp
        return cost.FIXED_COST + window_mean(rays, 1)

    def image(self) -> np.ndarray:
        """(H, W, C): x_p = Σ_q T_qp / N_q ÷ Σ_q W_qp / N_q (module docstring), on the device."""
        inv = jit_array(mi.Float, np.where(self.n > 0, 1.0 / np.maximum(self.n, 1), 0.0))
        p = dr.arange(mi.UInt32, self.pixels)
        px, py = mi.Int32(p % self.width), mi.Int32(p // self.width)
        width = len(self.offsets) * (self.channels + 1)
        total = [dr.zeros(mi.Float, self.pixels) for _ in range(self.channels + 1)]
        for k, (dy, dx) in enumerate(self.offsets):   # source q = target p − d
            qx, qy = px - dx, py - dy
            ok = (qx >= 0) & (qx < self.width) & (qy >= 0) & (qy < self.height)
            q = mi.UInt32(dr.select(ok, qy * self.width + qx, 0))
            scale = dr.gather(mi.Float, inv, q, ok)
            base = q * width + k * (self.channels + 1)
            for c in range(self.channels + 1):
                total[c] += dr.gather(mi.Float, self.splat, base + c, ok) * scale
        dr.eval(total)
        t = np.stack([np.array(a, dtype=np.float64) for a in total], axis=1)
        t = t.reshape(self.height, self.width, self.channels + 1)
        weight = t[..., -1:]
        self.weight = weight          # W_p, the ratio's denominator (exact_variances)
        return np.where(weight > 0, t[..., :-1] / np.where(weight > 0, weight, 1), 0.0)

    def _neighbour(self, px, py, dy: int, dx: int, sign: int):
        """(index, in-image mask) of the pixel at (px, py) + sign·(dx, dy)."""
        qx, qy = px + sign * dx, py + sign * dy
        ok = (qx >= 0) & (qx < self.width) & (qy >= 0) & (qy < self.height)
        return mi.UInt32(dr.select(ok, qy * self.width + qx, 0)), ok

    def _den(self, n, px, py):
        """(D_p = Σ_q A_{p−q} [N_q > 0], Σ_q A_{p−q} [N_q = 1]) on the device."""
        den, lonely = mi.Float64(0.0), mi.Float64(0.0)
        for dy, dx, a_d, _ in self.window:
            q, ok = self._neighbour(px, py, dy, dx, -1)
            nq = dr.gather(mi.Float64, n, q, ok)
            den += dr.select(nq > 0, mi.Float64(a_d), 0.0)
            lonely += dr.select(nq == 1, mi.Float64(a_d), 0.0)
        return den, lonely

    def variance(self, image: np.ndarray, exclude: np.ndarray | None = None) -> np.ndarray:
        """(H, W, C) the delta-method variance of each filtered pixel, position-free model
        (module docstring), from the source pixels not in ``exclude`` (flat bool).

        The sum over source pixels q = p − d of ``[B_d (S2 − 2x S1 + x² N) − A_d² (S1 −
        x N)²/N] / (N (N − 1))`` (x = x_p), one Dr.Jit kernel with a lane per target pixel
        gathering its sources in float64.  (In numpy, as convolutions with the separable
        kernels, it took 10–35 ms a pass at 128² to 512×128, 9–17 % of an adaptive render.)
        """
        c = self.channels
        n = jit_array(mi.Float64, self.n)
        scale = np.where(self.n > 1, 1.0 / np.maximum(self.n * (self.n - 1.0), 1.0), 0.0)
        if exclude is not None:
            scale = scale * ~exclude
        scale = jit_array(mi.Float64, scale)
        s1, s2 = jit_array(mi.Float64, self.s1), jit_array(mi.Float64, self.s2)
        x_all = jit_array(mi.Float64, image)
        p = dr.arange(mi.UInt32, self.pixels)
        px, py = mi.Int32(p % self.width), mi.Int32(p // self.width)
        x = [dr.gather(mi.Float64, x_all, p * c + ch) for ch in range(c)]
        num = [mi.Float64(0.0) for _ in range(c)]
        for dy, dx, a_d, b_d in self.window:
            q, ok = self._neighbour(px, py, dy, dx, -1)
            nq = dr.gather(mi.Float64, n, q, ok)
            sc = dr.gather(mi.Float64, scale, q, ok)
            for ch in range(c):
                m1 = dr.gather(mi.Float64, s1, q * c + ch, ok)
                m2 = dr.gather(mi.Float64, s2, q * c + ch, ok)
                centred = x[ch] * x[ch] * nq - 2 * x[ch] * m1
                num[ch] += sc * (b_d * (m2 + centred)
                                 - a_d * a_d * (m1 * m1 / dr.maximum(nq, 1.0) + centred))
        den, lonely = self._den(n, px, py)
        known = (den > 0) & (lonely == 0)        # a source of 1 sample: unknown
        var = [dr.select(known, dr.maximum(v, 0.0) / (den * den), dr.inf) for v in num]
        dr.eval(var)
        return np.stack([np.array(v, dtype=np.float64) for v in var], axis=1).reshape(
            self.height, self.width, c)

    def estimate(self, image: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """((H, W, C) Var x_p, (H, W) u_q): the exact sums' terms for the source pixels in Q
        (:attr:`exact`; every pixel in the pilot), the position-free model's for the rest."""
        h, w = self.height, self.width
        if self.squares:
            exact = np.ones(self.pixels, bool) if self.exact is None else self.exact
            var_q, u_q = self.exact_variances(image, exact)
            var = self.variance(image, exclude=exact) + var_q
            u = np.where(exact.reshape(h, w), u_q, self.source_variance(image))
        else:
            var, u = self.variance(image), self.source_variance(image)
        # u weighs by 1/(x² + ε); relative_error_map by the unbiased 1/(x² − Var + ε): scaled
        # so that Σ u/N is P · mean e² (the allocation's prediction is the stop's estimate)
        n = self.n.reshape(h, w)
        err2, pred = relative_error_map(image, var), np.where(n > 0, u / np.maximum(n, 1), 0.0)
        ok = np.isfinite(err2).all() and pred.sum() > 0
        return var, u * (float(err2.mean() / pred.mean()) if ok else 1.0)

    def select_exact(self, image: np.ndarray, u_q: np.ndarray,
                     spread: float = EXACT_RATIO) -> None:
        """After the pilot (``u_q`` its exact u, :meth:`estimate`): keep Q only for the source
        pixels where the position-free model's u is off the exact one by more than ``spread``
        either way while the larger is at least :data:`EXACT_FLOOR` of the mean u, and their
        3×3 neighbours (an edge the pilot only grazed); none: Q is dropped."""
        u_m = self.source_variance(image)
        big, small = np.maximum(u_q, u_m), np.minimum(u_q, u_m)
        off = (big > spread * small) & (big > EXACT_FLOOR * float(np.mean(u_q)))
        off = separable_filter(np.ones(3), off.astype(np.float64)) > 0
        self.exact = off.reshape(self.pixels)
        if not self.exact.any():
            self.squares, self.splat2 = False, None

    def source_variance(self, image: np.ndarray) -> np.ndarray:
        """(H, W) u_q of the position-independent model: per-sample variance of source pixel q
        (its box moments) times Σ_p B_{p−q} / (D_p² (x_p² + ε)), mean over channels (module
        docstring, "Where the variance lives"); two Dr.Jit kernels (D_p, then u_q)."""
        h, w, c = self.height, self.width, self.channels
        n = jit_array(mi.Float64, self.n)
        p = dr.arange(mi.UInt32, self.pixels)
        px, py = mi.Int32(p % w), mi.Int32(p // w)
        den, _ = self._den(n, px, py)
        x_all = jit_array(mi.Float64, image)
        omega = []
        for ch in range(c):
            x = dr.gather(mi.Float64, x_all, p * c + ch)
            omega.append(dr.select(den > 0, 1.0 / (den * den), 0.0) / (x * x + REL_EPS))
        dr.eval(omega)
        spread = [mi.Float64(0.0) for _ in range(c)]
        for dy, dx, _, b_d in self.window:   # targets p = q + d of source q
            t, ok = self._neighbour(px, py, dy, dx, +1)
            for ch in range(c):
                spread[ch] += b_d * dr.gather(mi.Float64, omega[ch], t, ok)
        dr.eval(spread)
        nn = self.n.reshape(h, w, 1).astype(np.float64)
        s1, s2 = self.s1.reshape(h, w, c), self.s2.reshape(h, w, c)
        sigma2 = np.where(nn > 1, (s2 - s1 * s1 / np.maximum(nn, 1)) / np.maximum(nn - 1, 1), 0.0)
        spread = np.stack([np.array(v, dtype=np.float64) for v in spread], axis=1)
        return np.mean(np.maximum(sigma2, 0.0) * spread.reshape(h, w, c), axis=2)

    def exact_variances(self, image: np.ndarray, sources: np.ndarray
                        ) -> tuple[np.ndarray, np.ndarray]:
        """((H, W, C) Var x_p, (H, W) u_q) by the delta method on the exact squared-weight sums
        Q (module docstring): no assumption on where in its pixel a sample lies; the terms of
        the source pixels in ``sources`` (flat bool), each of which has every sample in Q.
        ``image`` is the last :meth:`image` (its weights W_p are reused).

        One Dr.Jit kernel over the lanes (q, k), a source pixel and a filter offset (at most
        :data:`MAX_WAVEFRONT` a launch): each gathers its rows of T and Q where they lie and
        scatters its term, in float64, to its target pixel p = q + d_k and to u_q.  (A numpy
        version copied the rows to the host in blocks: 0.06 s of the pilot's 0.15 s on
        textured_room at 128², more than the device kernel by an order of magnitude.)"""
        h, w, c, k = self.height, self.width, self.channels, len(self.offsets)
        every = np.flatnonzero(sources & (self.n > 1)).astype(np.uint32)
        var = dr.zeros(mi.Float64, self.pixels * c)
        u = dr.zeros(mi.Float64, self.pixels)
        if len(every):
            x_all = jit_array(mi.Float64, image)
            weight = jit_array(mi.Float64, self.weight)
            counts = jit_array(mi.Float64, self.n)
            dy, dx = (jit_array(mi.Int32, np.array(self.offsets)[:, i])
                      for i in (0, 1))
            per_launch = max(1, MAX_WAVEFRONT // k)
            for start in range(0, len(every), per_launch):
                lane = dr.arange(mi.UInt32, min(per_launch, len(every) - start) * k)
                q = dr.gather(mi.UInt32, jit_array(mi.UInt32, every[start:start + per_launch]),
                              lane // k)
                j = lane % k
                py = mi.Int32(q // w) + dr.gather(mi.Int32, dy, j)
                px = mi.Int32(q % w) + dr.gather(mi.Int32, dx, j)
                inside = (py >= 0) & (py < h) & (px >= 0) & (px < w)
                p = mi.UInt32(dr.select(inside, py * w + px, 0))        # target p = q + d
                wp = dr.gather(mi.Float64, weight, p, inside)
                ok = inside & (wp > 0)
                n = dr.gather(mi.Float64, counts, q)
                rows_t = q * (k * (c + 1)) + j * (c + 1)
                rows_q = q * (k * (2 * c + 1)) + j * (2 * c + 1)
                T = [mi.Float64(dr.gather(mi.Float, self.splat, rows_t + i)) for i in range(c + 1)]
                Q = [mi.Float64(dr.gather(mi.Float, self.splat2, rows_q + i))
                     for i in range(2 * c + 1)]
                scale = 1.0 / (n * (n - 1) * wp * wp)
                rel = mi.Float64(0.0)
                for ch in range(c):
                    x = dr.gather(mi.Float64, x_all, p * c + ch, ok)
                    sz = T[ch] - x * T[c]
                    sz2 = Q[1 + c + ch] - 2 * x * Q[1 + ch] + x * x * Q[0]
                    term = dr.maximum(sz2 - sz * sz / n, 0.0) * scale
                    dr.scatter_reduce(dr.ReduceOp.Add, var, term, p * c + ch, ok)
                    rel += term / (x * x + REL_EPS)
                dr.scatter_reduce(dr.ReduceOp.Add, u, n * rel / c, q, ok)
                dr.eval(var, u)
        return (np.array(var, dtype=np.float64).reshape(h, w, c),
                np.array(u, dtype=np.float64).reshape(h, w))


def relative_error_map(image: np.ndarray, variance: np.ndarray) -> np.ndarray:
    """(H, W) e_p² = mean over channels of Var / (r̂² + ε), r̂² = max(x² − Var, 0) the
    first-order unbiased estimate of the true value's square (E x² = r² + Var x)."""
    var = np.nan_to_num(variance, posinf=np.inf)
    return np.mean(variance / (np.maximum(image * image - np.where(np.isfinite(var), var, 0.0),
                                          0.0) + REL_EPS), axis=2)
