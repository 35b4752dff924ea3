"""The estimators of one BSDF, re-targetable to any problem without recompiling.

:class:`ReflectionEstimators` loads the BSDF once, keeps every parameter a sweep changes
opaque (:mod:`.kernel`) and runs any of :data:`METHODS`: the five i.i.d. ones of :mod:`.iid`
and the two-stage ``mis_optimal`` of :mod:`.optimal_mis`.
"""

from __future__ import annotations

import time
from dataclasses import replace

import drjit as dr
import mitsuba as mi
import numpy as np

from ... import registration
from ...errors import PhonglabError
from .exact import exact_value
from .iid import ESTIMATORS
from .kernel import (Integrand, KernelLight, channel_mean, chunks, interaction, kernel_stats,
                     uniforms)
from .optimal_mis import pilot_size, run_optimal
from .problem import METHODS, Estimate, Problem


def _load_bsdf(problem: Problem):
    """The BSDF of ``problem`` (a phonglab plugin or Mitsuba's ``diffuse``)."""
    if problem.bsdf == "phong":
        spec = {"type": "phong", "diffuse_reflectance": problem.diffuse_reflectance,
                "specular_reflectance": problem.specular_reflectance,
                "exponent": float(problem.exponent)}
    elif problem.bsdf in ("lambert", "diffuse"):
        spec = {"type": problem.bsdf, "reflectance": problem.diffuse_reflectance}
    else:
        raise PhonglabError(f"unsupported bsdf {problem.bsdf!r} for the estimators; use "
                            f"phong, lambert or diffuse")
    try:
        return mi.load_dict(spec)
    except Exception as exc:
        raise PhonglabError(f"cannot create the {problem.bsdf} BSDF: {exc}") from exc


class ReflectionEstimators:
    """The five estimators of one BSDF, re-targetable to any :class:`Problem` without recompiling.

    The BSDF is loaded once per (type, k_d, k_s); the exponent is changed through
    ``mi.traverse`` + ``params.update()`` (phong keeps it opaque); ω_i, the light
    axis, cos δ, L_e and the seed are opaque Dr.Jit values.

    Example::

        est = ReflectionEstimators(Problem(exponent=100, theta_i=30))
        e = est.run("mis", n=2**14, seed=0)
        print(e.value, e.stderr[0], est.exact())
    """

    #: Largest number of per-sample values one launch brings back to the host.
    CHUNK = 1 << 22

    def __init__(self, problem: Problem):
        registration.register()
        if not mi.variant().startswith(("llvm_", "cuda_")):
            raise PhonglabError(f"the estimators need a JIT variant (llvm_ad_rgb), not "
                                f"{mi.variant()}; call phonglab.register('llvm_ad_rgb') first")
        self.problem = problem
        self._material = None
        self._load(problem)

    def _load(self, problem: Problem) -> None:
        material = (problem.bsdf, problem.diffuse_reflectance, problem.specular_reflectance)
        if material != self._material:
            self.bsdf = _load_bsdf(problem)
            self.params = mi.traverse(self.bsdf)
            self._material = material
        if problem.bsdf == "phong" and float(self.params["exponent"][0]) != problem.exponent:
            self.params["exponent"] = mi.Float(float(problem.exponent))
            self.params.update()
        self.integrand = Integrand(self.bsdf, interaction(problem), KernelLight.of(problem),
                                   mi.BSDFContext())
        self.problem = problem

    def set(self, problem: Problem | None = None, **changes) -> "ReflectionEstimators":
        """Re-target to ``problem`` (or the current one with ``changes``); no recompilation."""
        self._load(replace(problem or self.problem, **changes))
        return self

    def exact(self) -> float:
        return exact_value(self.problem)

    def _samples(self, method: str, n_total: int, seed: int):
        """Per-sample values X (a Dr.Jit Float of n_total entries; MIS: of pairs).

        Sample k draws from PCG32 stream TEA(seed, k): u1, then u2 (then MIS's u3).
        """
        if method not in ESTIMATORS:
            raise PhonglabError(f"unknown estimator {method!r}; use one of {', '.join(METHODS)}")
        _, u1, u2, rng = uniforms(n_total, seed)
        return channel_mean(ESTIMATORS[method](self.integrand, u1, u2, rng))

    #: Pilot samples of an n-sample ``mis_optimal`` estimate (:func:`.optimal_mis.pilot_size`).
    pilot_size = staticmethod(pilot_size)

    def _values(self, method: str, per: int, batches: int, seed: int) -> np.ndarray:
        """(batches, per) float64 per-sample values, launched in chunks of <= CHUNK samples."""
        out = []
        for _, b, chunk_seed in chunks(batches, max(1, self.CHUNK // per), seed):
            x = self._samples(method, per * b, chunk_seed)
            dr.eval(x)
            out.append(np.array(x, dtype=np.float64).reshape(b, per))
        return out[0] if len(out) == 1 else np.concatenate(out)

    def run(self, method: str, n: int, seed: int = 0, batches: int = 1) -> Estimate:
        """``batches`` independent estimates with ``n`` samples each, vectorized.

        Args:
            method: one of :data:`METHODS`.
            n: samples per estimate (MIS draws n/2 pairs; n >= 2).
            seed: the random seed (sample k of the launch uses PCG32 stream TEA(seed, k)).
            batches: S, the number of independent estimates.
        """
        if method not in METHODS:
            raise PhonglabError(f"unknown estimator {method!r}; use one of {', '.join(METHODS)}")
        if n < 2 or batches < 1:
            raise PhonglabError(f"need n >= 2 samples and batches >= 1, got n={n}, batches={batches}")
        if method == "mis_optimal" and n < 2 * self.pilot_size(n):
            raise PhonglabError(f"mis_optimal needs n >= {2 * self.pilot_size(n)} samples (a pilot of "
                                f"{self.pilot_size(n)} and a main stage), got n={n}")
        dr.set_flag(dr.JitFlag.KernelHistory, True)
        dr.kernel_history()                              # clear
        t0 = time.perf_counter()
        if method == "mis_optimal":
            values, stderr, nan_count, inf_count = run_optimal(self.integrand, n, batches, seed,
                                                               self.CHUNK)
        else:
            per = n // 2 if method == "mis" else n      # MIS: n/2 pairs of 2 samples
            arr = self._values(method, per, batches, seed)
            values = arr.mean(axis=1)
            dev = arr - values[:, None]
            stderr = np.sqrt(np.einsum("ij,ij->i", dev, dev) / max(per - 1, 1) / per)
            nan_count = int(np.isnan(arr).sum())
            inf_count = int(np.isinf(arr).sum())
        seconds = time.perf_counter() - t0
        hashes: list[str] = []
        compile_ms, kernels, hits = kernel_stats(hashes)
        # Per-sample variance in the units of n: an n-sample estimate has variance σ²/n.
        per_n = n // 2 if method == "mis" else n
        return Estimate(method, n, values, stderr, nan_count, inf_count, seconds,
                        compile_ms, kernels, hits, float(np.mean(stderr ** 2)) * per_n, hashes)

    def moments(self, method: str, n: int = 1 << 22, seed: int = 0xC0FFEE) -> tuple[float, float, float]:
        """(mean, variance σ², excess kurtosis γ₂) of the per-sample value X, from n samples.

        For MIS, X is the value of one pair (two samples), so that an n-sample estimate
        has variance σ²/(n/2).  ``mis_optimal``'s samples are not identically distributed:
        σ² is n times the variance of one n-sample estimate (stratified), γ₂ is NaN.
        """
        if method == "mis_optimal":
            e = self.run(method, n, seed=seed)
            return e.value, e.sample_variance, float("nan")
        per = n // 2 if method == "mis" else n
        arr = self._values(method, per, 1, seed).ravel()
        mean = float(arr.mean())
        dev = arr - mean
        m2 = float(np.mean(dev * dev))
        m4 = float(np.mean(dev ** 4))
        return mean, m2 * per / max(per - 1, 1), (m4 / (m2 * m2) - 3.0) if m2 > 0 else 0.0

    def time_steady(self, method: str, n: int, repeats: int = 5, seed: int = 0) -> tuple[float, Estimate]:
        """Median wall time of ``repeats`` single estimates after one warm-up call (the JIT one)."""
        first = self.run(method, n, seed=seed)
        times = [self.run(method, n, seed=seed + 1 + r).seconds for r in range(repeats)]
        return float(np.median(times)), first
