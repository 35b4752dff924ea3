"""A refused ``params.update()`` undoes the whole update, across every object it touched.

Mitsuba's :class:`mitsuba.SceneParameters` writes a value into its object at the assignment
(``params[key] = value``: ``__setitem__`` calls ``mi.set_property`` at once) and tells the
objects only in :meth:`~mitsuba.SceneParameters.update`, bottom-up, each through its
``parameters_changed`` (``mitsuba/python/util.py`` of Mitsuba 3.9.1).  When one object refuses
its new values there -- a phonglab plugin raising ``MaterialError`` for a negative exponent --
that plugin puts its own members back (``phonglab.plugins._common.commit``), but the values
the same update wrote into *other* objects stay: an emitter's new radiance, a neighbour BSDF's
colour.  The user is told "refused", yet the next render differs (ten times darker when the
update also scaled the light).  Mitsuba also leaves that update's pending notifications
behind, so the next ``update()`` re-notifies objects with whatever they then hold.

:func:`install` closes the gap for every parameter map of the process:

* ``__setitem__`` keeps a copy (``dr.copy``) of the value a key held before its first write
  since the last update;
* ``update`` that raises writes every kept value back, notifies the same objects again (so
  each re-derives from its restored values) and re-raises the original error; one that
  succeeds forgets the copies.

So after a refused update every traversed value is bit-identical to before it, the render is
too, and a later good update works.  Not covered: an array changed in place without an
assignment (``dr.scatter`` into a fetched value), which Mitsuba itself detects only by its
JIT id inside ``update()``; nothing keeps its earlier contents.
"""

from __future__ import annotations

import copy
import threading

_lock = threading.Lock()
_installed = False
_BEFORE = "_phonglab_values_before_update"


def _value(params, key: str):
    """The current value of ``key`` as Mitsuba's own ``__getitem__`` reads it, unrecorded."""
    cur, value_type, node, _ = params.properties[key]
    return cur if value_type is None else params.get_property(cur, value_type, node)


def _copy(value):
    import drjit as dr

    if dr.is_array_v(value) or dr.is_tensor_v(value):
        return dr.copy(value)
    try:
        return copy.copy(value)
    except TypeError:          # an object that cannot be copied: kept as it is
        return value


def install() -> None:
    """Make every ``mi.SceneParameters.update()`` transactional (idempotent)."""
    global _installed
    import mitsuba as mi

    with _lock:
        if _installed:
            return
        cls = mi.SceneParameters
        set_item, update = cls.__setitem__, cls.update

        def __setitem__(self, key, value):
            before = self.__dict__.setdefault(_BEFORE, {})
            if key not in before and key in self.properties:
                before[key] = _copy(_value(self, key))
            set_item(self, key, value)

        def transactional_update(self, values=None):
            try:
                out = update(self, values)
            except BaseException:
                _roll_back(self, set_item, update)
                raise
            self.__dict__.pop(_BEFORE, None)
            return out

        transactional_update.__doc__ = update.__doc__
        cls.__setitem__, cls.update = __setitem__, transactional_update
        _installed = True


def _roll_back(params, set_item, update) -> None:
    """Write back the values kept since the last update and notify their objects again."""
    before = params.__dict__.pop(_BEFORE, {})
    for key, value in before.items():
        set_item(params, key, value)
    try:
        update(params)          # the failed update's pending objects, now with old values
    except Exception:           # the original error is the one to report
        params.nodes_to_update.clear()
        params.update_candidates.clear()
