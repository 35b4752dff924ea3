"""The parts of the emitter kind (:data:`phonglab.validate.emitter.KIND`): its statistical tests,
its runners, its loading (an area emitter attached to a shape, an environment placed in a scene:
:mod:`.setup`); the package face :mod:`phonglab.validate` gives it ``validate_emitter``.

The statistical tests of an emitter are its χ² reference points (non-delta emitters) and the
Monte Carlo estimate of its power from ``sample_ray``; the other topics are identities at
float32 round-off, or informational (``cost``).
"""

from __future__ import annotations

import mitsuba as mi

from ...settings import Loaded, load_plugin
from ..conformance import known_of
from ..inputs import ValidateError
from . import ranges
from . import setup as setup_
from .config import options
from .cost import cost
from .gradient import gradient
from .identities import finite, pdf, weight
from .power import power
from .sampling import chi2


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



#: The sweep's parameters and the values a documented cause's ``at`` is held against.
parameters = ranges.parameters
domain = ranges.domain
values = ranges.values


def load(spec, params, hint) -> Loaded:
    """Load the emitter (:func:`phonglab.settings.load_plugin`) and build its
    :class:`~.setup.Setup`; ``params["shape"]`` (from ``--set shape.type=...``) is the shape a
    surface emitter loaded alone is attached to."""
    params = dict(params or {})
    shape = params.pop("shape", None)
    if shape is not None and (not isinstance(shape, dict) or "type" not in shape):
        raise ValidateError("--set shape.* needs shape.type (e.g. --set shape.type=sphere)")
    loaded = load_plugin(spec, params or None, kind=mi.Emitter, word="emitter", hint=hint)
    target = setup_.build(loaded.plugin, shape)
    spec_meta = loaded.spec
    if shape is not None:
        spec_meta = {**(spec_meta or {}), "shape": shape}
    elif target.shape is not None:
        spec_meta = {**(spec_meta or {}), "shape": target.shape_name}
    return Loaded(target, loaded.label, spec_meta)



def _shape_key(shape: dict | None) -> dict:
    """What identifies a surface emitter's shape for its findings: every entry but the file."""
    return {k: v for k, v in (shape or {}).items() if k != "filename"}


def known_for(name: str, params: dict | None = None) -> dict:
    """topic -> the documented causes of the emitter table's cases of ``name`` (a type name),
    for that emitter validated outside the table (``phonglab validate area --set
    shape.type=sphere``).  A surface emitter's cases count only with the same shape
    (``params["shape"]``: type and flags, boolean flags False when absent; None: the rectangle
    an area emitter loaded alone is attached to): the vertex-normal mesh finding says nothing
    of a rectangle, the sphere's nothing of a disk.  Each cause still holds only inside its own
    signature."""
    wanted = _shape_key((params or {}).get("shape") or setup_.DEFAULT_SHAPE)

    def same_shape(case) -> bool:
        if name != "area":
            return True
        have = _shape_key(case.options.get("shape") or setup_.DEFAULT_SHAPE)
        return all(have.get(k, False) == wanted.get(k, False) for k in {*have, *wanted})

    return known_of(catalogue().cases(), name, same_shape)


def catalogue():
    """The emitter conformance table (:mod:`.builtins`)."""
    from .builtins import CATALOGUE
    return CATALOGUE
