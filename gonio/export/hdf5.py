"""``--format hdf5``: the whole run in one HDF5 file, readable with plain h5py
(docs/reference/formats.md#hdf5).

Layout (every unit and convention an attribute beside the data it describes)::

    /                 attrs: format = "gonio-run", format_version = 1, gonio_version,
                      source (the run file's name), conventions (frame, directions, units)
    /meta             one scalar string per journal metadata key: its value as JSON text
    /plan             attrs: parametrization, isotropic, coordinate_names (JSON);
                      datasets: stored (the ``# gonio-plan v1`` file's bytes, uint8),
                      coords (M, d), wi, wo (M, 3), angles (M, A) rad, exposure_s,
                      averages, travel_s, arrival_s (M,)
    /samples          one (N,) dataset per column (`gonio.export.columns`), attrs
                      units, description
    /events           (E,) datasets id, session, kind, target (−1: none), t_s, utc,
                      data (JSON text)
    /sessions         (S,) datasets id, started_utc, ended_utc (""), outcome (""), info
                      (JSON text)
    /reconstruction   optional (`grid`): axes (one dataset per coordinate, rad or
                      unitless), values (n, n, n[, 3]) in sr⁻¹, NaN where the
                      coordinates have no direction pair, supported (bool)

Strings are UTF-8 variable-length strings; JSON text keeps nested metadata whole.
"""

from __future__ import annotations

import json
from typing import TYPE_CHECKING, Any

import numpy as np

from gonio import __version__, params
from gonio.errors import GonioError
from gonio.export.columns import coordinate_unit, sample_columns
from gonio.export.steps import evaluated, reconstructed, sparse_note, step
from gonio.output import PendingOutput
from gonio.planner import ARRAYS, plan_bytes
from gonio.store import Run
from gonio.types import Evaluable, FloatArray

if TYPE_CHECKING:
    from pathlib import Path

    from gonio.export import Options

CONVENTIONS = (
    "sample frame: z = surface normal, x = the sample's reference mark, y = z × x; "
    "directions are unit vectors pointing away from the surface, wi toward the light, "
    "wo toward the detector; angles in radians, azimuths in [0, 2π); BRDF values in sr^-1, "
    "cosine factor excluded; times in seconds (run time) or ISO 8601 UTC"
)


def _h5py() -> Any:
    try:
        import h5py  # optional: the hdf5 extra
    except ImportError:
        raise GonioError("--format hdf5 needs h5py: pip install 'gonio[hdf5]'") from None
    return h5py


def _strings(h5py: Any, group: Any, name: str, values: list[str]) -> None:
    group.create_dataset(name, data=np.array(values, dtype=object), dtype=h5py.string_dtype())


def write_run(h5: Any, run: Run) -> None:
    """The run's metadata, plan, samples, events and sessions into the open file."""
    h5py = _h5py()
    h5.attrs.update(
        format="gonio-run",
        format_version=1,
        gonio_version=__version__,
        source=run.path.name,
        conventions=CONVENTIONS,
    )
    meta = h5.create_group("meta")
    for key, value in run.meta.items():  # datasets: attributes are limited to 64 kB
        meta.create_dataset(
            key, data=json.dumps(value, ensure_ascii=False), dtype=h5py.string_dtype()
        )

    plan = h5.create_group("plan")
    plan.attrs.update(
        parametrization=run.plan.spec.parametrization,
        isotropic=run.plan.spec.isotropic,
        coordinate_names=json.dumps(list(run.plan.coordinate_names)),
        angles_axes=json.dumps(list(run.axes)),
    )
    plan.create_dataset("stored", data=np.frombuffer(plan_bytes(run.plan), dtype=np.uint8))
    for name in ARRAYS:
        plan.create_dataset(name, data=np.asarray(getattr(run.plan, name)))
    plan["coords"].attrs["units"] = json.dumps(
        [coordinate_unit(n) for n in run.plan.coordinate_names]
    )
    for name in ("angles", "travel_s", "arrival_s", "exposure_s"):
        plan[name].attrs["units"] = "rad" if name == "angles" else "s"

    samples = h5.create_group("samples")
    for column in sample_columns(run):
        if column.values.dtype.kind in "OU":
            _strings(h5py, samples, column.key, [str(v) for v in column.values])
        else:
            samples.create_dataset(column.key, data=column.values)
        samples[column.key].attrs.update(units=column.unit, description=column.description)

    events = h5.create_group("events")
    evs = run.events
    events.create_dataset("id", data=np.array([e.id for e in evs], dtype=np.int64))
    events.create_dataset("session", data=np.array([e.session for e in evs], dtype=np.int64))
    _strings(h5py, events, "kind", [e.kind for e in evs])
    events.create_dataset(
        "target", data=np.array([-1 if e.target is None else e.target for e in evs], np.int64)
    )
    events.create_dataset("t_s", data=np.array([e.t_s for e in evs], dtype=np.float64))
    events["t_s"].attrs["units"] = "s"
    _strings(h5py, events, "utc", [e.utc for e in evs])
    _strings(h5py, events, "data", [json.dumps(dict(e.data), ensure_ascii=False) for e in evs])

    sessions = h5.create_group("sessions")
    ss = run.sessions
    sessions.create_dataset("id", data=np.array([s.id for s in ss], dtype=np.int64))
    _strings(h5py, sessions, "started_utc", [s.started_utc for s in ss])
    _strings(h5py, sessions, "ended_utc", [s.ended_utc or "" for s in ss])
    _strings(h5py, sessions, "outcome", [s.outcome or "" for s in ss])
    _strings(h5py, sessions, "info", [json.dumps(dict(s.info), ensure_ascii=False) for s in ss])


def grid_axes(parametrization: str, points: int) -> list[FloatArray]:
    """The regular grid's axes: ``points`` cell centres across each isotropic coordinate's
    bounds (so no node sits on a bound where the coordinates degenerate)."""
    bounds = params.get(parametrization).iso_bounds
    steps = (np.arange(points, dtype=np.float64) + 0.5) / points
    return [lo + steps * (hi - lo) for lo, hi in bounds]


def write_grid(
    h5: Any, model: Evaluable, parametrization: str, points: int, *, allow_sparse: bool = False
) -> str:
    """``model`` evaluated on the regular grid of ``parametrization``'s isotropic
    coordinates, into ``/reconstruction`` (see the module docstring); a warning line
    when the run supports too little of it and ``allow_sparse`` (`sparse_note`)."""
    if points < 2:
        raise GonioError(f"--grid-points {points}: expected at least 2")
    p = params.get(parametrization)
    axes = grid_axes(parametrization, points)
    coords = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)
    ok = p.valid_iso(coords)
    wi, wo = p.inverse_iso(np.where(ok[..., None], coords, [a[0] for a in axes]))
    values, supported = evaluated(model, wi, wo, f"evaluating the {parametrization} grid")
    note = ""
    if supported is not None:
        paired = int(np.count_nonzero(ok))
        held = int(np.count_nonzero(supported & ok))
        note = sparse_note(held, paired, f"{parametrization} grid's nodes", allow=allow_sparse)
    mask = ok[..., None] if values.ndim == ok.ndim + 1 else ok
    group = h5.create_group("reconstruction")
    group.attrs.update(
        parametrization=parametrization,
        coordinate_names=json.dumps(list(p.iso_names)),
        symmetry=p.iso_symmetry,
        nodes="cell centres: lo + (i + 0.5)(hi - lo)/n per coordinate",
    )
    for name, axis in zip(p.iso_names, axes, strict=True):
        group.create_dataset(f"axes/{name}", data=axis)
        group[f"axes/{name}"].attrs["units"] = coordinate_unit(name)
    group.create_dataset("values", data=np.where(mask, values, np.nan))
    group["values"].attrs["units"] = "sr^-1"
    if supported is not None:
        group.create_dataset("supported", data=supported & ok)
    return note


def write(
    path: Path,
    run: Run,
    model: Evaluable | None = None,
    parametrization: str = "hybrid",
    points: int = 32,
    *,
    allow_sparse: bool = False,
) -> str:
    """The HDF5 file of ``run`` at ``path``, with ``model`` (the run's reconstruction)
    on the grid of ``parametrization`` when given; `write_grid`'s warning line."""
    h5py = _h5py()
    with h5py.File(path, "w") as h5:
        write_run(h5, run)
        if model is not None:
            return write_grid(h5, model, parametrization, points, allow_sparse=allow_sparse)
    return ""


def export_run(run: Run, out: PendingOutput, options: Options) -> str:
    _h5py()
    if options.grid is not None:
        grid = options.grid
        _, surface = reconstructed(run, options.method, grid, allow_sparse=options.allow_sparse)
        notes: list[str] = []

        def write_to(path: Path) -> None:
            notes.append(
                write(
                    path, run, surface, grid, options.grid_points, allow_sparse=options.allow_sparse
                )
            )

        out.write_with(write_to)
        return (
            f"wrote {len(run)} samples, {len(run.events)} events, the plan and the "
            f"{options.method} reconstruction on a {options.grid_points}-point {grid} grid "
            f"to {out.path} (hdf5)"
        ) + "".join(f"\n{n}" for n in notes if n)

    def write_samples(path: Path) -> None:
        write(path, run)

    with step(f"writing {len(run):,} samples"):
        out.write_with(write_samples)
    return f"wrote {len(run)} samples, {len(run.events)} events and the plan to {out.path} (hdf5)"
