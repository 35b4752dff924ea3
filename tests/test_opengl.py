"""OpenGL ↔ phonglab mappings: validation, round trips, and rendered pixels against GL's equation.

The exactness claims of :mod:`phonglab.opengl` are checked by rendering: ``whitted``
(graphics units) with :func:`gl_to_whitted` reproduces :func:`gl_colour` (OpenGL 2.1's
equation with the seed's (L·R)^p) to float precision; ``path`` with :func:`gl_to_physical`
matches GL at the reference geometry and differs elsewhere by exactly the factors the
table states (cos θ_i on the specular term, r0²/r² against GL's default attenuation).
"""

from __future__ import annotations

import math

import mitsuba as mi
import numpy as np
import pytest

from phonglab.physics import opengl
from phonglab.physics.opengl import GLLight, GLMaterial
from phonglab.errors import PhonglabError


def test_gl_defaults_and_validation():
    m = GLMaterial()
    assert m.diffuse == (0.8, 0.8, 0.8) and m.ambient == (0.2, 0.2, 0.2) and m.shininess == 0
    with pytest.raises(PhonglabError, match="GL_SHININESS must lie in"):
        GLMaterial(shininess=129)
    with pytest.raises(PhonglabError, match="GL_DIFFUSE must be three finite"):
        GLMaterial(diffuse=(-0.1, 0, 0))
    with pytest.raises(PhonglabError, match="not all 0"):
        GLLight(constant_attenuation=0.0)
    with pytest.raises(PhonglabError, match="no OpenGL counterpart"):
        opengl.physical_to_gl(0.5, 0.1, 200.0, 10.0)
    with pytest.raises(PhonglabError, match="reference_distance"):
        opengl.gl_to_physical(GLMaterial(), GLLight())


@pytest.mark.parametrize("p", [0.0, 1.0, 10.0, 100.0])
def test_physical_gl_physical_round_trip(p):
    kd, ks, I = [0.5, 0.3, 0.2], [0.2, 0.1, 0.05], [10.0, 20.0, 30.0]
    material, light = opengl.physical_to_gl(kd, ks, p, I, position=(1, 2, 3))
    np.testing.assert_allclose(material.specular, np.array(ks) * (p + 2) / 2)
    back = opengl.gl_to_physical(material, light)
    np.testing.assert_allclose(back.bsdf["diffuse_reflectance"]["value"], kd)
    np.testing.assert_allclose(back.bsdf["specular_reflectance"]["value"], ks)
    np.testing.assert_allclose(back.light["intensity"]["value"], I)
    assert back.bsdf["exponent"] == p


def test_energy_violating_gl_material_is_rescaled_into_the_light():
    m = GLMaterial(diffuse=(0.8, 0.8, 0.8), specular=(1.0, 1.0, 1.0), shininess=20)
    mapping = opengl.gl_to_whitted(m, GLLight(diffuse=(2, 2, 2), specular=(2, 2, 2)))
    np.testing.assert_allclose(mapping.bsdf["diffuse_reflectance"]["value"], [0.8 / 1.8] * 3)
    np.testing.assert_allclose(mapping.light["intensity"]["value"], [3.6] * 3)
    assert mapping.exact


def _plane(mapping, extra=None):
    shape = {"type": "rectangle", "to_world": mi.ScalarTransform4f().scale([20, 20, 1]),
             "bsdf": mapping.bsdf}
    if mapping.shape_emitter:
        shape["emitter"] = mapping.shape_emitter
    return mi.load_dict({"type": "scene", "integrator": mapping.integrator, "plane": shape,
                         "light": mapping.light, **(extra or {})})


def _sample(scene, eyes, points):
    eyes, points = np.asarray(eyes, np.float32), np.asarray(points, np.float32)
    d = points - eyes
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    sampler = mi.load_dict({"type": "independent"})
    sampler.seed(0, len(eyes))
    ray = mi.Ray3f(mi.Point3f(*(mi.Float(c) for c in eyes.T)),
                   mi.Vector3f(*(mi.Float(c) for c in d.T)))
    return np.array(scene.integrator().sample(scene, sampler, ray, None, True)[0], np.float64).T


PTS = np.array([[0.0, 0.0, 0.0], [0.4, -0.3, 0.0], [1.5, 0.5, 0.0], [-1.0, 2.0, 0.0]])
EYES = PTS + np.array([-0.8, -0.5, 2.0])


@pytest.mark.parametrize("abc", [(1.0, 0.0, 0.0), (0.5, 0.2, 0.1)], ids=["gl-default", "abc"])
def test_gl_to_whitted_reproduces_the_gl_equation(variant_llvm_rgb, abc):
    """Emission + ambient (global + light) + diffuse + specular, k_d + k_s > 1 included."""
    material = GLMaterial(ambient=(0.3, 0.2, 0.1), diffuse=(0.7, 0.5, 0.3),
                          specular=(0.6, 0.6, 0.6), shininess=12.0, emission=(0.05, 0.0, 0.02))
    light = GLLight(position=(0.5, 1.0, 2.0), diffuse=(1.5, 1.2, 1.0), specular=(1.5, 1.2, 1.0),
                    ambient=(0.1, 0.1, 0.1) if abc == (1.0, 0.0, 0.0) else (0.0, 0.0, 0.0),
                    constant_attenuation=abc[0], linear_attenuation=abc[1],
                    quadratic_attenuation=abc[2])
    mapping = opengl.gl_to_whitted(material, light)
    assert mapping.exact, mapping.notes
    got = _sample(_plane(mapping), EYES, PTS)
    want = np.array([opengl.gl_colour(material, light, p, (0, 0, 1), e) for p, e in zip(PTS, EYES)])
    np.testing.assert_allclose(got, want, rtol=2e-5, atol=1e-6)


def test_gl_to_physical_matches_at_reference_and_differs_by_the_tabled_factors(variant_llvm_rgb):
    """Diffuse-only under GL's default a = 1, b = c = 0: path/GL = r0²/r² (1 at r0);
    specular-only at the mirror geometry with exact quadratic attenuation: path/GL = cos θ_i."""
    r0 = 2.0
    light = GLLight(position=(0.0, 0.0, r0), diffuse=(1, 1, 1), specular=(1, 1, 1))
    diffuse = GLMaterial(ambient=(0, 0, 0), diffuse=(0.6, 0.6, 0.6), specular=(0, 0, 0))
    mapping = opengl.gl_to_physical(diffuse, light, reference_distance=r0)
    scene = _plane(mapping)
    pts = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.5, -1.0, 0.0]])
    eyes = pts + np.array([0.0, 0.3, 3.0])
    got = _sample(scene, eyes, pts)[:, 0]
    gl = np.array([opengl.gl_colour(diffuse, light, p, (0, 0, 1), e, global_ambient=(0, 0, 0))
                   for p, e in zip(pts, eyes)])[:, 0]
    r2 = np.sum((np.array(light.position) - pts) ** 2, axis=1)
    np.testing.assert_allclose(got[0], gl[0], rtol=1e-5)               # the reference point
    np.testing.assert_allclose(got / gl, r0 * r0 / r2, rtol=1e-5)      # inverse square vs none
    assert got[2] / gl[2] < 0.5                                        # and it matters

    # Specular only, quadratic GL attenuation (exact distance law): the eye on the mirror
    # direction of the light, so (L·R) = 1 and GL = k_s D/(c r²), physics × cos θ_i.
    light_q = GLLight(position=(0.0, 0.0, r0), quadratic_attenuation=1.0, constant_attenuation=0.0)
    shiny = GLMaterial(ambient=(0, 0, 0), diffuse=(0, 0, 0), specular=(0.9, 0.9, 0.9),
                       shininess=30.0)
    scene = _plane(opengl.gl_to_physical(shiny, light_q))
    pts = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [3.0, 0.0, 0.0]])
    to_light = np.array(light_q.position) - pts
    mirror = to_light * np.array([-1.0, -1.0, 1.0])                   # reflect about N = +Z
    eyes = pts + mirror
    got = _sample(scene, eyes, pts)[:, 0]
    gl = np.array([opengl.gl_colour(shiny, light_q, p, (0, 0, 1), e, global_ambient=(0, 0, 0))
                   for p, e in zip(pts, eyes)])[:, 0]
    cos_i = to_light[:, 2] / np.linalg.norm(to_light, axis=1)
    np.testing.assert_allclose(got / gl, cos_i, rtol=1e-4)
    assert cos_i[-1] < 0.6
    assert math.isclose(got[0], gl[0], rel_tol=1e-4)
