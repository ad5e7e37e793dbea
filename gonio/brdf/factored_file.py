"""The two text files of a factored BRDF (Lawrence et al. 2004): tables, grid, I/O.

The factor file holds f(ωi, ωo) cos θi ≈ Σⱼ Fⱼ(θo, φo) Gⱼ(θp, φp), the inner split
Gⱼ ≈ Σₖ uⱼₖ(θp) vⱼₖ(φp) and the colour factors Fc, Gc; the CDF file the 1D CDFs of each
of the L = J·K terms over φp and z = 1 − cos θp. (θp, φp) are the polar angles of the
halfway vector ĥ = (ωi + ωo)/‖ωi + ωo‖ ("halfangle"). The layout, the bin conventions
and where they depart from the file-format notes are in docs/reference/formats_factored.md.

Every table is piecewise constant on equal bins: θo, θp on [0, π/2], φo, φp on
[0, 2π), z on [0, 1]. The CDF of bin b is its value at the bin's upper edge (the last
one is 1, the one below the first bin is an implicit 0).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt

from gonio.brdf.base import beyond_bound
from gonio.config import ConfigError
from gonio.types import FloatArray

IntArray = npt.NDArray[np.int64]

HALF_PI = 0.5 * np.pi
TWO_PI = 2.0 * np.pi
#: The suffix appended to the factor file's name to name its CDF file.
CDF_SUFFIX = ".cdf"

_HEADER = (
    ("param", "param"),
    ("outer", "outer terms ('J' in paper)"),
    ("inner", "inner terms ('K' in paper)"),
    ("theta_out_count", "theta_out_count"),
    ("phi_out_count", "phi_out_count"),
    ("theta_p_count", "theta_p_count"),
    ("z_count", "z_count"),
    ("phi_p_count", "phi_p_count"),
)


@dataclass(frozen=True)
class FactoredTables:
    """The arrays of both files (float64, ≥ 0). J outer, K inner terms, L = J·K.

    F (J, θo, φo), G (J, θp, φp), u (J, K, θp), v (J, K, φp), Fc (θo, φo, 3),
    Gc (θp, φp, 3), cdf_phi (L, φp), cdf_z (L, z); term (j, k) is row j·K + k.
    """

    F: FloatArray
    G: FloatArray
    u: FloatArray
    v: FloatArray
    Fc: FloatArray
    Gc: FloatArray
    cdf_phi: FloatArray
    cdf_z: FloatArray

    @property
    def outer(self) -> int:
        return int(self.F.shape[0])

    @property
    def inner(self) -> int:
        return int(self.u.shape[1])

    @property
    def z_count(self) -> int:
        return int(self.cdf_z.shape[1])


def bin_index(x: FloatArray, upper: float, count: int) -> IntArray:
    """The bin of x among ``count`` equal bins of [0, upper] (the ends clamp in)."""
    i = np.floor(x * (count / upper)).astype(np.int64)
    return np.clip(i, 0, count - 1)


def theta_edges(count: int) -> FloatArray:
    """The count + 1 bin edges of θ on [0, π/2]."""
    return np.linspace(0.0, HALF_PI, count + 1)


def cell_dz(count: int) -> FloatArray:
    """Δz = cos θ₀ − cos θ₁ of each θ bin: its solid angle per radian of azimuth."""
    return -np.diff(np.cos(theta_edges(count)))


def z_overlap(theta_count: int, z_count: int) -> FloatArray:
    """(z_count, theta_count): the length in z of z bin b inside θ bin a.

    z = 1 − cos θ; z bins are equal on [0, 1]. u(θ(z)) is piecewise constant in z on
    the images of the θ bins, so ``z_overlap @ u`` is its exact integral over each z bin.
    """
    ze = np.linspace(0.0, 1.0, z_count + 1)
    te = 1.0 - np.cos(theta_edges(theta_count))
    te[-1] = 1.0
    lo = np.maximum(ze[:-1, None], te[None, :-1])
    hi = np.minimum(ze[1:, None], te[None, 1:])
    return np.asarray(np.maximum(hi - lo, 0.0), dtype=np.float64)


def term_cdfs(u: FloatArray, v: FloatArray, z_count: int) -> tuple[FloatArray, FloatArray]:
    """(cdf_phi (L, φp), cdf_z (L, z)) of the terms uⱼₖ(θp(z)) vⱼₖ(φp).

    A term with no mass gets the uniform CDF (it is never selected: its energy is 0).
    """
    j, k, ntp = u.shape
    uz = u.reshape(j * k, ntp) @ z_overlap(ntp, z_count).T
    return _cumulative(v.reshape(j * k, -1)), _cumulative(uz)


def _cumulative(mass: FloatArray) -> FloatArray:
    c = np.cumsum(mass, axis=1)
    total = c[:, -1:]
    uniform = np.arange(1, mass.shape[1] + 1, dtype=np.float64) / mass.shape[1]
    ok = total > 0.0
    out = np.where(ok, c / np.where(ok, total, 1.0), uniform[None, :])
    out[:, -1] = 1.0
    return np.asarray(out, dtype=np.float64)


# -- writing -----------------------------------------------------------------------------


def _rows(a: FloatArray) -> str:
    return "".join(" ".join(f"{x:.17g}" for x in row) + "\n" for row in np.atleast_2d(a))


def format_factors(t: FactoredTables) -> str:
    """The factor file's text."""
    j, k = t.outer, t.inner
    counts = (j, k, *t.F.shape[1:], t.G.shape[1], t.z_count, t.G.shape[2])
    out = ["# factored BRDF (Lawrence et al. 2004) by gonio: docs/reference/formats_factored.md\n"]
    out.append("param: halfangle\n")
    out.extend(f"{label}: {n}\n" for (_, label), n in zip(_HEADER[1:], counts, strict=True))
    out.append("INTENSITY DATA\n")
    for jj in range(j):
        out.append(f"F_{jj}\n{_rows(t.F[jj])}G_{jj}\n{_rows(t.G[jj])}")
        for kk in range(k):
            out.append(f"u_{jj}_{kk}\n{_rows(t.u[jj, kk])}v_{jj}_{kk}\n{_rows(t.v[jj, kk])}")
    out.append("COLOR DATA\n")
    out.append(f"Fc\n{_rows(t.Fc.reshape(t.Fc.shape[0], -1))}")
    out.append(f"Gc\n{_rows(t.Gc.reshape(t.Gc.shape[0], -1))}")
    out.append("EOF\n")
    return "".join(out)


def format_cdfs(t: FactoredTables) -> str:
    """The CDF file's text."""
    out = ["# factored BRDF CDFs by gonio, term j*K + k: docs/reference/formats_factored.md\n"]
    out.append("CDF DATA\n")
    for i in range(t.cdf_phi.shape[0]):
        out.append(f"P(phi_p|term {i})\n{_rows(t.cdf_phi[i])}P(z|term {i})\n{_rows(t.cdf_z[i])}")
    out.append("EOF\n")
    return "".join(out)


# -- reading -----------------------------------------------------------------------------


class _Lines:
    """The meaningful lines of a file (no blanks, no # comments), with their numbers."""

    def __init__(self, path: Path) -> None:
        self.path = path
        try:
            text = path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as exc:
            raise ConfigError(f"{path}: cannot read it: {exc}") from None
        #: How many numbers the file could hold at most (every value is one word).
        self.words = len(text.split())
        lines = enumerate(text.splitlines(), 1)
        self._it: Iterator[tuple[int, str]] = (
            (n, s.strip()) for n, s in lines if s.strip() and not s.lstrip().startswith("#")
        )
        self.number = 0

    def error(self, what: str) -> ConfigError:
        return ConfigError(f"{self.path}:{self.number}: {what}")

    def next(self, expected: str) -> str:
        try:
            self.number, line = next(self._it)
        except StopIteration:
            raise ConfigError(f"{self.path}: ends early; expected {expected}") from None
        return line

    def keyword(self, word: str) -> None:
        if self.next(word) != word:
            raise self.error(f"expected {word!r}")

    def field(self, label: str) -> str:
        line = self.next(f"'{label}: …'")
        key, sep, value = line.partition(":")
        if not sep or key.strip() != label:
            raise self.error(f"expected '{label}: …', got {line!r}")
        return value.strip()

    def count(self, label: str) -> int:
        value = self.field(label)
        if not value.isdigit() or len(value) > 12 or int(value) < 1:
            raise self.error(f"{label}: expected a positive integer, got {value[:40]!r}")
        return int(value)

    def table(self, name: str, rows: int, cols: int, *, cdf: bool = False) -> FloatArray:
        self.keyword(name)
        out = np.empty((rows, cols), dtype=np.float64)
        for r in range(rows):
            line = self.next(f"row {r} of {name}")
            try:
                out[r] = np.array(line.split(), dtype=np.float64)
            except ValueError:
                raise self.error(f"{name}: expected {cols} numbers on row {r}") from None
            if not np.all(np.isfinite(out[r])) or np.any(out[r] < 0.0):
                raise self.error(f"{name}: expected finite values ≥ 0")
            absurd = beyond_bound(out[r])
            if absurd is not None:
                raise self.error(f"{name}: row {r}: {absurd}")
        if cdf and (np.any(np.diff(out[0]) < 0.0) or abs(out[0, -1] - 1.0) > 1e-9):
            raise self.error(f"{name}: expected a non-decreasing CDF ending at 1")
        return out


def read(path: Path | str) -> FactoredTables:
    """Both files: ``path`` and ``path`` + `CDF_SUFFIX`. ConfigError (one line) if malformed."""
    p = Path(path)
    lines = _Lines(p)
    param = lines.field("param")
    if param != "halfangle":
        raise lines.error(f"param: expected 'halfangle' (the only one supported), got {param!r}")
    j, k, nto, npo, ntp, nz, npp = (lines.count(label) for _, label in _HEADER[1:])
    # Every size the header states is bounded by what the file holds before anything is
    # allocated: a header asking for 10⁹ × 10⁹ cells is one line, not an allocation.
    stated = j * (nto * npo + ntp * npp + k * (ntp + npp)) + 3 * (nto * npo + ntp * npp)
    if stated > lines.words:
        raise ConfigError(
            f"{p}: the header states {stated:,} values; the file holds at most "
            f"{lines.words:,} numbers (truncated, or a wrong header)"
        )
    lines.keyword("INTENSITY DATA")
    F, G = np.empty((j, nto, npo)), np.empty((j, ntp, npp))
    u, v = np.empty((j, k, ntp)), np.empty((j, k, npp))
    for jj in range(j):
        F[jj] = lines.table(f"F_{jj}", nto, npo)
        G[jj] = lines.table(f"G_{jj}", ntp, npp)
        for kk in range(k):
            u[jj, kk] = lines.table(f"u_{jj}_{kk}", 1, ntp)[0]
            v[jj, kk] = lines.table(f"v_{jj}_{kk}", 1, npp)[0]
    lines.keyword("COLOR DATA")
    Fc = lines.table("Fc", nto, 3 * npo).reshape(nto, npo, 3)
    Gc = lines.table("Gc", ntp, 3 * npp).reshape(ntp, npp, 3)
    lines.keyword("EOF")
    cdf = _Lines(p.with_name(p.name + CDF_SUFFIX))
    if j * k * (npp + nz) > cdf.words:
        raise ConfigError(
            f"{cdf.path}: the header of {p.name} states {j * k * (npp + nz):,} CDF values; "
            f"the file holds at most {cdf.words:,} numbers"
        )
    cdf.keyword("CDF DATA")
    cdf_phi, cdf_z = np.empty((j * k, npp)), np.empty((j * k, nz))
    for i in range(j * k):
        cdf_phi[i] = cdf.table(f"P(phi_p|term {i})", 1, npp, cdf=True)[0]
        cdf_z[i] = cdf.table(f"P(z|term {i})", 1, nz, cdf=True)[0]
    cdf.keyword("EOF")
    return FactoredTables(F=F, G=G, u=u, v=v, Fc=Fc, Gc=Gc, cdf_phi=cdf_phi, cdf_z=cdf_z)
