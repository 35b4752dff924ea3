"""Fixtures only: Mitsuba variants (phonglab's plugins registered in each) and paths.

The default variant is llvm_ad_rgb.  A machine where it cannot run does not skip
the suite: ``test_registration.py::test_llvm_variant_is_usable`` fails loudly and
the other tests run in the scalar fallback.  The significance level and the Šidák
correction the statistical tests use come from :mod:`phonglab.stats` (``ALPHA``, ``sidak``),
the same as the checks and the bench.
"""

from __future__ import annotations

import os
import signal
from pathlib import Path

import pytest

os.environ.setdefault("MPLBACKEND", "Agg")

import phonglab  # noqa: E402
from phonglab import runtime  # noqa: E402
from phonglab.engine.scenes import SCENES_DIR  # noqa: E402


@pytest.fixture
def variant_llvm_rgb():
    return phonglab.register("llvm_ad_rgb" if runtime.configure().usable else "scalar_rgb")


@pytest.fixture
def variant_scalar_rgb():
    return phonglab.register("scalar_rgb")


@pytest.fixture(params=["llvm_ad_rgb", "llvm_ad_mono", "llvm_ad_spectral", "scalar_rgb"])
def any_variant(request):
    """Every variant the plugins promise to work in (llvm_* need a usable libLLVM)."""
    v = request.param
    if v.startswith("llvm") and not runtime.configure().usable:
        pytest.fail(f"{v} needs a usable libLLVM: {runtime.configure().reason}")
    return phonglab.register(v)


#: pytest-xdist's worker processes share the cores (PYTEST_XDIST_WORKER_COUNT, set by xdist)
SHARED_CORES = int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1")) > 1


@pytest.fixture(autouse=True)
def kernel_threads_in_the_background():
    """Where xdist's workers share the cores, each worker's Dr.Jit kernel threads run in the
    background (runtime.background_kernel_threads: their spin between kernels would take a
    core from another worker's tests), as in phonglab's own worker processes."""
    if SHARED_CORES:
        runtime.background_kernel_threads()


@pytest.fixture(autouse=True)
def sigint_left_as_found():
    """Every test leaves the SIGINT handler as it found it: phonglab routes Ctrl-C only while
    Python's own handler is installed (runtime.interrupts_routed), so a test that leaves
    SIG_IGN behind silently turns the routing off for every later test of its xdist worker
    (seen once: test_interrupts' routing test found SIG_IGN)."""
    before = signal.getsignal(signal.SIGINT)
    yield
    after = signal.getsignal(signal.SIGINT)
    assert after is before, f"the test left SIGINT's handler {after!r} (it found {before!r})"


@pytest.fixture(scope="session")
def scenes_dir() -> Path:
    return SCENES_DIR


#: Tests moved to the slow tier (``.ci/run`` runs them after ``make test`` while its budget
#: lasts), each with why: every one took ≥ 3 s of a warm default-tier run on 2 cores
#: (2026-12-04) and has a cheaper sibling left in the default tier that guards the same code.
SLOW_TIER: dict[str, str] = {
    "test_fuzz_plugins.py::test_fuzz_plugins_that_exit_or_hang":
        "hypothesis over exit/hang x every method x four commands (12 s); each case stays as a "
        "deterministic test in test_plugin_exits.py",
    "test_plugin_exits.py::test_check_and_fit_take_a_timeout[eval-check]":
        "check waits out its timeout on every check (8 s); fit's variant stays",
    "test_validate_normalization_mixture.py::test_mixture_passes_and_integrates_to_the_independent_value_quick[0.5-1000.0]":
        "a middle weight (4 s); the extreme weights 1e-4 and 1 - 1e-4 stay",
    "test_validate_normalization_mixture.py::test_mixture_passes_and_integrates_to_the_independent_value_quick[0.5-10000.0]":
        "a middle weight (3 s); the extreme weights stay",
    "test_validate_normalization_mixture.py::test_mixture_passes_and_integrates_to_the_independent_value_quick[0.9999-1000.0]":
        "p = 1e3 (4.5 s); the same weight at p = 1e4 stays",
    "test_validate_normalization_mixture.py::test_mixture_passes_and_integrates_to_the_independent_value_quick[0.0001-1000.0]":
        "p = 1e3 (3.3 s); the same weight at p = 1e4 stays",
    "test_corpus.py::test_a_defect_fails_on_its_topic_with_a_measured_row[while_loop_sampler_missing]":
        "an integrator's bias rows over several depths (7 s); the other corpus integrators stay",
    "test_validate_chi2.py::test_roughdielectric_at_nearly_equal_iors_passes_chi2":
        "roughdielectric's chi2 at eta near 1 at default sizes (6 s)",
    "test_validate_sweep.py::test_a_defect_at_a_parameter_edge_fails_there_and_passes_elsewhere":
        "two planted edge defects swept at default sizes (8-17 s); the sweep's points and "
        "its emitter sweep stay in the default tier",
    "test_whitted.py::test_graphics_and_radiance_units_launch_the_same_kernels_without_recompiling":
        "kernel-count check over a full scene (14 s); exponent_series already slow",
    "test_whitted.py::test_scenes_render_with_whitted_and_path[glass_sphere]":
        "glass_sphere renders (8 s); the other scenes stay",
    "test_validate_integrator.py::test_cli_detects_an_integrator_and_fails_a_defect":
        "CLI integrator run (12 s); the defect matrix below stays for the cheap defects",
    "test_validate_integrator.py::test_defect_fails_its_topic_only[nan_grazing]":
        "12 s; the other planted integrator defects stay",
    "test_validate_integrator.py::test_defect_fails_its_topic_only[path_control]":
        "a control at full quick size (9 s); path passes in test_builtins_pass elsewhere",
    "test_parallel.py::test_cluster_results_identical_to_serial":
        "starts a Dask LocalCluster (18 s); the serial/parallel equality of a sweep stays",
    "test_fit_render.py::test_recovers_a_known_phong_from_its_render":
        "an AD render fit (7 s); the BSDF-level fit tests stay",
    "test_checks_catch_bugs.py::test_sampling_inconsistent_with_pdf_fails_chi2_and_monte_carlo_rows":
        "7 s; the other planted check bugs stay",
    "test_checks_catch_bugs.py::test_pdf_with_wrong_normalization_fails_chi2_and_monte_carlo_rows":
        "7 s; the other planted check bugs stay",
    "test_notebooks.py::test_notebook_runs[01_radiometry.ipynb]":
        "a notebook (7 s); notebook 06 (plugin authors) stays",
    "test_notebooks.py::test_notebook_runs[02_lambert_and_phong.ipynb]": "a notebook (6 s)",
    "test_notebooks.py::test_notebook_runs[03_refraction.ipynb]": "a notebook (4 s)",
    "test_convergence.py::test_render_rmse_falls_as_inverse_sqrt_spp":
        "render convergence slopes (6-7 s each); the estimator convergence tests stay",
    "test_fuzz_content.py::test_bitmap_textures_load_as_mitsuba_decodes_them":
        "bitmap decoding against Mitsuba's per texture slot (4-7 s each)",
    "test_planner.py::test_plans_price_the_stratified_sampler_and_its_render_meets_the_target":
        "a planned render to its target (6 s); the plan-only tests stay",
    "test_planner.py::test_a_planned_render_reuses_the_pilot_and_reaches_the_target":
        "a planned render to its target (5 s)",
    "test_planner.py::test_one_kernel_pilot_measures_what_per_depth_renders_measure":
        "per-depth renders (5 s)",
    "test_planner.py::test_achieved_error_is_near_the_target": "planned renders per scene",
    "test_scenes.py::test_scene_loads_and_renders[glass_sphere]": "glass_sphere (6 s)",
    "test_validate_defects.py::test_pdf_scaled_1pct_fails_normalization_alone_at_default_sizes":
        "default sizes (5 s); every defect still runs at --quick",
    "test_validate_emitter.py::test_builtin_emitters_pass_quick_spectral":
        "spectral repeats of the built-in emitter cases; the RGB ones stay",
    "test_validate_emitter.py::test_builtin_emitters_pass_quick[area (cube)]":
        "a mesh area light (6 s); the rectangle, disk and sphere stay",
    "test_checks_catch_bugs.py::test_dropping_inv_pi_fails_reflection_scene_constancy_and_sanity_rows":
        "4 s; test_checks' rows keep the reflection scene",
    "test_validate_chi2.py::test_narrow_lobes_pass_chi2_at_default_size":
        "default sizes; the quick narrow-lobe tests stay",
    "test_adaptive.py::test_bench_part_writes_chart_speedups_and_report":
        "the adaptive bench part at test size (21 s, the default tier's longest test); `make "
        "bench` runs it in full and test_bench's CLI test keeps the bench's plumbing",
    "test_validate_emitter.py::test_builtin_emitters_pass_quick[area (sphere, flip_normals)]":
        "an inward sphere light (6 s); test_sphere_inside_finding keeps flip_normals",
    "test_validate_emitter.py::test_sunsky_without_sky_fails_chi2_by_the_suns_float32_cone_only_there":
        "two χ² runs at 10⁶ samples (the finding shows only at default sizes, ~15 s)",
    "test_validate.py::test_cli_pass_json_and_html":
        "a passing CLI run with JSON and HTML (3.5 s); the failing CLI run with its figure stays",
}


def pytest_collection_modifyitems(config, items):
    """Mark the :data:`SLOW_TIER` tests slow (a key without ``[...]`` takes every parameter)."""
    for item in items:
        node = item.nodeid.split("/")[-1]
        if node in SLOW_TIER or node.split("[")[0] in SLOW_TIER:
            item.add_marker(pytest.mark.slow)
