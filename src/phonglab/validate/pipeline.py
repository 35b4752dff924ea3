r"""The one way a plugin is validated, whoever asks: the command line, the package face
(:func:`phonglab.validate.validate`, ``validate_bsdf`` ...), the pytest helpers
(:mod:`phonglab.testing`) and the conformance batch all call :func:`validate`.

The steps, each bad input a one-sentence :class:`~phonglab.validate.inputs.ValidateError`
raised before any topic runs:

1. the variant set (phonglab's plugins registered in it), unless the target is an object already
   loaded in the active one (:func:`phonglab.validate.loading.start`);
2. the ``plugins`` files run once, recording what each registers
   (:func:`~phonglab.validate.loading.load_plugins`);
3. the kind: given, or detected from the target and what the files registered
   (:func:`phonglab.validate.registry.detect`), and every file registered a plugin of it; a
   plugin of a scene (``scene_id``: the id of an object of ``kind`` in the scene file ``spec``,
   a material) is of the kind given;
4. the topics checked against the kind's;
5. the plugin loaded once (:func:`~phonglab.validate.loading.load`: its ``traverse`` and the returns
   of its Python methods checked);
6. the ``--set`` values (``params``) checked against the declared or documented ranges
   (:func:`phonglab.validate.sweep.check_set`);
7. the topics run at the given point (``sweep=False``) or at every point of the kind's
   parameter sweep (:func:`phonglab.validate.sweep.run`), on ``runner``'s workers if given.

The Report carries the kind and plugin as data (``meta["kind"]``, ``meta["plugin"]``); the
worker of one sweep point (:func:`phonglab.validate.sweep.run_point`) runs step 7 alone on a
target it prepares itself.
"""

from __future__ import annotations

import time

from ..registration import PLUGINS
from ..verdict import Report
from . import core, loading, registry, sweep as sweep_
from .builtin import BUILTIN, scene_object
from .kind import Kind, ValidateError

__all__ = ["validate"]


def validate(spec, *, kind: Kind | str | None = None, variant=None, params=None, plugins=(),
             topics=None, seed=0, quick=False, known=None, sweep=True, runner=None,
             progress=None, family=1, sizes=None, scene_id: str | None = None) -> Report:
    """Validate ``spec`` (a type name, a dict, an XML file, a loaded object; with
    ``scene_id``, the scene file holding the plugin of ``kind`` with that id) as its ``kind``
    (a Kind, a kind's name, or None: detected); the steps are the module docstring's.  ``known``: topic ->
    documented causes, or :data:`phonglab.validate.builtin.BUILTIN`: the documented findings
    of the Mitsuba built-in that is loaded (and those a wrapper inherits from its built-in
    children; for a kind that cannot identify a loaded built-in, those of its type name)."""
    t0 = time.perf_counter()
    if isinstance(kind, str):
        kind = registry.by_name(kind)
    loading.start(variant, spec, kind)
    registered = loading.load_plugins(plugins)
    if scene_id is not None:
        if kind is None:
            raise ValidateError(f"give the kind of the scene's plugin with id {scene_id!r} "
                                f"(kind=...): a scene holds plugins of several kinds")
        topics = kind.check_topics(topics)
        found = scene_object(kind, spec, scene_id)
        target = loading.load(kind, found.plugin, None, registered)._replace(
            label=found.label, origin=found.origin)
    else:
        kind = kind or registry.detect(spec, registered)
        loading.check_registered(registered, kind)
        topics = kind.check_topics(topics)
        target = loading.load(kind, spec, params, registered)
    sweep_.check_set(kind, target, spec, params)
    known = _findings(kind, known, spec, params, plugins)
    if not sweep:
        report = core.run(kind, target, topics=topics, seed=seed, quick=quick, known=known,
                          family=family, sizes=sizes)
    else:
        report = sweep_.run(kind, target, spec, params=params, topics=topics, seed=seed,
                            quick=quick, known=known, plugins=plugins, family=family,
                            sizes=sizes, runner=runner, progress=progress, t0=t0)
    if registered:
        report.meta["registered"] = [list(pair) for pair in registered]
    return report


def _findings(kind: Kind, known, spec, params, plugins):
    """``known`` as the run takes it.  :data:`BUILTIN` stays for a kind that tells a built-in
    from the loaded object (its ``identify`` part: BSDFs); another kind gets the findings of
    its type name (its ``known_for`` part), none for a plugin file's, an XML file's or
    phonglab's own plugins."""
    if not (isinstance(known, str) and known == BUILTIN) or kind.part("identify") is not None:
        return known
    if plugins or not isinstance(spec, str) or spec.endswith(".xml") \
            or spec in {name for _, name, _ in PLUGINS}:
        return None
    known_for = kind.part("known_for")
    return (known_for(spec, params) or None) if known_for is not None else None
