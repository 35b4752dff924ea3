r"""The ``overrides`` topic: a plain statement of each method a Python medium defines that
Mitsuba does not call through the plugin, and whether what it returns is what Mitsuba runs.

Mitsuba 3.9.1's trampoline forwards three methods to Python (``PyMedium``,
src/render/python/medium_v.cpp:22-33: ``intersect_aabb``, ``get_majorant``,
``get_scattering_coefficients``; plus ``to_string``, ``traverse``, ``parameters_changed``).
The rest of ``mi.Medium``'s interface is non-virtual base-class code
(include/mitsuba/render/medium.h): ``sample_interaction`` (line 53, src/render/medium.cpp:42-82)
and ``transmittance_eval_pdf`` (line 71, medium.cpp:87-96), and the getters ``phase_function``,
``use_emitter_sampling``, ``is_homogeneous``, ``has_spectral_extinction`` (lines 77-90, which
return the fields ``m_phase_function``, ``m_sample_emitters``, ``m_is_homogeneous``,
``m_has_spectral_extinction``).  A Python method of the same name shadows the binding for a
caller in Python holding the object itself, and nothing else: volpath and volpathmis
(src/integrators/volpath.cpp:215-229, 479-488) and prbvolpath's tracking loops (through a
``MediumPtr``, prbvolpath.py:159-170, 396-406) run the base class's.  One exception:
prbvolpath's ``prepare_scene`` (prbvolpath.py:88-90) calls ``use_emitter_sampling()`` and
``is_homogeneous()`` on the medium object, so those two overrides are called there and the
field everywhere else.

A row per such method the plugin's class defines: it passes, saying so, when the override
returns what the base class returns on ``override_lanes`` probe lanes (to 2⁻¹⁰ relative), and
fails when it does not (or raises): the code an author tests by calling the method is then
not the code that renders.  A plugin that defines none has one skipped row (not applicable).
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np

from ...verdict import NOT_APPLICABLE
from ... import probe as probe_
from ..returns import defines
from ..roundoff import REL_TOL
from . import lanes
from .config import rng
from .topics import Row

#: Non-virtual methods of mi.Medium a Python class may shadow -> where 3.9.1 defines them.
NON_VIRTUAL = {
    "sample_interaction": "include/mitsuba/render/medium.h:53 (src/render/medium.cpp:42)",
    "transmittance_eval_pdf": "include/mitsuba/render/medium.h:71 (src/render/medium.cpp:87)",
    "phase_function": "include/mitsuba/render/medium.h:77",
    "use_emitter_sampling": "include/mitsuba/render/medium.h:82",
    "is_homogeneous": "include/mitsuba/render/medium.h:85",
    "has_spectral_extinction": "include/mitsuba/render/medium.h:88",
}
#: The overrides some integrator does call on the Python object.
CALLED_BY = {"use_emitter_sampling": "prbvolpath's prepare_scene (prbvolpath.py:88)",
             "is_homogeneous": "prbvolpath's prepare_scene (prbvolpath.py:89-90)"}


def overridden(medium) -> list[str]:
    """The non-virtual methods ``medium``'s Python class defines."""
    return [m for m in NON_VIRTUAL if defines(medium, m)]


def _differ(a, b) -> np.ndarray:
    """Per lane: whether two (N, ...) arrays differ beyond 2^-10 relative (inf = inf)."""
    a = a.reshape(len(a), -1)
    b = b.reshape(len(b), -1)
    with np.errstate(invalid="ignore"):
        same = (a == b) | (np.abs(a - b) <= REL_TOL * np.maximum(np.abs(a), np.abs(b)))
    return ~np.all(same, axis=1)


def _lanes(medium, opts):
    p = lanes.probe(medium, opts)
    r = rng(opts.seed, "overrides")
    i = np.flatnonzero(p.inside)
    if not len(i):
        i = np.arange(len(p.o))
    i = r.choice(i, size=min(opts.override_lanes, len(i)), replace=False)
    n = len(i)
    return p.o[i], p.d[i], p.exit[i], r.random(n), r.integers(0, lanes.channels(), n), r


def _interaction_arrays(mei, n) -> dict:
    return {"t": probe_.to_numpy(mei.t, n),
            "sigma_t": lanes.spectrum(mei.sigma_t, n),
            "sigma_n": lanes.spectrum(mei.sigma_n, n),
            "combined_extinction": lanes.spectrum(mei.combined_extinction, n)}


def _compare(medium, name, opts):
    """(lanes compared, lanes that differ, what the first differing lane shows)."""
    v = lanes.view(medium)
    if name in ("phase_function", "use_emitter_sampling", "is_homogeneous",
                "has_spectral_extinction"):
        base, own = getattr(v, name)(), getattr(medium, name)()
        same = (own is base or own == base) if name == "phase_function" else \
            bool(own) == bool(base)
        return 1, 0 if same else 1, {"base": str(base)[:200], "override": str(own)[:200]}
    o, d, ex, u, ch, r = _lanes(medium, opts)
    n = len(o)
    ray = lanes.ray(o, d, ex)
    uu, cc, act = lanes.floats(u), mi.UInt32(ch.astype(np.uint32)), mi.Bool(True)
    base = v.sample_interaction(ray, uu, cc, act)
    if name == "sample_interaction":
        own = medium.sample_interaction(ray, uu, cc, act)
        a, b = _interaction_arrays(base, n), _interaction_arrays(own, n)
    else:
        si = dr.zeros(mi.SurfaceInteraction3f, n)
        si.t = lanes.floats(ex * r.random(n))
        a = dict(zip(("tr", "pdf"), (lanes.spectrum(x, n) for x in
                                     v.transmittance_eval_pdf(base, si, act))))
        b = dict(zip(("tr", "pdf"), (lanes.spectrum(x, n) for x in
                                     medium.transmittance_eval_pdf(base, si, act))))
    bad = np.zeros(n, bool)
    for key in a:
        bad |= _differ(np.asarray(a[key]), np.asarray(b[key]))
    shown = {}
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        shown = {"o": o[k].tolist(), "d": d[k].tolist(), "u": float(u[k]), "channel": int(ch[k]),
                 "base": {key: np.asarray(x)[k].tolist() for key, x in a.items()},
                 "override": {key: np.asarray(x)[k].tolist() for key, x in b.items()}}
    return n, int(bad.sum()), shown


def overrides(medium, opts) -> list[Row]:
    names = overridden(medium)
    if not names:
        return [Row("overrides", "methods Mitsuba does not call through the plugin", None, None,
                    None, None, "skipped",
                    "the plugin defines none of mi.Medium's non-virtual methods ("
                    + ", ".join(NON_VIRTUAL) + ")", {NOT_APPLICABLE: True})]
    rows = []
    for name in names:
        where = NON_VIRTUAL[name]
        called = CALLED_BY.get(name)
        who = (f"only {called} calls it on the object; volpath, volpathmis and every tracking "
               f"loop read the base class's ({where})" if called else
               f"no integrator calls it: they run the base class's ({where})")
        try:
            n, bad, shown = _compare(medium, name, opts)
        except Exception as exc:      # the override raises: Mitsuba's code still runs
            rows.append(Row("overrides", f"{name}() overridden", 1.0, 0.0, None, 0.0, "fail",
                            f"the plugin defines {name}(), which is not virtual in Mitsuba "
                            f"3.9.1: {who}; the override raised {type(exc).__name__}: "
                            f"{str(exc).splitlines()[0][:200] if str(exc) else ''}",
                            {"method": name, "source": where}))
            continue
        if bad:
            reason = (f"the plugin defines {name}(), which is not virtual in Mitsuba 3.9.1: "
                      f"{who}; the override returns something else on {bad} of {n} lanes, so "
                      f"what the plugin's own tests of {name}() see is not what renders")
        else:
            reason = (f"the plugin defines {name}(), which is not virtual in Mitsuba 3.9.1: "
                      f"{who}; the override returns what the base class returns on all {n} "
                      f"lanes, so it changes nothing (and can be removed)")
        rows.append(Row("overrides", f"{name}() overridden", float(bad), 0.0, None, 0.0,
                        "fail" if bad else "pass", reason,
                        {"method": name, "source": where, "lanes": n, "differ": bad,
                         **({"first": shown} if shown else {})}))
    return rows
