"""`gonio export --format hdf5`, read back with plain h5py from the layout in
docs/reference/formats.md; the optional reconstruction grid with an analytic model."""

from __future__ import annotations

import json
from pathlib import Path

import h5py
import numpy as np
import pytest

from gonio import brdf, params
from gonio.analysis.calibrated import calibrate
from gonio.analysis.measured import Measured
from gonio.cli import main
from gonio.export.hdf5 import write
from gonio.planner.stored import parse_plan
from gonio.reconstruct.methods import reconstruction
from gonio.store import open_run


@pytest.fixture(scope="module")
def out(run_file: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("hdf5") / "run.h5"
    assert main(["export", str(run_file), "--format", "hdf5", "-o", str(path), "-q"]) == 0
    return path


def test_root_attributes_and_groups(out):
    with h5py.File(out, "r") as h5:
        assert h5.attrs["format"] == "gonio-run" and h5.attrs["format_version"] == 1
        assert "z = surface normal" in h5.attrs["conventions"]
        assert set(h5) == {"meta", "plan", "samples", "events", "sessions"}


def test_samples_with_units_are_the_runs(out, run_file):
    run = open_run(run_file)
    with h5py.File(out, "r") as h5:
        s = h5["samples"]
        np.testing.assert_array_equal(s["target"][()], run.target)
        np.testing.assert_array_equal(s["counts"][()], run.samples["counts"])
        np.testing.assert_array_equal(s["brdf_per_sr"][()], calibrate(run).brdf)
        assert s["brdf_per_sr"].attrs["units"] == "sr^-1"
        assert s["exposure_s"].attrs["units"] == "s"
        assert s["wi_z"].attrs["units"] == ""
        assert s["saturated"].dtype == np.bool_
        assert s["utc"].asstr()[0] == run.samples["utc"][0]


def test_metadata_plan_events_and_sessions(out, run_file):
    run = open_run(run_file)
    with h5py.File(out, "r") as h5:
        meta = {k: json.loads(v.asstr()[()]) for k, v in h5["meta"].items()}
        assert meta == json.loads(json.dumps(dict(run.meta)))
        stored = h5["plan/stored"][()].tobytes()
        assert stored.startswith(b"# gonio-plan v1")
        assert parse_plan(stored, "stored") == run.plan
        np.testing.assert_array_equal(h5["plan/angles"][()], run.plan.angles)
        assert h5["plan"].attrs["parametrization"] == "hybrid"
        assert list(h5["events/kind"].asstr()[()]) == [e.kind for e in run.events]
        assert json.loads(h5["events/data"].asstr()[0]) == json.loads(
            json.dumps(dict(run.events[0].data))
        )
        assert list(h5["sessions/outcome"].asstr()[()]) == ["completed"]


class _Supported:
    """An analytic model with a synthetic measured support (θi, θo < 60°)."""

    def __init__(self) -> None:
        self.model = brdf.create("cook_torrance", alpha=0.3, kd=(0.5, 0.3, 0.2), f0=0.04)

    def eval(self, wi, wo):
        return self.model.eval(wi, wo)

    def supported(self, wi, wo):
        return (np.asarray(wi)[..., 2] > 0.5) & (np.asarray(wo)[..., 2] > 0.5)


def test_the_reconstruction_grid_at_cell_centres(run_file, tmp_path):
    path = tmp_path / "grid.h5"
    model = _Supported()
    write(path, open_run(run_file), model, "rusinkiewicz", 6)
    with h5py.File(path, "r") as h5:
        g = h5["reconstruction"]
        assert g.attrs["parametrization"] == "rusinkiewicz"
        names = json.loads(g.attrs["coordinate_names"])
        assert names == ["theta_h", "theta_d", "phi_d"]
        axes = [g[f"axes/{n}"][()] for n in names]
        values, supported = g["values"][()], g["supported"][()]
    half_pi = np.pi / 2
    np.testing.assert_allclose(axes[0], (np.arange(6) + 0.5) / 6 * half_pi)
    np.testing.assert_allclose(axes[2], (np.arange(6) + 0.5) / 6 * np.pi)
    assert values.shape == (6, 6, 6, 3) and supported.shape == (6, 6, 6)
    th, td, pd = np.meshgrid(*axes, indexing="ij")
    # No pair where a direction would lie below the horizon: NaN there.
    below = np.tan(th) * np.tan(td) * np.abs(np.cos(pd)) > 1
    assert np.all(np.isnan(values[below])) and not np.any(np.isnan(values[~below]))
    c = np.stack([th, np.zeros_like(th), td, pd], axis=-1)[~below]
    wi, wo = params.get("rusinkiewicz").inverse(c)
    np.testing.assert_allclose(values[~below], model.eval(wi, wo), rtol=1e-12)
    np.testing.assert_array_equal(supported[~below], model.supported(wi, wo))


def test_the_grid_holds_the_runs_reconstruction(run_file, tmp_path):
    out = tmp_path / "grid.h5"
    args = ["export", str(run_file), "--format", "hdf5", "--grid", "rusinkiewicz"]
    assert main([*args, "--grid-points", "6", "-o", str(out), "-q"]) == 0
    with h5py.File(out, "r") as h5:
        group = h5["reconstruction"]
        assert group.attrs["parametrization"] == "rusinkiewicz"
        axes = [group[f"axes/{n}"][()] for n in json.loads(group.attrs["coordinate_names"])]
        values, supported = group["values"][()], group["supported"][()]
    p = params.get("rusinkiewicz")
    coords = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)
    ok = p.valid_iso(coords)
    wi, wo = p.inverse_iso(coords[ok])
    surface = reconstruction(Measured.from_run(run_file), "linear", "rusinkiewicz")
    np.testing.assert_array_equal(supported[ok], surface.supported(wi, wo))
    np.testing.assert_allclose(values[ok], surface.eval(wi, wo), rtol=1e-12, equal_nan=True)
    assert supported.any() and np.all(np.isnan(values[~ok]))


def test_the_plain_h5py_example_of_the_docs_runs(out, run_file):
    text = (Path(__file__).resolve().parents[3] / "docs" / "reference" / "formats.md").read_text()
    section = text[text.index('<a id="hdf5"></a>') : text.index('<a id="alta"></a>')]
    code = section.split("```python\n")[1].split("```")[0].replace('"run.h5"', repr(str(out)))
    scope: dict[str, object] = {}
    exec(code, scope)
    run = open_run(run_file)
    np.testing.assert_array_equal(scope["f"], calibrate(run).brdf)
    assert scope["units"] == "sr^-1"
    assert scope["meta"]["plan_name"] == run.meta["plan_name"]
    assert list(scope["kinds"]) == [e.kind for e in run.events]
    assert scope["plan_file"].startswith(b"# gonio-plan v1")
