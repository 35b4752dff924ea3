"""The physics phonglab checks renders against, independent of any renderer.

* :mod:`.optics`      Snell's law, total internal reflection, the Fresnel equations;
* :mod:`.radiometry`  the reflection equation by quadrature, directional albedo, 1/r², the
  furnace and radiance constancy (numpy, probing BSDFs through :mod:`phonglab.probe`);
* :mod:`.quadrature`  the reflection equation by a quadrature adapted to a glossy lobe
  (deterministic albedo, used by the checks);
* :mod:`.estimators`  Monte Carlo estimators of the reflection equation (uniform, cosine, BSDF,
  light, MIS, optimal MIS) in Dr.Jit, with exact values by quadrature (a package: the problem,
  the exact values, the shared kernel pieces, the i.i.d. estimators, optimal MIS, the runner);
* :mod:`.roughness`   Beckmann α ↔ Phong exponent p ↔ Blinn–Phong p_h (the folk rules);
* :mod:`.opengl`      the OpenGL fixed-function local model and its mapping to phonglab's.
"""
