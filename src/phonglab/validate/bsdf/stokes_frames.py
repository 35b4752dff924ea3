r"""The Stokes-frame convention of a polarized BSDF, checked from outside: a row of the
``mueller_identities`` topic (:mod:`.polarization`).

Mitsuba 3.9.1 expresses eval's Mueller matrix in implicit frames, the input Stokes vector in
``stokes_basis(−ω_o)`` and the output in ``stokes_basis(ω_i)`` (``mueller.h``,
conductor.cpp:272-301).  Nothing inside one query tells whether a plugin honours them, but an
isotropic BSDF's physics does: re-expressed in the s/p frames of the plane of incidence
(:func:`sp_frames`, :func:`to_sp`), its matrix is invariant under a rotation of ω_i and ω_o
together about the normal (:func:`rotate_z`).  :func:`isotropy` derives the statement, why
an unrotated matrix breaks it, and the lanes and tolerance of its row.
"""

from __future__ import annotations

import mitsuba as mi
import numpy as np

from ... import probe
from ...verdict import NOT_APPLICABLE
from ..roundoff import REL_TOL
from . import lanes
from .mueller import polarization_diff, rotate_stokes_basis, sensitivity, stokes_basis
from .rows import bounded_row, max_finite, worst_entry
from .topics import Row


#: The isotropy row's name.
ISOTROPY = "isotropy in Mitsuba's Stokes frames (rotation about n, s/p frames)"
#: Below this |sin θ| a direction's s/p frame (n × d) is not defined well enough to compare.
MIN_SIN = 1e-4
#: A lane whose M00 changes by more than this (relative) under the rotation is not isotropic in
#: intensity; when more than :data:`ANISO_SHARE` of the lanes are, the row is skipped.
M00_CHANGE, ANISO_SHARE = 1e-2, 0.1


def sp_frames(wi: np.ndarray, wo: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The s vectors (N, 3) of the s/p frames of a reflection or refraction at the normal
    n = (0, 0, 1): n × (−ω_o) for the beam arriving along −ω_o, n × ω_i for the one leaving
    along ω_i (the frames conductor.cpp:283-291 builds its matrix in), normalized."""
    n = np.array([0.0, 0.0, 1.0])
    s_in, s_out = np.cross(n, -wo), np.cross(n, wi)
    return (s_in / np.linalg.norm(s_in, axis=1, keepdims=True),
            s_out / np.linalg.norm(s_out, axis=1, keepdims=True))


def to_sp(m: np.ndarray, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
    """eval's matrices (N, C, 4, 4), from Mitsuba's implicit frames stokes_basis(−ω_o) →
    stokes_basis(ω_i) re-expressed in the s/p frames of :func:`sp_frames`:
    R_out M R_inᵀ (``rotate_mueller_basis``, mueller.h:361)."""
    s_in, s_out = sp_frames(wi, wo)
    r_in = rotate_stokes_basis(-wo, stokes_basis(-wo), s_in)
    r_out = rotate_stokes_basis(wi, stokes_basis(wi), s_out)
    return r_out[:, None] @ m @ np.swapaxes(r_in, -1, -2)[:, None]


def rotate_z(v: np.ndarray, psi: np.ndarray) -> np.ndarray:
    """Each row of v (N, 3) rotated by its own angle ψ (N,) about n = (0, 0, 1)."""
    c, s = np.cos(psi), np.sin(psi)
    return np.stack([c * v[:, 0] - s * v[:, 1], s * v[:, 0] + c * v[:, 1], v[:, 2]], axis=1)


def isotropy(bsdf, opts, n_eval: int) -> Row:
    r"""The Stokes-frame convention, checked from outside by rotating the input basis.

    Statement.  For a BSDF whose flags lack ``Anisotropic``, the matrix of its non-delta
    lobes expressed in the s/p frames of :func:`sp_frames` is invariant under a rotation R_ψ
    of both directions about the normal:

        M_sp(R_ψ ω_i, R_ψ ω_o) = M_sp(ω_i, ω_o)   for every ψ.

    Derivation.  An isotropic surface is unchanged by a rotation about its normal, so the
    rotated scattering configuration is the same physical event seen from a rotated
    observer: its matrix, in reference frames carried along by the rotation, is the same
    matrix.  The s/p frames are carried along: R_ψ n = n gives R_ψ (n × d) = n × (R_ψ d), and
    the y vectors (forward × x, Mitsuba's right-handed frames) follow.  Mitsuba's implicit
    frames are not: ``stokes_basis(d)`` is a fixed function of d (Duff et al.'s
    ``coordinate_system``), so eval's matrix itself changes with ψ and is rotated to the s/p
    frames first (:func:`to_sp`, the rotations of ``rotate_stokes_basis``).  A plugin that
    builds its matrix M₀ in the s/p frames and returns it *without* the rotation into
    ``stokes_basis(−ω_o)``, ``stokes_basis(ω_i)`` (the step conductor.cpp:296-299 takes)
    returns M = M₀, so this check reads R_out(ψ) M₀ R_in(ψ)ᵀ, where R(ψ) are the rotators by
    the angles between ``stokes_basis`` and the s/p vectors -- angles that change with ψ.
    The angles of R_in and R_out move independently as ψ varies (one depends on ω_o's
    azimuth, the other on ω_i's), so that is invariant only when M₀ R(α)ᵀ and R(β) M₀ are for
    all α, β: columns and rows 1, 2 of M₀ vanish, M₀ = [[a, 0, 0, b], [0, 0, 0, 0],
    [0, 0, 0, 0], [e, 0, 0, f]] -- a depolarizer (diffuse) or a circular polarizer or
    diattenuator.  Any entry in rows or columns 1, 2 (the linear part) moves by up to its
    own size.  An unrotated matrix is still a realizable Mueller matrix with the right M00, so no other row
    sees it, but the renderer converts it to world frames as if it were in
    ``stokes_basis`` (``SurfaceInteraction::to_world_mueller``): the polarization it puts out
    has the wrong angle, which a polarizer or a second polarizing bounce turns into wrong
    intensity (tests/defects_polarized/unrotated_frames.py).

    Lanes: ω_i at the incidence cells (``n_eval`` per cell), ω_o uniform on the sphere (reflection and
    transmission), ψ uniform per lane; lanes with |sin θ| < :data:`MIN_SIN` for either
    direction are left out (the s/p frame is undefined at the normal, where a BSDF picks an
    arbitrary axis).  Compared as the other rows: the polarization parts M/M00 entry by entry
    (:func:`.mueller.polarization_diff`), tolerance REL_TOL plus both sides' sensitivity to an 8-ulp move of
    both directions (the rotated directions are rounded to float32, and the s/p frames'
    conditioning ∝ 1/sin θ enters there).  M00's own invariance is an intensity property:
    where it fails at more than :data:`ANISO_SHARE` of the lanes by more than
    :data:`M00_CHANGE` the BSDF is not isotropic about the geometric normal although its flags
    say so (a ``bumpmap`` or ``normalmap`` tilts the shading frame at the probe's uv, and
    Mitsuba 3.9.1 has no flag for that), and the row is skipped saying so.  Skipped too for
    ``Anisotropic`` flags and for BSDFs whose lobes are all deltas (eval is 0)."""
    flags = int(bsdf.flags())
    if flags & int(mi.BSDFFlags.Anisotropic):
        return Row("mueller_identities", ISOTROPY, None, None, None, None, "skipped",
                   "the BSDF's flags include Anisotropic: a rotation about the normal is no "
                   "symmetry of it", {NOT_APPLICABLE: True})
    if lanes.delta_only(bsdf):
        return Row("mueller_identities", ISOTROPY, None, None, None, None, "skipped",
                   "every lobe is a delta: eval is 0, nothing to compare", {NOT_APPLICABLE: True})
    r = lanes.rng(opts.seed, "mueller_identities", 1)
    wi, _ = lanes.incident(opts.cells(), n_eval)
    wo = lanes.sphere(r, len(wi))
    keep = ((np.hypot(wi[:, 0], wi[:, 1]) >= MIN_SIN) & (np.hypot(wo[:, 0], wo[:, 1]) >= MIN_SIN))
    wi, wo = wi[keep], wo[keep]
    psi = r.uniform(0.0, 2.0 * np.pi, len(wi))
    wi2, wo2 = rotate_z(wi, psi), rotate_z(wo, psi)

    def sp_of(a, b):
        return to_sp(probe.mueller_eval(bsdf, a, b), a, b)

    m1, m2 = sp_of(wi, wo), sp_of(wi2, wo2)
    a00, b00 = m1[..., 0, 0], m2[..., 0, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        change = np.abs(a00 - b00) / np.maximum(np.abs(a00), np.abs(b00))
    moved = np.nan_to_num(change, nan=0.0).max(axis=1) > M00_CHANGE
    if moved.sum() > ANISO_SHARE * len(wi):
        return Row("mueller_identities", ISOTROPY, None, None, None, None, "skipped",
                   f"M00 itself changes by more than {M00_CHANGE:g} under the rotation at "
                   f"{int(moved.sum())} of {len(wi)} lanes: not isotropic about the geometric "
                   f"normal though its flags lack Anisotropic (a tilted shading frame, e.g. "
                   f"bumpmap or normalmap)", {NOT_APPLICABLE: True, "m00_moved": int(moved.sum())})
    sens = sensitivity(sp_of, wi, wo, m1, r) + sensitivity(sp_of, wi2, wo2, m2, r)
    ex = polarization_diff(m2, m1) / (REL_TOL + sens)
    ex = np.where(moved, np.nan, ex)
    details = worst_entry(ex, wi, wo, m1, m2, ("sp_matrix", "sp_matrix_rotated"))
    details["m00_moved"] = int(moved.sum())
    details["max_difference"] = float(max_finite(np.where(moved, np.nan, polarization_diff(m2, m1))))
    if details.get("worst_wi") is not None:
        k = int(np.nanargmax(np.where(np.isfinite(ex), ex, -1.0)))
        details.update(psi=float(psi[k]), rotated_wi=wi2[k].tolist(), rotated_wo=wo2[k].tolist())
    return bounded_row("mueller_identities", ISOTROPY, max_finite(ex), 1.0,
                       "max over entries of |M_sp(Rψ wi, Rψ wo)/M00 − M_sp(wi, wo)/M00|, M_sp "
                       "eval's matrix rotated from Mitsuba's stokes_basis frames to the s/p "
                       "frames (n × d), ψ random per lane, over (2^-10 + both sides' "
                       "sensitivity to an 8-ulp move); must be ≤ 1 (an isotropic BSDF's s/p "
                       f"matrix is rotation-invariant); {len(wi)} lanes",
                       details, lanes=(ex, {"wi": wi, "wo": wo}))
