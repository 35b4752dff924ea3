"""The integrator kind of the validator: ``mi.Integrator``, its topics table, its statistical
tests, its loading (the integrator rebuilt per scene at the scene's depth: :mod:`.setup`) and
:func:`validate_integrator`.

The statistical tests of an integrator are its bias scenes that apply, the two slopes of
``convergence``, the block tests of ``agreement`` and the ``gradient`` comparison; ``finite``
is exact and ``cost`` informational.
"""

from __future__ import annotations

from ...settings import Loaded
from ...verdict import Report
from .. import core
from ..inputs import check_topics
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


#: The integrator kind: what :mod:`phonglab.validate.core` runs (its plugin is a
#: :class:`~.setup.Target`, built by :func:`prepare`).
INTEGRATOR = core.Kind(name="integrator", word="integrator", class_name="Integrator",
                       register="mi.register_integrator", topics=TOPICS, options=options,
                       statistical_tests=statistical_tests, runners=runners,
                       informational=("cost",))


def prepare(spec, *, variant=None, params=None, plugins=()) -> Loaded:
    """Load the integrator (:func:`phonglab.validate.core.prepare`) and build its
    :class:`~.setup.Target`."""
    loaded = core.prepare(INTEGRATOR, spec, variant=variant, params=params, plugins=plugins)
    target = setup_.build(loaded, spec, params)
    meta = {**(loaded.spec or {}), "depth": target.depth_note}
    return Loaded(target, loaded.label, meta)


def validate_integrator(spec, *, variant=None, params=None, topics=None, seed=0, quick=False,
                        known=None, plugins=(), family=1, sizes=None) -> Report:
    """Validate one integrator on every topic (or ``topics``); see :mod:`phonglab.validate`.

    ``spec``: a plugin type name, a dict for ``mi.load_dict``, an XML file holding one
    ``<integrator>``, or a loaded ``mi.Integrator`` (the last two are run as they are: they
    cannot be rebuilt at the scenes' depths).  ``known``, ``plugins``, ``family``, ``sizes``:
    as for :func:`phonglab.validate.bsdf.kind.validate_bsdf`.  Bad input raises
    :class:`~phonglab.validate.inputs.ValidateError` with one sentence.
    """
    topics = check_topics(topics, TOPICS)
    target = prepare(spec, variant=variant, params=params, plugins=plugins)
    return core.run(INTEGRATOR, target, topics=topics, seed=seed, quick=quick, known=known,
                    family=family, sizes=sizes)


is_integrator = setup_.is_integrator
