"""The participating-medium kind of the validator: its topics, one module per topic family.

``finite``, ``majorant``, ``albedo``, ``bounds``, ``flags`` (:mod:`.coefficients`),
``transmittance`` (:mod:`.tracking`), ``overrides`` (:mod:`.overrides`), ``phase``
(:mod:`.scattering`, through the phase kind), ``gradient`` (:mod:`.gradient`), ``cost``
(:mod:`.cost`); the swept parameters and their ranges (:mod:`.ranges`); the probe rays and the
calls into Mitsuba (:mod:`.lanes`), sizes and seeds (:mod:`.config`), the topic list and the
row (:mod:`.topics`), Mitsuba's built-in media and their findings (:mod:`.builtins`), and the
table that ties them to the kind-independent runner (:mod:`.kind`; the validator is
:func:`phonglab.validate.validate_medium`).

What a medium written in Python is in Mitsuba 3.9.1 (each line checked against the source at
tag v3.9.1, commit 478e193a):

* The trampoline ``PyMedium`` (src/render/python/medium_v.cpp:15-52) forwards exactly three
  rendering methods to Python: ``intersect_aabb(ray)`` -> (mask, mint, maxt) (line 22),
  ``get_majorant(mi, active)`` -> UnpolarizedSpectrum (line 26) and
  ``get_scattering_coefficients(mi, active)`` -> (σ_s, σ_n, σ_t) (line 30; the declaration,
  include/mitsuba/render/medium.h:28-33, names them "Sigma_s, Sigma_n and Sigma_t").  The
  middle one is the *null-collision* coefficient σ_n = σ̄ − σ_t, not the absorption σ_a:
  ``heterogeneous`` returns ``m_max_density - sigmat`` (src/media/heterogeneous.cpp:194),
  ``homogeneous`` 0 (src/media/homogeneous.cpp:173), and volpath takes a null collision with
  probability mean(σ_n/σ̄) (src/integrators/volpath.cpp:238).  Besides these, ``to_string``,
  ``traverse`` and ``parameters_changed`` (medium_v.cpp:35-45).
* ``sample_interaction`` and ``transmittance_eval_pdf`` are non-virtual base-class code
  (medium.h:53 and 71, src/render/medium.cpp:42-82 and 87-96): one exponential step against
  the majorant, sampled_t = mint − log(1 − u)/σ̄[channel] (medium.cpp:71), and the majorant's
  transmittance exp(−t σ̄) with its pdf (93-94).  The Python binding calls them through the
  pointer (medium_v.cpp:81-91), so a Python override is never called by volpath or volpathmis
  (volpath.cpp:220, 229, 479) nor by prbvolpath's loops, which call them on a ``MediumPtr``
  (prbvolpath.py:159, 170, 396, 406); only a caller in Python holding the object calls it.
* ``get_majorant`` is queried by ``sample_interaction`` once per call (medium.cpp:62), i.e.
  once per tracking step of a walk (each null collision starts a new ray at mei.p,
  volpath.cpp:257), with the interaction as built before its position is set: wi = −ray.d,
  sh_frame, time and wavelengths (medium.cpp:47-51) but p = (0, 0, 0) and t = 0.  The issue's
  "once per ray, before the interaction's position is set" holds if "ray" means each
  segment a walk restarts; a majorant computed from ``mi.p`` sees the origin, not the ray.
* ``m_is_homogeneous`` and ``m_has_spectral_extinction`` (and ``m_sample_emitters``) are
  fields the plugin sets (medium_v.cpp:47-49, 106-108: ``self.m_is_homogeneous = ...``), read
  by the non-virtual getters (medium.h:82-90); the base constructor used by a Python class,
  ``Medium(const Properties&)`` (medium.cpp:16-32), sets only ``m_sample_emitters``
  (``sample_emitters``, default true) and leaves the other two uninitialised (the default
  constructor, lines 10-14, which sets false/true, is not the one bound), so a plugin must
  set them.  The integrators branch on them: volpath.cpp:215 and 488 (spectral or grey
  weights), 221 and 480 (a homogeneous medium ends the scene ray at the sampled distance);
  prbvolpath.py:89-90, 162, 404-406 (a homogeneous medium's shadow-ray transmittance is
  exp(−σ̄ t)).  Overriding the getters ``is_homogeneous()`` etc. as Python methods changes
  only prbvolpath's ``prepare_scene`` (prbvolpath.py:88-90), which calls them on the object.
* The phase function comes from the properties: the base constructor takes the one nested
  ``PhaseFunction`` object of the medium's properties (medium.cpp:18-24; two is an error) or
  creates an ``isotropic`` one (25-29); ``phase_function()`` returns it (medium.h:77), and
  ``traverse`` exposes it as ``phase_function`` (medium.cpp:37).

Importing this package imports no Mitsuba (it declares :data:`KIND`); its modules do.
"""

from ..kind import Kind
from .topics import TOPICS


def _parts():
    """The kind's implementation module, :mod:`.kind` (imports Mitsuba: only when a part is
    first asked for)."""
    from . import kind
    return kind


#: The participating-medium kind (:mod:`phonglab.validate.kind`); its parts are in :mod:`.kind`.
KIND = Kind(name="medium", word="medium", plural="participating media", class_name="Medium",
            register="mi.register_medium", topics=TOPICS, informational=("cost",),
            bounds=("albedo",), given_point_only=("phase",), object_type="Medium",
            tag="medium",
            implementation=_parts, conformance="docs/conformance-media.md")
