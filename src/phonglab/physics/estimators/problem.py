"""The reflection-equation problem an estimator solves, and the record of its estimates.

A :class:`Problem` names the BSDF, the incidence ω_i and the light (the package docstring
defines the integral and the two lights); an :class:`Estimate` holds S independent
N-sample estimates with their standard errors, the non-finite sample counts and the JIT
costs of the call.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ... import probe
from ...errors import PhonglabError

#: Estimator names, in the order charts and tables list them.
METHODS: tuple[str, ...] = ("uniform", "cosine", "bsdf", "light", "mis", "mis_optimal")
#: Estimators whose N samples are independent and identically distributed (all but the
#: two-stage ``mis_optimal``, whose samples follow a pilot-chosen allocation).
IID_METHODS: tuple[str, ...] = METHODS[:5]
LIGHTS: tuple[str, ...] = ("constant", "disk")


@dataclass(frozen=True)
class Problem:
    """One reflection-equation integral: the BSDF, the incidence and the light.

    Attributes:
        bsdf: ``"phong"`` or ``"lambert"`` (phonglab's plugins, whose exact values
            :func:`~.exact.exact_value` knows), or a Mitsuba built-in (``"diffuse"``; no
            exact value).
        diffuse_reflectance: k_d (ρ for ``lambert``/``diffuse``), grey.
        specular_reflectance: k_s (``phong`` only), grey.
        exponent: p (``phong`` only).
        theta_i: incidence angle of ω_i in degrees, in [0, 90).
        light: ``"constant"`` or ``"disk"``.
        half_angle: δ of the disk light in degrees.
        radiance: L_e.
    """

    bsdf: str = "phong"
    diffuse_reflectance: float = 0.0
    specular_reflectance: float = 1.0
    exponent: float = 100.0
    theta_i: float = 30.0
    light: str = "disk"
    half_angle: float = 3.0
    radiance: float = 1.0

    def __post_init__(self):
        if self.light not in LIGHTS:
            raise PhonglabError(f"unknown light {self.light!r}; use one of {', '.join(LIGHTS)}")
        if not 0.0 <= self.theta_i < 90.0:
            raise PhonglabError(f"theta_i must lie in [0, 90) degrees, got {self.theta_i}")
        if not 0.0 < self.half_angle < 90.0:
            raise PhonglabError(f"half_angle must lie in (0, 90) degrees, got {self.half_angle}")
        if not (math.isfinite(self.exponent) and self.exponent >= 0):
            raise PhonglabError(f"exponent must be finite and >= 0, got {self.exponent}")

    @property
    def wi(self) -> tuple[float, float, float]:
        """ω_i in the local frame: (sin θ_i, 0, cos θ_i)."""
        return tuple(float(c) for c in probe.direction(math.radians(self.theta_i)))

    @property
    def label(self) -> str:
        if self.bsdf == "phong":
            mat = (f"phong kd={self.diffuse_reflectance:g} ks={self.specular_reflectance:g} "
                   f"p={self.exponent:g}")
        else:
            mat = f"{self.bsdf} rho={self.diffuse_reflectance:g}"
        light = "constant light" if self.light == "constant" else f"disk {self.half_angle:g}deg"
        return f"{mat}, {light}, theta_i={self.theta_i:g}deg"


@dataclass
class Estimate:
    """S independent estimates of one :class:`Problem` with N samples each.

    Attributes:
        method: estimator name.
        n: samples per estimate (MIS: n/2 pairs).
        values: (S,) float64 estimates (sample means).
        stderr: (S,) float64 standard errors s/√n of each estimate.
        nan_count / inf_count: non-finite per-sample values over all S·n samples.
        seconds: wall time of the call (trace + kernel + transfer).
        compile_ms: JIT compile time inside this call (codegen + backend, ms; 0 on a
            kernel-cache hit).
        kernels: kernels launched; cache_hits: how many of them were cached.
        sample_variance: pooled per-sample variance s² (over all S·n samples around
            their batch means).
        kernel_hashes: Dr.Jit hashes of the kernels launched (equal hashes = no recompile).
    """

    method: str
    n: int
    values: np.ndarray
    stderr: np.ndarray
    nan_count: int
    inf_count: int
    seconds: float
    compile_ms: float
    kernels: int
    cache_hits: int
    sample_variance: float
    kernel_hashes: list = field(default_factory=list)

    @property
    def value(self) -> float:
        return float(self.values[0])

    @property
    def is_zero_variance(self) -> bool:
        """Whether every sample took (up to float32 rounding) the same value."""
        scale = float(np.nanmax(np.abs(self.values))) if self.values.size else 0.0
        return bool(np.isfinite(self.sample_variance)
                    and self.sample_variance <= (8 * 2.0 ** -24 * scale) ** 2)
