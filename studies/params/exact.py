"""Arbitrary-precision reference maps (mpmath), for measuring float64 error only.

Written independently of the float64 code, straight from the definitions (rotations,
polar angles, the appendix's h·k = 0 for θk), one pair at a time: slow, exact to
``DIGITS`` decimal digits. Needs ``mpmath`` (the ``test`` extra).

`roundtrip_bound` is what the float64 maps are measured against: the input
directions normalized exactly, their exact coordinates moved by the half ulp that
float64 cannot resolve, mapped back exactly. Coordinates that the move pushes out of
the domain are mapped to the nearest directions in the closed upper hemisphere.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from typing import Any

import mpmath as mp
import numpy as np

DIGITS = 40

Vec = list[Any]  # three mpf


def _vec(w: Sequence[float]) -> Vec:
    v = [mp.mpf(float(x)) for x in w]
    n = mp.sqrt(sum(x * x for x in v))
    return [x / n for x in v]


def _norm(v: Vec) -> Any:
    return mp.sqrt(sum(x * x for x in v))


def _azimuth(y: Any, x: Any) -> Any:
    if x == 0 and y == 0:
        return mp.mpf(0)
    phi = mp.atan2(y, x)
    return phi + 2 * mp.pi if phi < 0 else phi


def _polar(v: Vec) -> tuple[Any, Any]:
    return mp.atan2(mp.sqrt(v[0] ** 2 + v[1] ** 2), v[2]), _azimuth(v[1], v[0])


def _rot_z(v: Vec, a: Any) -> Vec:
    c, s = mp.cos(a), mp.sin(a)
    return [c * v[0] - s * v[1], s * v[0] + c * v[1], v[2]]


def _rot_y(v: Vec, a: Any) -> Vec:
    c, s = mp.cos(a), mp.sin(a)
    return [c * v[0] + s * v[2], v[1], -s * v[0] + c * v[2]]


def _to_hemisphere(v: Vec) -> Vec:
    """The nearest unit vector with z ≥ 0."""
    v = [v[0], v[1], max(v[2], mp.mpf(0))]
    n = _norm(v)
    return [x / n for x in v] if n > 0 else [mp.mpf(1), mp.mpf(0), mp.mpf(0)]


def forward(name: str, wi: Sequence[float], wo: Sequence[float]) -> list[Any]:
    """Exact coordinates of the exactly normalized pair."""
    with mp.workdps(DIGITS):
        return forward_unit(name, _vec(wi), _vec(wo))


def forward_unit(name: str, a: Vec, b: Vec) -> list[Any]:
    """Exact coordinates of unit vectors given as mpf (e.g. a pair moved exactly)."""
    with mp.workdps(DIGITS):
        h = [(x + y) / 2 for x, y in zip(a, b, strict=True)]
        k = [(x - y) / 2 for x, y in zip(a, b, strict=True)]
        if name == "spherical":
            return [*_polar(a), *_polar(b)]
        if name == "rusinkiewicz":
            if _norm(h) == 0:
                return [mp.mpf(0), mp.mpf(0), mp.pi / 2, _azimuth(a[1], a[0])]
            theta_h, phi_h = _polar(h)
            d = _rot_y(_rot_z(a, -phi_h), -theta_h)
            return [theta_h, phi_h, *_polar(d)]
        hbar, phi_h = mp.sqrt(h[0] ** 2 + h[1] ** 2), _azimuth(h[1], h[0])
        phi_k = _azimuth(k[1], k[0])
        if name == "orthographic":
            return [hbar, phi_h, mp.sqrt(k[0] ** 2 + k[1] ** 2), phi_k]
        if name == "hybrid":
            return [hbar, phi_h, _norm(k), phi_k]
        raise KeyError(name)


def inverse(name: str, coords: Sequence[Any]) -> tuple[Vec, Vec]:
    """Exact directions of coordinates (floats or mpf), projected onto the closed
    upper hemisphere where they fall outside the domain."""
    with mp.workdps(DIGITS):
        c = [mp.mpf(x) for x in coords]
        if name == "spherical":
            ti, to = (min(max(t, mp.mpf(0)), mp.pi / 2) for t in (c[0], c[2]))
            wi = [mp.sin(ti) * mp.cos(c[1]), mp.sin(ti) * mp.sin(c[1]), mp.cos(ti)]
            wo = [mp.sin(to) * mp.cos(c[3]), mp.sin(to) * mp.sin(c[3]), mp.cos(to)]
        elif name == "rusinkiewicz":
            theta_h, phi_h, theta_d, phi_d = c
            d = [mp.sin(theta_d) * mp.cos(phi_d), mp.sin(theta_d) * mp.sin(phi_d), mp.cos(theta_d)]
            wi = _rot_z(_rot_y(d, theta_h), phi_h)
            hhat = _rot_z(_rot_y([mp.mpf(0), mp.mpf(0), mp.mpf(1)], theta_h), phi_h)
            dot = sum(x * y for x, y in zip(wi, hhat, strict=True))
            wo = [2 * dot * y - x for x, y in zip(wi, hhat, strict=True)]
        elif name == "orthographic":
            hb, ph, kb, pk = c
            h = [hb * mp.cos(ph), hb * mp.sin(ph)]
            k = [kb * mp.cos(pk), kb * mp.sin(pk)]
            wi, wo = (_lift([h[0] + s * k[0], h[1] + s * k[1]]) for s in (1, -1))
        elif name == "hybrid":
            hb, ph, kn, pk = c
            hz = mp.sqrt(max(1 - kn * kn - hb * hb, mp.mpf(0)))
            a = hb * mp.cos(ph - pk)
            theta_k = mp.pi / 2 if hz == 0 and a == 0 else mp.atan2(hz, -a)
            kz = kn * mp.cos(theta_k)
            kbar = kn * mp.sin(theta_k)
            if abs(kz) > hz:  # outside the domain: the nearest pair keeps ‖k‖
                kz = hz if kz > 0 else -hz
                kbar = mp.sqrt(max(kn * kn - hz * hz, mp.mpf(0)))
            h = [hb * mp.cos(ph), hb * mp.sin(ph), hz]
            k = [kbar * mp.cos(pk), kbar * mp.sin(pk), kz]
            wi = [x + y for x, y in zip(h, k, strict=True)]
            wo = [x - y for x, y in zip(h, k, strict=True)]
        else:
            raise KeyError(name)
        return _to_hemisphere(wi), _to_hemisphere(wo)


def _lift(t: list[Any]) -> Vec:
    r2 = t[0] ** 2 + t[1] ** 2
    if r2 >= 1:
        r = mp.sqrt(r2)
        return [t[0] / r, t[1] / r, mp.mpf(0)]
    return [t[0], t[1], mp.sqrt(1 - r2)]


def distance(a: Vec, w: Sequence[float]) -> float:
    """Euclidean distance between an exact vector and a float64 one."""
    with mp.workdps(DIGITS):
        return float(mp.sqrt(sum((x - mp.mpf(float(y))) ** 2 for x, y in zip(a, w, strict=True))))


def _half_ulp(x: float) -> Any:
    return mp.mpf(float(np.spacing(abs(x)))) / 2


def roundtrip_bound(name: str, wi: Sequence[float], wo: Sequence[float]) -> float:
    """The round-trip error float64 coordinates cannot avoid at this pair.

    Each exact coordinate is known to float64 only within half an ulp; this is the
    largest max(‖ωi' − ωi‖, ‖ωo' − ωo‖) over the exact inverses of the exact
    coordinates moved by ±half an ulp (all sign patterns, and no move), each plus
    the half ulps of rounding the resulting directions to float64.
    """
    with mp.workdps(DIGITS):
        exact = forward(name, wi, wo)
        steps = [_half_ulp(float(c)) for c in exact]
        worst = 0.0
        for signs in itertools.product((-1, 1), repeat=4):
            moved = [c + s * h for c, s, h in zip(exact, signs, steps, strict=True)]
            worst = max(worst, _error(name, moved, wi, wo))
        return max(worst, _error(name, exact, wi, wo))


def _error(name: str, coords: Sequence[Any], wi: Sequence[float], wo: Sequence[float]) -> float:
    """The error of the exact inverse, plus the half ulps its float64 output must lose."""
    a, b = inverse(name, coords)
    return max(distance(a, wi) + _output_rounding(a), distance(b, wo) + _output_rounding(b))


def _output_rounding(v: Vec) -> float:
    return float(np.sqrt(sum(float(_half_ulp(float(x))) ** 2 for x in v)))


def roundtrip_bounds(name: str, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
    """`roundtrip_bound` over (n, 3) arrays (a loop: this is the slow reference)."""
    return np.array([roundtrip_bound(name, a, b) for a, b in zip(wi, wo, strict=True)])


#: The step (radians of arc) of `tangent_jacobian`'s central differences: at ``DIGITS``
#: digits their truncation error is about (step/d)² relative at distance d from a
#: singular configuration, their rounding 10^-DIGITS/step.
JACOBIAN_STEP = mp.mpf("1e-20")


def tangent_jacobian(name: str, wi: Sequence[float], wo: Sequence[float], frame: Any) -> Any:
    """∂c/∂s (4 × 4 floats) along the four tangent vectors ``frame`` (6, 4), the columns
    split into ωi's rows and ωo's rows: central differences of `forward_unit` with
    `JACOBIAN_STEP`, on the exactly normalized pair moved as (ω + s e)/‖ω + s e‖."""
    with mp.workdps(DIGITS):
        a, b = _vec(wi), _vec(wo)
        out = np.zeros((4, 4))
        for j in range(4):
            e_i = [mp.mpf(float(x)) for x in frame[:3, j]]
            e_o = [mp.mpf(float(x)) for x in frame[3:, j]]
            ends = []
            for s in (JACOBIAN_STEP, -JACOBIAN_STEP):
                moved_i = [x + s * y for x, y in zip(a, e_i, strict=True)]
                moved_o = [x + s * y for x, y in zip(b, e_o, strict=True)]
                unit_i = [x / _norm(moved_i) for x in moved_i]
                unit_o = [x / _norm(moved_o) for x in moved_o]
                ends.append(forward_unit(name, unit_i, unit_o))
            for row in range(4):
                diff = ends[0][row] - ends[1][row]
                if row in (1, 3):  # azimuths: the difference modulo 2π, in (−π, π]
                    diff -= 2 * mp.pi * mp.floor((diff + mp.pi) / (2 * mp.pi))
                out[row, j] = float(diff / (2 * JACOBIAN_STEP))
        return out
