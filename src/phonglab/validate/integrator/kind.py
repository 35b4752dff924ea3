"""The parts of the integrator kind (:data:`phonglab.validate.integrator.KIND`): its statistical
tests, its runners, its loading (the integrator rebuilt per scene at the scene's depth: :mod:`.setup`) and
:func:`validate_integrator`.

The statistical tests of an integrator are its bias scenes that apply, the two slopes of
``convergence``, the block tests of ``agreement`` and the ``gradient`` comparison; ``finite``
is exact and ``cost`` informational.
"""

from __future__ import annotations

import mitsuba as mi

from ...settings import Loaded, load_plugin
from ...verdict import Report
from .. import core
from ..conformance import known_of
from ..inputs import check_topics
from ..sweep import validate as sweep_validate
from . import KIND
from . import agreement as agreement_
from . import analytic
from . import gradient as gradient_
from . import setup as setup_
from .config import options
from .cost import cost
from .topics import TOPICS


def statistical_tests(target, opts, topics) -> int:
    """m: the applicable bias scenes, 2 convergence slopes, the agreement blocks, 1 gradient."""
    m = 0
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
    return {
        "finite": lambda: analytic.finite(target, opts),
        "bias": lambda: analytic.bias(target, opts, m),
        "convergence": lambda: analytic.convergence(target, opts, m),
        "agreement": lambda: agreement_.agreement(target, opts, m),
        "gradient": lambda: gradient_.gradient(target, opts, m),
        "cost": lambda: cost(target, opts),
    }


#: The integrator kind (declared by the package, whose parts this module holds).
INTEGRATOR = KIND


def load(spec, params, hint) -> Loaded:
    """Load the integrator (:func:`phonglab.settings.load_plugin`) and build its
    :class:`~.setup.Target`."""
    loaded = load_plugin(spec, params, kind=mi.Integrator, word="integrator", hint=hint)
    target = setup_.build(loaded, spec, params)
    meta = {**(loaded.spec or {}), "depth": target.depth_note}
    return Loaded(target, loaded.label, meta)


def prepare(spec, *, variant=None, params=None, plugins=()) -> Loaded:
    """Set the variant, run the plugin files, load the integrator
    (:func:`phonglab.validate.core.prepare`)."""
    return core.prepare(INTEGRATOR, spec, variant=variant, params=params, plugins=plugins)


def known_for(name: str, params: dict | None) -> dict:
    """The conformance table's findings of the Mitsuba built-in integrator ``name``."""
    return known_of(catalogue().cases(), name)


def catalogue():
    """The integrator conformance table (:mod:`.builtins`)."""
    from .builtins import CATALOGUE
    return CATALOGUE


def validate_integrator(spec, *, variant=None, params=None, topics=None, seed=0, quick=False,
                        known=None, plugins=(), family=1, sizes=None, sweep=False,
                        runner=None) -> Report:
    """Validate one integrator on every topic (or ``topics``); see :mod:`phonglab.validate`.

    ``spec``: a plugin type name, a dict for ``mi.load_dict``, an XML file holding one
    ``<integrator>``, or a loaded ``mi.Integrator`` (the last two are run as they are: they
    cannot be rebuilt at the scenes' depths).  ``known``, ``plugins``, ``family``, ``sizes``:
    ``sweep``, ``runner``: as for :func:`phonglab.validate.bsdf.kind.validate_bsdf`.  Bad input
    raises :class:`~phonglab.validate.inputs.ValidateError` with one sentence.
    """
    if sweep:
        return sweep_validate(INTEGRATOR, spec, variant=variant, params=params, topics=topics,
                              seed=seed, quick=quick, known=known, plugins=plugins,
                              family=family, sizes=sizes, runner=runner)
    topics = check_topics(topics, TOPICS)
    target = prepare(spec, variant=variant, params=params, plugins=plugins)
    return core.run(INTEGRATOR, target, topics=topics, seed=seed, quick=quick, known=known,
                    family=family, sizes=sizes)

