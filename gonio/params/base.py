"""The interface every BRDF parametrization implements, and its shared machinery.

A parametrization maps a pair of unit directions (ωi, ωo) in the closed upper
hemisphere to four coordinates and back. Subclasses implement the maps on
component arrays (``_forward``, ``_inverse``, ``_reduce``, ``_expand``); this class
handles shapes, broadcasting, validation and the isotropic reduction.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import ClassVar, NoReturn

import numpy as np

from gonio.directions import pair_components
from gonio.errors import DomainError
from gonio.params._arrays import as_coordinates, components, stack
from gonio.types import ArrayLike, BoolArray, FloatArray

#: Rounding margin of the closed domain. Coordinates computed in float64 from a valid
#: pair can lie outside the exact domain by a few ulps; `valid` accepts them and
#: `inverse` projects them onto the domain (directions with z ≥ 0, exactly).
DOMAIN_TOLERANCE = 64.0 * np.finfo(np.float64).eps

#: Coordinates larger than this in magnitude are never valid (radii are ≤ 1, and an
#: azimuth of 1e100 rad has no digits left modulo 2π); it keeps squares from overflowing.
COORDINATE_LIMIT = 1e100

Parts = tuple[FloatArray, ...]


class Parametrization(ABC):
    """A bijection between direction pairs and four coordinates (see module docstring).

    Attributes:
        name: registry name.
        names: the four coordinate names, in order.
        bounds: (4, 2) array, the coordinate box [low, high] the planner samples.
        iso_names, iso_bounds: the same for the isotropic reduction (three coordinates).
        iso_symmetry: which symmetries the isotropic reduction assumes.
    """

    name: ClassVar[str]
    names: ClassVar[tuple[str, str, str, str]]
    bounds: ClassVar[FloatArray]
    iso_names: ClassVar[tuple[str, str, str]]
    iso_bounds: ClassVar[FloatArray]
    iso_symmetry: ClassVar[str]

    # -- public API -------------------------------------------------------------------
    def forward(self, wi: ArrayLike, wo: ArrayLike) -> FloatArray:
        """Coordinates (..., 4) of unit directions ``wi``, ``wo`` (..., 3), z ≥ 0.

        Raises ``DomainError`` for directions that are not finite unit vectors in the
        closed upper hemisphere (`gonio.directions.pair_components`).
        """
        lead, a, b = pair_components(wi, wo)
        return stack(lead, *self._forward(a, b))

    def inverse(self, coords: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Directions (wi, wo), each (..., 3), of coordinates (..., 4).

        Raises ``DomainError`` if any row is not `valid`: the inverse never returns NaN.
        """
        c = as_coordinates(coords, 4)
        return self._checked_inverse(components(c), c.shape[:-1])

    def valid(self, coords: ArrayLike) -> BoolArray:
        """True where the coordinates map to two directions in the closed upper hemisphere.

        Azimuths are periodic: any value up to `COORDINATE_LIMIT` in magnitude is
        accepted. The domain is closed up to `DOMAIN_TOLERANCE` (see there); non-finite
        coordinates are never valid.
        """
        c = as_coordinates(coords, 4)
        return self._valid_parts(components(c)).reshape(c.shape[:-1])

    def forward_iso(self, wi: ArrayLike, wo: ArrayLike) -> FloatArray:
        """Isotropic coordinates (..., 3): the pair's azimuth rotated out (see `iso_symmetry`)."""
        lead, a, b = pair_components(wi, wo)
        return stack(lead, *self._reduce(self._forward(a, b)))

    def inverse_iso(self, coords3: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """A direction pair with the given isotropic coordinates (..., 3).

        The rotated-out azimuth is 0 (φh = 0, or φi = 0 for spherical).
        """
        c = as_coordinates(coords3, 3)
        return self._checked_inverse(self._expand(components(c)), c.shape[:-1])

    def valid_iso(self, coords3: ArrayLike) -> BoolArray:
        """`valid` for isotropic coordinates (..., 3)."""
        c = as_coordinates(coords3, 3)
        return self._valid_parts(self._expand(components(c))).reshape(c.shape[:-1])

    def __repr__(self) -> str:
        return f"<parametrization {self.name!r}: {', '.join(self.names)}>"

    # -- shared machinery -------------------------------------------------------------
    @staticmethod
    def _usable(parts: Parts) -> BoolArray:
        """Finite and below `COORDINATE_LIMIT` in magnitude (NaN compares False)."""
        ok = np.abs(parts[0]) <= COORDINATE_LIMIT
        for p in parts[1:]:
            ok &= np.abs(p) <= COORDINATE_LIMIT
        return ok

    def _valid_parts(self, parts: Parts) -> BoolArray:
        # The mask comes from the inverse itself, so `valid` and `inverse` never disagree.
        usable = self._usable(parts)
        _, ok = self._inverse(tuple(np.where(usable, p, 0.0) for p in parts))
        return np.asarray(ok & usable, dtype=np.bool_)

    def _checked_inverse(
        self, parts: Parts, lead: tuple[int, ...]
    ) -> tuple[FloatArray, FloatArray]:
        usable = self._usable(parts)
        if not usable.all():  # checked first: the math below never meets inf, NaN, overflow
            self._raise_invalid(parts, lead, usable)
        out, ok = self._inverse(parts)
        if not ok.all():
            self._raise_invalid(parts, lead, ok)
        return stack(lead, *out[:3]), stack(lead, *out[3:])

    def _raise_invalid(self, parts: Parts, lead: tuple[int, ...], ok: BoolArray) -> NoReturn:
        ok = ok & self._valid_parts(parts)
        flat = int(np.argmin(ok))
        index = tuple(int(i) for i in np.unravel_index(flat, lead))
        first = [float(p[flat]) for p in parts]
        raise DomainError(
            f"{ok.size - int(np.count_nonzero(ok))} of {ok.size} coordinate rows are "
            f"outside the valid domain of {self.name!r} ({', '.join(self.names)}); "
            f"first at index {index}: {first}"
        )

    # -- what each parametrization implements -----------------------------------------
    # Every hook works on tuples of 1-d component arrays: a direction is (x, y, z), a
    # coordinate row (c0, c1, c2, c3), a reduced row (r0, r1, r2).
    @abstractmethod
    def _forward(self, wi: Parts, wo: Parts) -> Parts:
        """Four coordinate arrays from the components of ωi and ωo."""

    @abstractmethod
    def _inverse(self, c: Parts) -> tuple[Parts, BoolArray]:
        """Six direction components (xi, yi, zi, xo, yo, zo) from finite coordinates, and
        the domain mask computed along the way (`valid` is this mask; rows where it is
        False are never returned)."""

    @abstractmethod
    def _reduce(self, c: Parts) -> Parts:
        """Three isotropic coordinates from four."""

    def _expand(self, r: Parts) -> Parts:
        """Four coordinates from three, the rotated-out azimuth (the second) set to 0."""
        return r[0], np.zeros_like(r[0]), r[1], r[2]
