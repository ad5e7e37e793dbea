"""``--format alta``: ALTA's text data format (docs/reference/formats.md#alta), so that ALTA's
fitters take a run's samples with their uncertainty.

The file (after ALTA's ``data_storage.cpp``, ``args.h`` and ``params.cpp``)::

    #DIM 3 1
    #PARAM_IN STARK_3D            (or RUSIN_TH_TD_PD)
    #PARAM_OUT INV_STERADIAN
    #VS 1
    # comment lines (a '#' then a space)
    x1 x2 x3 f dt                 one row per sample

``#VS 1``: each row ends with the half-width dt of a symmetric confidence interval
[f − dt, f + dt] on its (single) output; dt is the sample's 1σ uncertainty.

Input coordinates, as ALTA defines them (its ``CARTESIAN`` packs the view V = ωo first,
then the light L = ωi):

- ``STARK_3D``: ‖h̄‖ of H = (L + V)/2 projected on the tangent plane, ‖B‖ of
  B = (L − V)/2 (our k), and φB − φH in [0, 2π) (ALTA adds 2π to a negative difference
  of the two atan2).
- ``RUSIN_TH_TD_PD``: θh, θd, φd (rad) with the difference vector of V (ALTA rotates
  the view, where Rusinkiewicz and MERL rotate the light: φd differs by π, which
  reciprocity makes immaterial), φd in [0, 2π) (ALTA's own conversion gives atan2 in
  (−π, π]; the two agree modulo 2π, and ALTA's grid takes [0, 2π]).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from gonio import params
from gonio.analysis import Measured
from gonio.errors import GonioError
from gonio.export.steps import step
from gonio.output import PendingOutput
from gonio.store import Run
from gonio.types import FloatArray

if TYPE_CHECKING:
    from gonio.export import Options

TWO_PI = 2.0 * np.pi


def stark_3d(wi: FloatArray, wo: FloatArray) -> FloatArray:
    """(N, 3) ALTA ``STARK_3D`` coordinates: ‖h̄‖, ‖k‖, (φk − φh) mod 2π."""
    hbar, phi_h, k, phi_k = np.moveaxis(params.get("hybrid").forward(wi, wo), -1, 0)
    return np.stack([hbar, k, np.mod(phi_k - phi_h, TWO_PI)], axis=-1)


def rusin_th_td_pd(wi: FloatArray, wo: FloatArray) -> FloatArray:
    """(N, 3) ALTA ``RUSIN_TH_TD_PD`` coordinates: θh, θd, and φd of the view (ωo)
    rotated into the halfway frame, in [0, 2π)."""
    # Swapping the pair keeps ĥ and θd and gives ωo's difference vector.
    theta_h, _, theta_d, phi_d = np.moveaxis(params.get("rusinkiewicz").forward(wo, wi), -1, 0)
    return np.stack([theta_h, theta_d, np.mod(phi_d, TWO_PI)], axis=-1)


#: gonio's option name → (ALTA's name, the coordinates, their description).
PARAMETRIZATIONS = {
    "stark_3d": ("STARK_3D", stark_3d, "|hbar| |k| phi_k-phi_h[rad, 0..2pi]"),
    "rusin_th_td_pd": ("RUSIN_TH_TD_PD", rusin_th_td_pd, "theta_h theta_d phi_d[rad, of V]"),
}


def to_text(
    coords: FloatArray, f: FloatArray, sigma: FloatArray, param: str, comments: list[str]
) -> str:
    """The ALTA file of N samples: ``coords`` (N, 3), f and its 1σ (N,) in sr⁻¹."""
    name, _, columns = PARAMETRIZATIONS[param]
    head = ["#DIM 3 1", f"#PARAM_IN {name}", "#PARAM_OUT INV_STERADIAN", "#VS 1"]
    head += [f"# {c}" for c in comments]
    head.append(f"# columns: {columns} f[1/sr] sigma[1/sr]")
    table = np.column_stack([coords, f, sigma])
    rows = [" ".join(repr(v) for v in row) for row in table.tolist()]
    return "\n".join(head + rows) + "\n"


def export_run(run: Run, out: PendingOutput, options: Options) -> str:
    param = options.alta_param
    if param not in PARAMETRIZATIONS:
        raise GonioError(f"--alta-param {param}: expected one of {', '.join(PARAMETRIZATIONS)}")
    with step("reading and calibrating the run"):
        measured = Measured.from_run(run)
    if measured.is_rgb:  # pragma: no cover (a run is one band)
        raise GonioError(f"{run.path}: ALTA's confidence intervals cover one output only")
    coords = PARAMETRIZATIONS[param][1](measured.wi, measured.wo)
    comments = [
        f"gonio export of {run.path.name}: plan {run.meta.get('plan_name')!r}, "
        f"{len(measured)} samples, band {measured.band}",
        "dt = the sample's 1-sigma uncertainty (symmetric interval f - dt .. f + dt)",
    ]
    with step(f"writing {len(measured):,} samples"):
        out.write_bytes(to_text(coords, measured.f, measured.sigma, param, comments).encode())
    return f"wrote {len(measured)} samples to {out.path} (ALTA {PARAMETRIZATIONS[param][0]}, #VS 1)"
