"""What every Dr.Jit estimator kernel shares: the light, the integrand, random streams, sums.

Every parameter that a sweep changes (exponent, ω_i, light axis, cos δ, L_e, seed)
enters the kernel as an opaque Dr.Jit value, so a sweep compiles each estimator
once; :class:`~.problem.Estimate` records the first call's JIT compile time separately
(:func:`kernel_stats`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import drjit as dr
import mitsuba as mi
import numpy as np

from .problem import Problem


def kernel_stats(hashes: list | None = None) -> tuple[float, int, int]:
    """(compile ms, kernels, cache hits) of the JIT kernels launched since the last call.

    Reads (and so clears) ``dr.kernel_history()``; appends each kernel's hash to ``hashes``
    when given.
    """
    ms, count, hits = 0.0, 0, 0
    for k in dr.kernel_history():
        if str(k.get("type", "")).endswith("JIT"):
            count += 1
            hits += int(bool(k.get("cache_hit", 0)))
            ms += float(k.get("codegen_time", 0.0)) + float(k.get("backend_time", 0.0))
            if hashes is not None:
                hashes.append(k.get("hash"))
    return ms, count, hits


@dataclass(frozen=True)
class KernelLight:
    """A :class:`Problem`'s light inside the kernel: L(ω), its own sampling and that density.

    ``axis`` (the mirror direction R), ``cos_cutoff`` (cos δ) and ``radiance`` (L_e) are
    opaque Dr.Jit values, so a new problem reuses the compiled kernel.
    """

    constant: bool              #: the constant light (else the disk)
    axis: mi.Vector3f           #: R = 2(N·ω_i)N − ω_i, the cone's axis
    cos_cutoff: mi.Float        #: cos δ
    radiance: mi.Float          #: L_e

    @classmethod
    def of(cls, problem: Problem) -> "KernelLight":
        wi = problem.wi
        return cls(problem.light == "constant",
                   dr.opaque(mi.Vector3f, (-wi[0], -wi[1], wi[2])),     # R = 2(N·ω_i)N − ω_i
                   dr.opaque(mi.Float, math.cos(math.radians(problem.half_angle))),
                   dr.opaque(mi.Float, problem.radiance))

    def emitted(self, wo):
        """L(ω_o): L_e inside the cone (disk) or everywhere (constant)."""
        if self.constant:
            return dr.full(mi.Float, 1.0, dr.width(wo)) * self.radiance
        inside = dr.dot(wo, self.axis) >= self.cos_cutoff
        return dr.select(inside, self.radiance, 0.0)

    def sample(self, sample2):
        """(ω, pdf) of the light's own sampling: uniform in the cone (disk) or on the sphere."""
        if self.constant:
            wo = mi.warp.square_to_uniform_sphere(sample2)
            return wo, mi.warp.square_to_uniform_sphere_pdf(wo)
        local = mi.warp.square_to_uniform_cone(sample2, self.cos_cutoff)
        return mi.Frame3f(self.axis).to_world(local), \
            mi.warp.square_to_uniform_cone_pdf(local, self.cos_cutoff)

    def pdf(self, wo):
        """The density of :meth:`sample` at ω_o: 1/(4π), or 1/Ω inside the cone and 0 outside."""
        if self.constant:
            return dr.full(mi.Float, dr.inv_four_pi, dr.width(wo))
        inside = dr.dot(wo, self.axis) >= self.cos_cutoff
        return dr.select(inside, dr.rcp(dr.two_pi * (1.0 - self.cos_cutoff)), 0.0)


@dataclass(frozen=True)
class Integrand:
    """eval(ω_i, ω) · L(ω) at one surface point: the BSDF, its interaction, the light."""

    bsdf: mi.BSDF
    si: mi.SurfaceInteraction3f     #: si.wi = ω_i (local frame)
    light: KernelLight
    ctx: mi.BSDFContext


def interaction(problem: Problem) -> mi.SurfaceInteraction3f:
    """A one-lane interaction whose ``wi`` = ω_i is an opaque Dr.Jit value (all else zero).

    Not :func:`phonglab.probe.interaction`, which is the numpy-side bridge: with it (ω_i in a
    one-lane buffer made from numpy) the sweep of tests/test_estimators.py launched kernels of
    a new hash after :meth:`ReflectionEstimators.set`, i.e. recompiled, where ``dr.opaque``
    keeps one kernel per estimator.  The phonglab plugins and ``diffuse`` read only ``si.wi``
    (and constant textures) here.
    """
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi = dr.opaque(mi.Vector3f, problem.wi)
    return si


def safe_ratio(value, pdf):
    """value / pdf where pdf > 0, else 0 (no 0/0 or x/0 for a sample the density never draws)."""
    return dr.select(pdf > 0, value / dr.select(pdf > 0, pdf, 1.0), 0.0)


def row_sums_device(values: list, row, rows: int):
    """The K Dr.Jit arrays summed over the lanes of each row, left on the device: a Float64
    buffer of (rows + 1)·K entries, row r's sum of value k at r·K + k (the last row stays 0:
    a gather source of one entry would compile a different kernel).

    A scatter-add inside the kernel (``ReduceMode.Local``: reduced within each SIMD packet
    first) at the opaque index row·K + k.  Not ``dr.block_sum``, whose block size is a kernel
    literal (a new N would recompile), nor the automatic mode, which compiles a kernel per
    buffer size.  Nothing runs until the buffer is read: by :func:`row_sums`, or by a gather
    of a later kernel (which launches this one first, with no round trip to the host).
    """
    k = len(values)
    target = dr.zeros(mi.Float64, (rows + 1) * k)
    base = row * dr.opaque(mi.UInt32, k)
    for i, value in enumerate(values):
        dr.scatter_reduce(dr.ReduceOp.Add, target, mi.Float64(value), base + i,
                          mode=dr.ReduceMode.Local)
    return target


def row_sums(values: list, row, rows: int) -> np.ndarray:
    """(rows, K) float64 sums of K Dr.Jit arrays over the lanes of each row, read back at once
    (:func:`row_sums_device`)."""
    k = len(values)
    target = row_sums_device(values, row, rows)
    dr.eval(target)
    return np.array(target, dtype=np.float64)[:rows * k].reshape(rows, k)


def row_column(sums, width: int, column: int, rows: int):
    """Column ``column`` of a :func:`row_sums_device` buffer of ``width`` values a row, as a
    Float64 of rows + 1 entries (the padding row's 0 last), still on the device."""
    idx = dr.arange(mi.UInt32, rows + 1) * dr.opaque(mi.UInt32, width) + column
    return dr.gather(mi.Float64, sums, idx)


def channel_mean(spectrum):
    """Mean over colour channels (the problems are grey, so all channels agree)."""
    channels = [spectrum[k] for k in range(len(spectrum))]
    return sum(channels[1:], channels[0]) * (1.0 / len(channels))


def uniforms(n_total: int, seed):
    """(lane index, u1, u2, rng) of n_total lanes; lane k draws from PCG32 stream TEA(seed, k).

    ``seed``: a Python int (made an opaque UInt32) or already a UInt32 (a frozen function's
    input)."""
    idx = dr.arange(mi.UInt32, n_total)
    if not isinstance(seed, mi.UInt32):
        seed = dr.opaque(mi.UInt32, seed & 0xFFFFFFFF)
    v0, v1 = mi.sample_tea_32(seed, idx)
    rng = mi.PCG32(size=n_total)
    rng.seed(mi.UInt64(v0), mi.UInt64(v1))
    u1 = rng.next_float32()
    return idx, u1, mi.Point2f(rng.next_float32(), rng.next_float32()), rng


def chunks(batches: int, rows: int, seed: int):
    """(first row, rows, seed) of each launch of ``batches`` rows, at most ``rows`` per launch:
    the first launch keeps ``seed``, launch c > 0 takes (seed·0x9E3779B1 + c) mod 2³²."""
    for c, b0 in enumerate(range(0, batches, rows)):
        chunk_seed = seed if c == 0 else (seed * 0x9E3779B1 + c) & 0xFFFFFFFF
        yield b0, min(rows, batches - b0), chunk_seed
