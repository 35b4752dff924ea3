"""The BSDF kind of the validator: ``mi.BSDF``, its topics table, its statistical tests, and
:func:`validate_bsdf` (the kind-independent runner :mod:`phonglab.validate.core` does the rest).

The statistical tests of a BSDF are the χ² cells and the normalization cells (unless every lobe
is a delta), when it has a delta lobe the energy cells whose albedo is a mean of sample
weights, and when it has a Null lobe the eval_null_transmission cells (a mean Null-sample
weight); the other topics are identities at float32 round-off, or informational (``cost``).
"""

from __future__ import annotations

import mitsuba as mi

from ...verdict import Report
from .. import core
from ..sweep import validate as sweep_validate
from . import lanes, ranges
from .config import options
from .contract import eval_diffuse_reflectance, eval_null_transmission, has_null
from .cost import cost
from .energy import energy
from .gradient import gradient
from .identities import component, eval_pdf, finite, weight_and_pdf
from .normalization import normalization
from .polarization import intensity, mueller, mueller_identities, mueller_reciprocity
from .reciprocity import reciprocity
from .sampling import chi2
from .topics import TOPICS


def statistical_tests(bsdf, opts, topics) -> int:
    """m: the number of statistical tests the run makes (χ² and normalization cells, energy
    cells with delta lobes, eval_null_transmission cells with a Null lobe)."""
    m = 0
    if "chi2" in topics and not lanes.delta_only(bsdf):
        m += len(opts.cells(opts.chi2_cos, opts.chi2_phi))
    if "normalization" in topics and not lanes.delta_only(bsdf):
        m += len(opts.cells(opts.energy_cos))
    if "energy" in topics and lanes.bsdf_has(bsdf, int(mi.BSDFFlags.Delta) |
                                             int(mi.BSDFFlags.Delta1D)):
        m += len(opts.energy_cos)
    if "eval_null_transmission" in topics and has_null(bsdf):
        m += len(opts.cells())
    return max(m, 1)


def runners(bsdf, opts, topics, m: int) -> dict:
    """topic -> the function that makes its rows (``weight`` makes the ``pdf`` rows too when
    both run: they share the samples)."""
    return {
        "finite": lambda: finite(bsdf, opts),
        "eval_pdf": lambda: eval_pdf(bsdf, opts),
        "weight": lambda: weight_and_pdf(bsdf, opts, {"weight", "pdf"} & set(topics)),
        "pdf": lambda: [] if "weight" in topics else weight_and_pdf(bsdf, opts, {"pdf"}),
        "chi2": lambda: chi2(bsdf, opts, m),
        "normalization": lambda: normalization(bsdf, opts, m),
        "energy": lambda: energy(bsdf, opts, m),
        "reciprocity": lambda: reciprocity(bsdf, opts),
        "component": lambda: component(bsdf, opts),
        "eval_null_transmission": lambda: eval_null_transmission(bsdf, opts, m),
        "eval_diffuse_reflectance": lambda: eval_diffuse_reflectance(bsdf, opts),
        "mueller": lambda: mueller(bsdf, opts),
        "intensity": lambda: intensity(bsdf, opts),
        "mueller_identities": lambda: mueller_identities(bsdf, opts),
        "mueller_reciprocity": lambda: mueller_reciprocity(bsdf, opts),
        "gradient": lambda: gradient(bsdf, opts),
        "cost": lambda: cost(bsdf, opts),
    }


#: The BSDF kind: what :mod:`phonglab.validate.core` runs.
BSDF = core.Kind(name="bsdf", word="BSDF", class_name="BSDF", register="mi.register_bsdf",
                 topics=TOPICS, options=options, statistical_tests=statistical_tests,
                 runners=runners, parameters=ranges.parameters, informational=("cost",),
                 values=ranges.traversed)


def validate_bsdf(spec, *, variant=None, params=None, topics=None, seed=0, quick=False,
                  known=None, plugins=(), family=1, sizes=None, sweep=False,
                  runner=None) -> Report:
    """Validate one BSDF on every topic (or ``topics``); see :mod:`phonglab.validate`.

    ``spec``: a plugin type name, a dict for ``mi.load_dict``, an XML file holding one
    ``<bsdf>``, or a loaded ``mi.BSDF``; ``params`` are added to a name's or dict's parameters.
    ``known``: topic -> documented causes (:class:`~phonglab.validate.core.Known` with a
    signature, or a plain string judging the whole topic): a failing row is KNOWN when every
    failing lane lies in the signature of a cause that names it; ``plugins``:
    Python files that call ``mi.register_bsdf``, run after the variant is set.  ``family``,
    ``sizes``: see :func:`phonglab.validate.core.run`.  ``sweep``: check every point of the
    plugin's parameter sweep (:mod:`phonglab.validate.sweep`; ``params`` are then pinned and
    ``runner`` says where the points run), not the given point alone.  Bad input raises
    :class:`~phonglab.validate.inputs.ValidateError` with one sentence.
    """
    if sweep:
        return sweep_validate(BSDF, spec, variant=variant, params=params, topics=topics,
                              seed=seed, quick=quick, known=known, plugins=plugins,
                              family=family, sizes=sizes, runner=runner)
    return core.validate(BSDF, spec, variant=variant, params=params, topics=topics, seed=seed,
                         quick=quick, known=known, plugins=plugins, family=family, sizes=sizes)
