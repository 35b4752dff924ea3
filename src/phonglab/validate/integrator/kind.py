"""The parts of the integrator kind (:data:`phonglab.validate.integrator.KIND`): its statistical
tests, its runners, its loading (the integrator rebuilt per scene at the scene's depth:
:mod:`.setup`; the return of a Python ``sample()`` checked first, :func:`check_returns`); the
package face :mod:`phonglab.validate` gives it ``validate_integrator``.

The statistical tests of an integrator are its bias scenes that apply, the two slopes of
``convergence``, the block tests of ``agreement`` and the ``gradient`` comparison; ``finite``
is exact and ``cost`` informational.

One return is misread rather than refused (:mod:`phonglab.validate.returns`): an integrator
whose ``sample()`` returns a bare ``mi.Spectrum`` instead of ``(L, valid, aovs)`` has its three
channels unpacked as the tuple, and the process aborts inside Dr.Jit ("Referenced an unknown
variable", exit 134) with no report.  Its return is therefore first checked in Python to be a
sequence of three.
"""

from __future__ import annotations

import mitsuba as mi

from ...settings import Loaded, load_plugin
from ..conformance import known_of
from . import agreement as agreement_
from . import analytic
from . import gradient as gradient_
from . import ranges, setup as setup_
from ..returns import call, checked, defines, refuse, sequence
from .config import options
from .cost import cost


def statistical_tests(target, opts, topics) -> int:
    """m: the applicable bias scenes, 2 convergence slopes, the agreement blocks, 1 gradient,
    and 2 for a measured depth (:func:`.analytic.measure_depth`: its scenes are counted at the
    best-fitting depth, and stay counted when :func:`.analytic.settle_depth` finds that it
    matches none -- the tests were planned before the verdict, so the level is still α)."""
    analytic.measure_depth(target, opts)       # an undeclared depth: measured before m is counted
    m = 2 if target.measurement is not None else 0
    if "bias" in topics:
        m += sum(1 for _, integ, _ in analytic.bias_scenes(target, opts) if integ is not None)
    if "convergence" in topics and analytic.convergence_applies(target, opts)[0] is not None:
        m += 2
    if "agreement" in topics and agreement_.depth_of(target)[0] is not None:
        m += agreement_.blocks(opts)
    if "gradient" in topics and not gradient_.applies(target):
        m += 1
    return max(m, 1)


def runners(target, opts, topics, m: int) -> dict:
    analytic.settle_depth(target, m)
    return {
        "finite": lambda: analytic.finite(target, opts),
        "bias": lambda: analytic.bias(target, opts, m),
        "convergence": lambda: analytic.convergence(target, opts, m),
        "agreement": lambda: agreement_.agreement(target, opts, m),
        "gradient": lambda: gradient_.gradient(target, opts, m),
        "cost": lambda: cost(target, opts),
    }



#: The sweep's parameters, the ranges a ``--set`` must lie in and the values a documented
#: cause's ``at`` is held against.
parameters = ranges.parameters
domain = ranges.domain
values = ranges.values


def check_returns(plugin, name: str = "integrator") -> None:
    """A Python ``SamplingIntegrator.sample()`` returns three things, ``(L, valid, aovs)``,
    that Mitsuba casts to (Spectrum, Bool, list of Float); L may be any 3-vector or number."""
    if not isinstance(plugin, mi.SamplingIntegrator) or not defines(plugin, "sample"):
        return
    scene = mi.load_dict({"type": "scene", "shape": {"type": "sphere"},
                          "light": {"type": "constant"}})
    sampler = mi.load_dict({"type": "independent"})
    sampler.seed(0, 1)
    ray = mi.RayDifferential3f(mi.Point3f(0, 0, -4), mi.Vector3f(0, 0, 1))
    args = (scene, sampler, ray, None, mi.Bool(True))
    expects = ("a tuple (L: the radiance, a mi.Spectrum, mi.Color3f or mi.Vector3f; valid: "
               "mi.Bool; aovs: a list of mi.Float, one per aov_names()), e.g. return L, valid, []")
    ok, out = call(plugin.sample, *args)
    if not ok:
        return
    if not sequence(out, 3):
        refuse("integrator", name, "sample", out, expects)
    sampler.seed(0, 1)
    checked(setup_.view(plugin), "integrator", name, "sample", args, expects)


def load(spec, params, hint) -> Loaded:
    """Load the integrator (:func:`phonglab.settings.load_plugin`) and build its
    :class:`~.setup.Target`."""
    loaded = load_plugin(spec, params, kind=mi.Integrator, word="integrator", hint=hint)
    check_returns(loaded.plugin, loaded.label)   # before any render: a wrong tuple aborts
    target = setup_.build(loaded, spec, params)
    meta = {**(loaded.spec or {}), "depth": target.depth_note}
    return Loaded(target, loaded.label, meta)



def known_for(name: str, params: dict | None) -> dict:
    """The conformance table's findings of the Mitsuba built-in integrator ``name``."""
    return known_of(catalogue().cases(), name)


def catalogue():
    """The integrator conformance table (:mod:`.builtins`)."""
    from .builtins import CATALOGUE
    return CATALOGUE
