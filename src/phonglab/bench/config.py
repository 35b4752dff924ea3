"""Sizes, constants and CSV layouts of a bench run.

:class:`Config` holds the sizes that differ between a full run and ``--quick``; the rest
(the estimator problems, the stability grid, the verdict thresholds, the render-time
comparisons) is the same for both.  :data:`LOGS` names every CSV file the sweeps write,
its columns and the columns that identify a row (what a resumed run skips).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..physics.estimators import METHODS, Problem

DEFAULT_OUT = Path("out") / "bench"
#: The parts of a run, in the order they run (``phonglab bench --only``).
PARTS = ("estimators", "stability", "renders", "variants", "ratios", "jit", "adaptive")
#: The variant every sweep but the variant comparison renders and estimates in.
VARIANT = "llvm_ad_rgb"

#: Relative RMSE at the stability budget past which an estimator "breaks down".
BREAKDOWN_REL_RMSE = 0.10
#: Per-sample relative standard deviation below which a strategy counts as near-zero-variance.
NEAR_ZERO_REL_SD = 0.05
#: Smallest relative bias that counts as a failure when it is statistically significant.
BIAS_FLOOR = 0.01
STABILITY_N = 1 << 14
STABILITY_EXPONENTS = (0.0, 1.0, 10.0, 100.0, 1e3, 1e4, 1e5)
STABILITY_ANGLES = (0.0, 30.0, 60.0, 80.0, 89.0, 89.9)
STABILITY_LIGHTS = {"constant": dict(light="constant"), "disk 1deg": dict(light="disk", half_angle=1.0)}
#: Cells of the stability map (the Šidák family of its bias tests).
STABILITY_CELLS = len(STABILITY_LIGHTS) * len(METHODS) * len(STABILITY_EXPONENTS) * len(STABILITY_ANGLES)

#: The two estimator problems of the error-versus-time charts.
ESTIMATOR_SCENES = {
    "env p=100": Problem(bsdf="phong", diffuse_reflectance=0.5, specular_reflectance=0.3,
                         exponent=100.0, theta_i=30.0, light="constant"),
    "disk3 p=100": Problem(bsdf="phong", diffuse_reflectance=0.5, specular_reflectance=0.3,
                           exponent=100.0, theta_i=30.0, light="disk", half_angle=3.0),
}

#: (comparison, A, B, what is swapped) of the render-time ratios.
RATIO_COMPARISONS = (
    ("lambert/diffuse", "lambert", "diffuse", "all surfaces"),
    ("phong/plastic", "phong", "plastic", "boxes (walls diffuse)"),
    ("phong/roughplastic", "phong", "roughplastic", "boxes (walls diffuse)"),
)
#: Render-time targets: comparison → largest acceptable median ratio.
RATIO_TARGETS = {"lambert/diffuse": 1.05, "phong/plastic": 1.25}
#: whitted graphics/radiance units: the scene, spp and the target (largest median ratio).
WHITTED_SCENES = ("exponent_series", "attenuation_demo")
WHITTED_SPP = 16
WHITTED_TARGET = 1.1
RATIO_RES = 64
VARIANT_RES = 16
RENDER_RES = 32

RESULT_FIELDS = ["group", "method", "scene", "variant", "samples", "seeds", "wall_time_s",
                 "first_call_s", "rmse", "rel_mse", "var_n", "nan_count", "reference"]
STABILITY_FIELDS = ["light", "method", "exponent", "theta_i", "samples", "seeds", "exact", "mean",
                    "rel_rmse", "rel_stderr", "var_n", "bias_z", "nan_count", "inf_count",
                    "seconds", "verdict", "reason"]
RATIO_FIELDS = ["comparison", "a", "b", "pair", "scene", "variant", "spp", "t_a", "t_b", "ratio"]
COST_FIELDS = ["scene", "method", "round", "samples", "seconds"]
WHITTED_FIELDS = ["scene", "pair", "spp", "t_graphics", "t_radiance", "ratio", "kernels_graphics",
                  "kernels_radiance"]
JIT_FIELDS = ["group", "method", "scene", "variant", "first_call_s", "steady_s", "compile_ms",
              "kernels", "cache_hits", "cold_compile_ms"]

#: name → (file, columns, key columns) of every CSV log of a run.
LOGS = {
    "results": ("results.csv", RESULT_FIELDS, ("group", "method", "scene", "variant", "samples")),
    "stability": ("stability.csv", STABILITY_FIELDS, ("light", "method", "exponent", "theta_i")),
    "ratios": ("ratios.csv", RATIO_FIELDS, ("comparison", "pair")),
    "cost": ("cost.csv", COST_FIELDS, ("scene", "method", "round")),
    "jit": ("jit.csv", JIT_FIELDS, ("group", "method", "scene", "variant")),
    "whitted": ("whitted.csv", WHITTED_FIELDS, ("scene", "pair")),
}


@dataclass(frozen=True)
class Config:
    """Sizes of one bench run (``quick`` keeps it under 3 minutes on 2 cores)."""

    quick: bool = False

    @property
    def estimator_ns(self) -> list[int]:
        return [2 ** k for k in (range(6, 19, 2) if self.quick else range(6, 21))]

    @property
    def estimator_seeds(self) -> int:
        return 16 if self.quick else 32

    @property
    def repeats(self) -> int:
        return 3 if self.quick else 5

    @property
    def cost_rounds(self) -> int:
        return 5 if self.quick else 15

    @property
    def stability_seeds(self) -> int:
        return 8 if self.quick else 16

    @property
    def render_spps(self) -> list[int]:
        return [1, 4, 16, 64] if self.quick else [1, 2, 4, 8, 16, 32, 64, 128, 256]

    @property
    def reference_spp(self) -> int:
        return 2048 if self.quick else 8192

    @property
    def variant_spps(self) -> list[int]:
        return [4, 16] if self.quick else [4, 16, 64]

    @property
    def ratio_pairs(self) -> int:
        return 5 if self.quick else 15

    @property
    def ratio_spp(self) -> int:
        return 64 if self.quick else 256

    # --- adaptive sampling (phonglab.bench.adaptive_sweeps) ---
    @property
    def adaptive_res(self) -> int:
        return 32 if self.quick else 128

    @property
    def adaptive_scenes(self) -> list[str]:
        return (["gray_direct", "check_furnace_enclosure"] if self.quick else
                ["gray_direct", "cornell_phong", "check_furnace_enclosure"])

    @property
    def adaptive_oracle_scenes(self) -> dict[str, tuple[float, dict]]:
        """Scene -> (target E, parameters) of the oracle rows: the planner bench's scenes and
        targets at 128² (scripts/planner_bench.py), and the uniform-variance furnace."""
        if self.quick:
            return {"gray_direct": (0.04, {"res": 32}),
                    "check_furnace_enclosure": (0.04, {"res": 32})}
        return {"gray_direct": (0.005, {"res": 128}), "gray_room": (0.01, {"res": 128}),
                "cornell_phong": (0.02, {"res": 128}), "glass_slab": (0.05, {"res": 128}),
                "nb_sphere_row": (0.005, {"width": 512, "height": 128}),
                "textured_room": (0.02, {"res": 128}), "outdoor_envmap": (0.01, {"res": 128}),
                "check_furnace_enclosure": (0.02, {"res": 32})}

    @property
    def adaptive_planned_targets(self) -> list[float]:
        """Targets of the planned points (a plan runs a pilot: seconds each)."""
        return [0.04] if self.quick else [0.05, 0.02]

    @property
    def adaptive_spps(self) -> list[int]:
        return [16, 64, 256] if self.quick else [16, 32, 64, 128, 256, 512]

    @property
    def adaptive_targets(self) -> list[float]:
        return [0.04, 0.02] if self.quick else [0.05, 0.03, 0.02, 0.012]

    @property
    def adaptive_seeds(self) -> int:
        return 2 if self.quick else 3

    @property
    def adaptive_reference_spp(self) -> int:
        return 4096 if self.quick else 8192
