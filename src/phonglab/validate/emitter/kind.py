"""The emitter kind of the validator: ``mi.Emitter``, its topics table, its statistical tests,
its loading (an area emitter attached to a shape, an environment placed in a scene:
:mod:`.setup`) and :func:`validate_emitter`.

The statistical tests of an emitter are its χ² reference points (non-delta emitters) and the
Monte Carlo estimate of its power from ``sample_ray``; the other topics are identities at
float32 round-off, or informational (``cost``).
"""

from __future__ import annotations

import mitsuba as mi

from ...settings import Loaded
from ...verdict import Report
from .. import core
from ..inputs import ValidateError, check_topics
from . import setup as setup_
from .config import options
from .cost import cost
from .gradient import gradient
from .identities import finite, pdf, weight
from .power import power
from .sampling import chi2
from .topics import TOPICS


def statistical_tests(target, opts, topics) -> int:
    """m: χ² reference points (non-delta emitters) and the power estimate."""
    m = 0
    if "chi2" in topics and not target.delta:
        m += sum(g.chi2 for g in setup_.ref_groups(target, 1, opts.seed))
    if "power" in topics:
        m += 1
    return max(m, 1)


def runners(target, opts, topics, m: int) -> dict:
    return {
        "finite": lambda: finite(target, opts),
        "weight": lambda: weight(target, opts),
        "pdf": lambda: pdf(target, opts),
        "chi2": lambda: chi2(target, opts, m),
        "power": lambda: power(target, opts, m),
        "gradient": lambda: gradient(target, opts),
        "cost": lambda: cost(target, opts),
    }


#: The emitter kind: what :mod:`phonglab.validate.core` runs (its plugin is a
#: :class:`~.setup.Setup`, built by :func:`prepare`).
EMITTER = core.Kind(name="emitter", word="emitter", class_name="Emitter",
                    register="mi.register_emitter", topics=TOPICS, options=options,
                    statistical_tests=statistical_tests, runners=runners)


def prepare(spec, *, variant=None, params=None, plugins=(), shape=None) -> Loaded:
    """Load the emitter (:func:`phonglab.validate.core.prepare`) and build its
    :class:`~.setup.Setup`; ``shape`` (or ``params["shape"]``, from ``--set shape.type=...``)
    is the shape a surface emitter loaded alone is attached to."""
    params = dict(params or {})
    if "shape" in params:
        if shape is not None:
            raise ValidateError("give the shape once: as shape= or as --set shape.*")
        shape = params.pop("shape")
        if not isinstance(shape, dict) or "type" not in shape:
            raise ValidateError("--set shape.* needs shape.type (e.g. --set shape.type=sphere)")
    loaded = core.prepare(EMITTER, spec, variant=variant, params=params or None,
                          plugins=plugins)
    target = setup_.build(loaded.plugin, shape)
    spec_meta = loaded.spec
    if shape is not None:
        spec_meta = {**(spec_meta or {}), "shape": shape}
    elif target.shape is not None:
        spec_meta = {**(spec_meta or {}), "shape": target.shape_name}
    return Loaded(target, loaded.label, spec_meta)


def validate_emitter(spec, *, variant=None, params=None, topics=None, seed=0, quick=False,
                     known=None, plugins=(), family=1, sizes=None, shape=None) -> Report:
    """Validate one emitter on every topic (or ``topics``); see :mod:`phonglab.validate`.

    ``spec``: a plugin type name, a dict for ``mi.load_dict``, an XML file holding one
    ``<emitter>``, or a loaded ``mi.Emitter`` (an area emitter may come attached to its shape);
    ``shape``: a shape dict a surface emitter without one is attached to (default
    :data:`~.setup.DEFAULT_SHAPE`).  ``known``, ``plugins``, ``family``, ``sizes``: as for
    :func:`phonglab.validate.bsdf.kind.validate_bsdf`.  Bad input raises
    :class:`~phonglab.validate.inputs.ValidateError` with one sentence.
    """
    topics = check_topics(topics, TOPICS)
    target = prepare(spec, variant=variant, params=params, plugins=plugins, shape=shape)
    return core.run(EMITTER, target, topics=topics, seed=seed, quick=quick, known=known,
                    family=family, sizes=sizes)


def is_emitter(spec) -> bool:
    """Whether ``spec`` names an emitter plugin (:func:`phonglab.validate.core.names_plugin`)."""
    return core.names_plugin(spec, mi.Emitter, mi.ObjectType.Emitter, "emitter")

