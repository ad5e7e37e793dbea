"""Beam footprint against the sample and the detector's view (collimated beam).

In the sample plane the beam (diameter D, from wi) lights an ellipse of semi-axes
D/(2 cos θi) along wi's azimuth × D/2; the detector (field of view F, toward wo) sees
an ellipse F/(2 cos θo) along wo's azimuth × F/2; the sample is a disc of diameter S.
All three are centred on the sample centre. The fraction of the beam's power that the
detector collects from the sample is

    η = Area(lit ∩ seen ∩ disc) / Area(lit),

exactly 1 wherever `gonio.rig.constraints.footprint_ok` says the lit ellipse fits
(the ideal chain's overfilled geometry), 0 at exactly grazing incidence.

Method (exact, not a quadrature): in coordinates where the lit ellipse is the unit disc
the other two regions are centred ellipses, so the intersection is star-shaped about
the centre with r(β)² = min(1, 1/q_seen, 1/q_disc) and η = (1/π) ∫₀^π r² dβ. The
integrand switches between the three conics only where two of them cross (up to six
angles in [0, π), from 2 × 2 eigen-problems); on each piece the integral of 1/q is a
sector area in closed form. Accuracy: rounding only; measured within the noise of a
10⁶-point Monte Carlo (5e-4) and within 1.3e-10 of a 2·10⁵-node midpoint rule (its own
error); the kick-in angle within 4e-12 rad of the closed form (docs/explanations/radiometry.md).
"""

from __future__ import annotations

import math

import numpy as np

from gonio.radiometry._checks import cosine, direction, direction_pair, positive
from gonio.radiometry._ellipses import Form, azimuth, crossings, ellipse_form, quadratic, sector
from gonio.rig import footprint_ok, view_on_sample
from gonio.types import ArrayLike, BoolArray, FloatArray

#: cos θo floor for the seen ellipse (as in footprint_ok): a strip at exactly grazing
#: view would make the form singular; the change in η is ≤ (S cos θ / F)² ~ 1e-18.
_CO_FLOOR = 1e-9
#: cos θi floor keeping (D / cos θi)² finite; η ≤ S² cos θi / D² below it, i.e. ~0.
_CI_FLOOR = 1e-100


def seen_fits_sample(fov_diameter_mm: float, sample_diameter_mm: float, wo: ArrayLike) -> BoolArray:
    """True where the detector's seen ellipse lies on the sample (F / cos θo ≤ S): the
    point-source chain's flooded-sample assumption."""
    f = positive("fov_diameter_mm", fov_diameter_mm)
    s = positive("sample_diameter_mm", sample_diameter_mm)
    return view_on_sample(direction("wo", wo), f, s)


def footprint_fraction(
    beam_diameter_mm: float,
    fov_diameter_mm: float,
    sample_diameter_mm: float,
    wi: ArrayLike,
    wo: ArrayLike,
) -> FloatArray:
    """η = Area(lit ∩ seen ∩ sample) / Area(lit) ∈ [0, 1], shape broadcast(wi, wo)[:-1].

    Collimated beam of diameter D (mm), field of view F (mm), sample disc of diameter S
    (mm). Exactly 1 where `footprint_ok` holds, 0 at θi = 90°; see the module.
    """
    d = positive("beam_diameter_mm", beam_diameter_mm)
    f = positive("fov_diameter_mm", fov_diameter_mm)
    s = positive("sample_diameter_mm", sample_diameter_mm)
    a, b = direction_pair(wi, wo)
    fits = footprint_ok(a, b, d, s, f)
    ci, co = cosine(a), np.maximum(cosine(b), _CO_FLOOR)
    cos_i, sin_i = azimuth(a)
    cos_o, sin_o = azimuth(b)
    # Lit-ellipse coordinates (ξ, η): x = a1 ξ e_i + b1 η e_i⊥; the lit ellipse is ξ² + η² ≤ 1.
    a1 = 0.5 * d / np.maximum(ci, _CI_FLOOR)
    b1 = 0.5 * d
    cd = cos_i * cos_o + sin_i * sin_o  # e_i · e_o
    sd = cos_i * sin_o - sin_i * cos_o  # e_i × e_o
    one, zero = np.ones_like(a1), np.zeros_like(a1)
    unit = Form(one, one, zero, one)
    # The seen ellipse: (2 cos θo / F)² (x·e_o)² + (2/F)² (x·e_o⊥)² ≤ 1, pulled back by
    # diag(a1, b1); its determinant is (a1 b1 (2 cos θo/F)(2/F))².
    seen_unscaled = ellipse_form(2.0 * co / f, np.full_like(co, 2.0 / f), cd, sd)
    seen = Form(
        a1 * a1 * seen_unscaled.a,
        b1 * b1 * seen_unscaled.b,
        a1 * b1 * seen_unscaled.c,
        (a1 * b1) ** 2 * seen_unscaled.det,
    )
    r2 = (0.5 * s) ** 2
    disc = Form(a1 * a1 / r2, np.full_like(a1, b1 * b1 / r2), zero, (a1 * b1 / r2) ** 2)

    cuts = [*crossings(unit, seen), *crossings(unit, disc), *crossings(seen, disc)]
    fixed = [np.broadcast_to(v, a1.shape) for v in (0.0, 0.5 * math.pi, math.pi)]
    edges = np.sort(np.stack([*fixed, *cuts], axis=-1), axis=-1)
    lo, hi = edges[..., :-1], edges[..., 1:]
    mid = 0.5 * (lo + hi)
    cm, sm = np.cos(mid), np.sin(mid)
    forms = [Form(*(np.asarray(x)[..., None] for x in m)) for m in (seen, disc)]
    q = np.stack([np.ones_like(mid), *(quadratic(m, cm, sm) for m in forms)], axis=0)
    active = np.argmax(q, axis=0)
    pieces = np.stack([hi - lo, *(sector(m, lo, hi) for m in forms)], axis=0)
    area = np.take_along_axis(pieces, active[None], axis=0)[0].sum(axis=-1)
    eta = np.clip(area / math.pi, 0.0, 1.0)
    return np.asarray(np.where(fits, 1.0, np.where(ci > 0.0, eta, 0.0)), dtype=np.float64)
