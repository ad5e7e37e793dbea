"""``--format merl``: a reconstruction tabulated in MERL's binary layout
(`gonio.brdf.merl`, docs/reference/formats.md#merl).

Each bin holds the reconstruction evaluated at the bin's representative pair: the pair
with φh = 0 at the bin's centre in index coordinates, θh = ((i + ½)/90)²·π/2,
θd = (j + ½)·π/180, φd = (k + ½)·π/180 (`gonio.brdf.merl.bin_centres`), which MERL's
own index mapping sends back to the bin (a bin's lower corner does not always: float
rounding of the square root can land in the bin below). Written missing (negative):
bins whose centre has no direction pair (a direction below the horizon), and bins
whose pair lies outside the measured support unless the reconstruction's extrapolation
is asked for (``fill="extrapolate"``). A one-channel reconstruction is written grey
(the same values in red, green and blue); negative or non-finite values of the
reconstruction are written 0 and missing respectively (a negative value would read as
missing).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from gonio.brdf import merl
from gonio.errors import GonioError
from gonio.export.steps import evaluated, reconstructed, sparse_note, step
from gonio.output import PendingOutput
from gonio.params import DOMAIN_TOLERANCE
from gonio.store import Run
from gonio.types import BoolArray, FloatArray, Surface

if TYPE_CHECKING:
    from gonio.export import Options


@dataclass(frozen=True)
class Table:
    """The filled table: ``values`` (3, 90, 90, 180) in sr⁻¹, ``missing`` (90, 90, 180),
    and how many bins have no pair, lie outside the support, or were extrapolated."""

    values: FloatArray
    missing: BoolArray
    no_pair: int
    unsupported: int
    extrapolated: int


def representative_pairs() -> tuple[FloatArray, FloatArray, BoolArray]:
    """(ωi, ωo) (90, 90, 180, 3) at every bin's centre, and where that pair exists
    (elsewhere the pair is a placeholder, ωi = ωo = n).

    Rusinkiewicz's inverse at φh = 0 (`gonio.params`' ``rusinkiewicz``, bit for bit):
    d̂ = (sin θd cos φd, sin θd sin φd, cos θd) turned by θh about y, ωo its mirror
    about ĥ; each angle's sine and cosine taken once along its own axis of the table
    (270 + 180 values, not 1.46 million per coordinate), the pair exists where both z
    components reach −`DOMAIN_TOLERANCE`."""
    theta_h, theta_d, phi_d = merl.bin_centres()
    st, ct = np.sin(theta_h), np.cos(theta_h)
    sd, cd = np.sin(theta_d), np.cos(theta_d)
    dx, dy = sd * np.cos(phi_d), sd * np.sin(phi_d)
    a, b = st * cd, ct * cd
    u, w = ct * dx, st * dx
    zi, zo = b - w, b + w
    ok = np.minimum(zi, zo) >= -DOMAIN_TOLERANCE
    wi = np.stack(np.broadcast_arrays(u + a, dy, np.maximum(zi, 0.0)), axis=-1)
    wo = np.stack(np.broadcast_arrays(a - u, -dy, np.maximum(zo, 0.0)), axis=-1)
    wi[~ok] = wo[~ok] = (0.0, 0.0, 1.0)
    return wi, wo, ok


def fill(reconstruction: Surface, *, extrapolate: bool = False) -> Table:
    """The reconstruction evaluated at every bin (see the module docstring)."""
    return _table(*_evaluated_bins(reconstruction), extrapolate=extrapolate)


def _evaluated_bins(reconstruction: Surface) -> tuple[FloatArray, BoolArray, BoolArray]:
    """The reconstruction at the bins that have a pair: values (M, 1 or 3) in sr⁻¹, where
    those pairs lie (90, 90, 180) and whether each is supported (M,)."""
    with step("the bins' direction pairs"):
        wi, wo, ok = representative_pairs()
    got, supported = evaluated(reconstruction, wi[ok], wo[ok], "filling the MERL table")
    if got.ndim == 1:
        got = got[:, None]
    if got.shape[1:] not in ((1,), (3,)):
        raise GonioError(
            f"the reconstruction gave values of shape {got.shape}, expected one or three channels"
        )
    return got, ok, np.ones(len(got), dtype=bool) if supported is None else supported


def _table(got: FloatArray, ok: BoolArray, supported: BoolArray, *, extrapolate: bool) -> Table:
    """The table of `_evaluated_bins`' values: each test made once per paired bin, and
    a grey value written to the three channels."""
    finite = np.all(np.isfinite(got), axis=1)
    good = finite & (supported | extrapolate)
    values = np.zeros((3, *ok.shape))
    values[:, ok] = np.where(good[:, None], np.maximum(got, 0.0), 0.0).T
    missing = np.ones(ok.shape, dtype=bool)
    missing[ok] = ~good
    return Table(
        values=values,
        missing=missing,
        no_pair=int(np.count_nonzero(~ok)),
        unsupported=int(np.count_nonzero(~supported)),
        extrapolated=int(np.count_nonzero(~supported & finite)) if extrapolate else 0,
    )


def write(
    out: PendingOutput,
    reconstruction: Surface,
    *,
    extrapolate: bool = False,
    allow_sparse: bool = False,
) -> str:
    """Fill the table and write it to ``out``; the one-line summary (and a warning line
    for a sparse run written with ``allow_sparse``; `sparse_note`, asked before the
    table is filled)."""
    got, ok, supported = _evaluated_bins(reconstruction)
    paired = int(np.count_nonzero(ok))
    supported_count = int(np.count_nonzero(supported))
    note = sparse_note(supported_count, paired, "MERL bins", allow=allow_sparse)
    table = _table(got, ok, supported, extrapolate=extrapolate)
    with step(f"writing {merl.FILE_SIZE / 1e6:.0f} MB"):
        out.write_bytes(merl.to_bytes(table.values, table.missing))
    written = merl.BINS - int(np.count_nonzero(table.missing))
    what = (
        f"{table.extrapolated} extrapolated"
        if extrapolate
        else f"{table.unsupported} outside the measured support written missing"
    )
    return (
        f"wrote {out.path} (MERL, {merl.FILE_SIZE} bytes): {written} of {merl.BINS} bins, "
        f"{table.no_pair} without a direction pair, {what}"
    ) + (f"\n{note}" if note else "")


def export_run(run: Run, out: PendingOutput, options: Options) -> str:
    extrapolate = options.merl_fill == "extrapolate"
    _, surface = reconstructed(
        run,
        options.method,
        extrapolate="nearest" if extrapolate else None,
        allow_sparse=options.allow_sparse,
    )
    return write(out, surface, extrapolate=extrapolate, allow_sparse=options.allow_sparse)
