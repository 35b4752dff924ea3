"""Property-based fuzzing of every numeric parameter of lambert, phong and whitted.

Values: finite, huge, tiny, denormal, NaN, ±Inf, negative and zero numbers, and RGB colours
of them, given at load (``mi.load_dict``) or written through ``mi.traverse`` + ``update()``.
The property: either a :class:`MaterialError` whose message is one line naming a given
parameter (and, on update, the parameter keeps its previous value), or a render of a tiny
scene (8 x 8, 1 spp, llvm_ad_rgb) that is finite and non-negative everywhere.

The default suite runs a bounded, derandomized search (reproducible in CI); the ``slow``
variants search a few hundred examples each.

Plugin files that do not return: a correct Lambertian that calls ``sys.exit(0)``,
``sys.exit(3)`` or ``os._exit(0)``, or loops forever, at import, in its constructor, in
``traverse`` or in any query method, given to ``validate``, ``check``, ``fit`` (each with
``--timeout``) or :func:`phonglab.testing.assert_bsdf_valid`.  The property: when the command
reached the plugin's act (a marker file says so) there is a verdict -- failing rows (exit 1) or
one sentence (exit 2), an AssertionError or ValidateError from the helper -- never exit 0, a
traceback, the end of the process or a hang (``os._exit`` raises in these tests and a
watchdog bounds each example: :mod:`helpers`).
"""

from __future__ import annotations

import math

import mitsuba as mi
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from phonglab.plugins._common import MaterialError
from phonglab.testing import assert_bsdf_valid
from phonglab.validate.inputs import ValidateError

from helpers import (PLUGIN_ACTIONS, PLUGIN_PLACES, acting_plugin, assert_no_green,
                     refuse_process_exit, run_cli, watchdog)
from test_plugin_hardening import material_message, tiny_scene

FAST = settings(max_examples=25, deadline=None, derandomize=True, database=None,
                suppress_health_check=[HealthCheck.too_slow])
LONG = settings(FAST, max_examples=300)
settings.register_profile("plugins-fuzz", FAST)
settings.register_profile("plugins-fuzz-long", LONG)

TINY32 = float(np.finfo(np.float32).tiny)
MAX32 = float(np.finfo(np.float32).max)
SPECIAL = [0.0, -0.0, 1e-45, -1e-45, 1e-40, TINY32, 1e-30, 1e-7, 0.5, 1.0, 1.0001, 2.0, 30.0,
           1e5, 1e30, MAX32, 1e39, 1e300, -1e-30, -0.5, -1.0, -1e30,
           math.nan, math.inf, -math.inf]
NUMBERS = st.one_of(st.sampled_from(SPECIAL), st.floats(), st.floats(-2.0, 2.0))
COLOURS = st.lists(NUMBERS, min_size=3, max_size=3).map(lambda v: {"type": "rgb", "value": v})
VALUES = st.one_of(NUMBERS, COLOURS)
DEPTHS = st.one_of(st.integers(-3, 12), NUMBERS)

# Every numeric parameter at load: plugin -> {name: strategy}.
LOAD = {
    "lambert": {"reflectance": VALUES},
    "phong": {"diffuse_reflectance": VALUES, "specular_reflectance": VALUES,
              "exponent": NUMBERS},
    "whitted": {"attenuation_constant": NUMBERS, "attenuation_linear": NUMBERS,
                "attenuation_quadratic": NUMBERS, "ambient": VALUES,
                "ambient_reflectance_mat": VALUES, "max_depth": DEPTHS},
}
# Every parameter mi.traverse exposes: plugin -> {key suffix: (parameter name, strategy)}.
UPDATE = {
    "lambert": {"reflectance.value": ("reflectance", NUMBERS)},
    "phong": {"diffuse_reflectance.value": ("diffuse_reflectance", NUMBERS),
              "specular_reflectance.value": ("specular_reflectance", NUMBERS),
              "exponent": ("exponent", NUMBERS)},
    "whitted": {"attenuation_constant": ("attenuation_constant", NUMBERS),
                "attenuation_linear": ("attenuation_linear", NUMBERS),
                "attenuation_quadratic": ("attenuation_quadratic", NUMBERS),
                "ambient.value": ("ambient", NUMBERS)},
}
WHITTED = {"type": "whitted", "max_depth": 2, "ambient": 0.1}


@pytest.fixture(autouse=True)
def _rgb(variant_llvm_rgb):
    return variant_llvm_rgb


def scene_dict(plugin: str, values: dict) -> dict:
    """The tiny scene (8 x 8, 1 spp) with ``values`` set on ``plugin``."""
    if plugin == "whitted":
        return tiny_scene({"type": "phong"}, {**WHITTED, **values}, res=8, spp=1)
    return tiny_scene({"type": plugin, **values}, res=8, spp=1)


def assert_one_sentence_naming(message: str | None, names, error) -> None:
    assert message is not None, f"not a MaterialError: {error!r}"
    # One line, as the command line prints it (the project's "one sentence").
    assert "\n" not in message, message
    assert message.endswith("."), message
    assert any(name in message for name in names), f"names none of {names}: {message}"


def assert_renders_finite_non_negative(scene) -> None:
    image = np.array(mi.render(scene, seed=1), dtype=np.float64)
    assert np.all(np.isfinite(image)), "NaN or Inf pixels"
    assert np.all(image >= 0), "negative pixels"


def _load_case(plugin: str, values: dict) -> None:
    try:
        scene = mi.load_dict(scene_dict(plugin, values))
    except Exception as exc:   # Mitsuba's loader wraps the plugin's error in a RuntimeError
        assert_one_sentence_naming(material_message(exc), list(values), exc)
        return
    assert_renders_finite_non_negative(scene)


def _update_case(plugin: str, suffix: str, value: float) -> None:
    name, _ = UPDATE[plugin][suffix]
    scene = mi.load_dict(scene_dict(plugin, {}))
    params = mi.traverse(scene)
    (key,) = [k for k in params.keys() if k.endswith(suffix)
              and (plugin == "whitted") == k.startswith("integrator.")]
    previous = np.array(params[key]).copy()
    params[key] = value
    try:
        params.update()
    except MaterialError as exc:
        assert_one_sentence_naming(str(exc), [name], exc)
        np.testing.assert_array_equal(np.array(params[key]), previous)
    assert_renders_finite_non_negative(scene)


def load_cases():
    return st.sampled_from(sorted(LOAD)).flatmap(
        lambda plugin: st.fixed_dictionaries({}, optional=LOAD[plugin]).filter(bool).map(
            lambda values: (plugin, values)))


def update_cases():
    return st.sampled_from([(p, s) for p in sorted(UPDATE) for s in UPDATE[p]]).flatmap(
        lambda ps: UPDATE[ps[0]][ps[1]][1].map(lambda v: (ps[0], ps[1], v)))


@FAST
@given(case=load_cases())
def test_fuzz_load(case):
    _load_case(*case)


@FAST
@given(case=update_cases())
def test_fuzz_update(case):
    _update_case(*case)


@pytest.mark.slow
@LONG
@given(case=load_cases())
def test_fuzz_load_long(case):
    _load_case(*case)


@pytest.mark.slow
@LONG
@given(case=update_cases())
def test_fuzz_update_long(case):
    _update_case(*case)


# --- plugin files that exit or hang, at import or in any method -------------------------------

#: How each entry point is asked about the plugin NAME in FILE, cheaply, with a 1 s limit.
COMMANDS = {
    "validate": ["validate", "{name}", "--plugin", "{file}", "--quick", "--no-sweep", "--only",
                 "finite", "--only", "weight", "--timeout", "1"],
    "check": ["check", "--lambert", "{name}", "--plugin", "{file}", "--only", "sanity",
              "--spp", "8", "--no-progress", "--timeout", "1"],
    "fit": ["fit", "{name}", "--plugin", "{file}", "--model", "lambert", "--maxiter", "2",
            "--timeout", "1"],
    "assert_bsdf_valid": None,
}
EXITS = settings(deadline=None, derandomize=True, database=None,
                 suppress_health_check=[HealthCheck.function_scoped_fixture,
                                        HealthCheck.too_slow])


def _acting_case(folder, place, action, command, n) -> None:
    marker = folder / f"reached{n}"
    plugin = acting_plugin(folder, place, action, name=f"act{n}_{place.strip('_')}_{action}",
                           marker=marker)
    if command == "assert_bsdf_valid":
        try:
            with watchdog(60):
                assert_bsdf_valid(plugin.stem, plugins=[plugin], sweep=False, quick=True,
                                  topics=["finite", "weight"], timeout=1)
        except (AssertionError, ValidateError) as exc:
            assert "Traceback" not in str(exc)
            return
        assert not marker.exists(), f"{place}/{action}: the helper passed a plugin that acted"
        return
    argv = [a.replace("{name}", plugin.stem).replace("{file}", str(plugin))
            for a in COMMANDS[command]]
    rc, out, err = run_cli(argv, seconds=90)
    if marker.exists():
        assert_no_green(rc, err)
    else:           # never reached (fit never calls traverse, say): any honest outcome
        assert rc in (0, 1, 2, 3) and "Traceback" not in err, (rc, err[-2000:])


_counter = iter(range(10**9))


@settings(EXITS, max_examples=10)
@given(place=st.sampled_from(PLUGIN_PLACES), action=st.sampled_from(sorted(PLUGIN_ACTIONS)),
       command=st.sampled_from(sorted(COMMANDS)))
def test_fuzz_plugins_that_exit_or_hang(tmp_path_factory, monkeypatch, place, action, command):
    refuse_process_exit(monkeypatch)
    _acting_case(tmp_path_factory.mktemp("acts"), place, action, command, next(_counter))


@pytest.mark.slow
@settings(EXITS, max_examples=80)
@given(place=st.sampled_from(PLUGIN_PLACES), action=st.sampled_from(sorted(PLUGIN_ACTIONS)),
       command=st.sampled_from(sorted(COMMANDS)))
def test_fuzz_plugins_that_exit_or_hang_long(tmp_path_factory, monkeypatch, place, action,
                                             command):
    refuse_process_exit(monkeypatch)
    _acting_case(tmp_path_factory.mktemp("acts"), place, action, command, next(_counter))
