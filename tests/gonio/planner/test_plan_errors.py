"""Bad plan files: one line naming the file, the line, the field path and what is
expected; exit code 2 from `gonio plan`; no traceback; nothing constructed by YAML.
In-process through `gonio.cli.main`, but for one real process (its exit code and stderr)."""

from __future__ import annotations

import copy
import re
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
import yaml

from gonio.config import ConfigError
from gonio.planner.files import load_plan_source
from gonio.rig import Rig
from tests.conftest import CONFIGS, CliResult

QUICK = yaml.safe_load((CONFIGS / "plans" / "quick.yaml").read_text())
ARCH = str(CONFIGS / "rigs" / "arch.yaml")
GONIO = Path(sys.executable).with_name("gonio")
Gonio = Callable[..., CliResult]


def write(tmp_path: Path, data: Any, name: str = "bad-plan.yaml") -> Path:
    path = tmp_path / name
    if isinstance(data, dict):
        data.setdefault("rig", ARCH)
    text = data if isinstance(data, str) else yaml.safe_dump(data, sort_keys=False)
    path.write_text(text, encoding="utf-8")
    return path


def edit(change: Callable[[dict[str, Any]], object]) -> dict[str, Any]:
    data = copy.deepcopy(QUICK)
    data["rig"] = ARCH
    change(data)
    return data


def line_of_key(path: Path, *keys: str) -> int:
    """1-based line of the value of the nested key (the key's line, or the next for a
    block value), as block-style YAML writes it."""
    lines = path.read_text().splitlines()
    at = 0
    for key in keys:
        at = next(i for i in range(at, len(lines)) if lines[i].lstrip().startswith(f"{key}:"))
    return at + 1 + lines[at].rstrip().endswith(":")


def run_plan(run_gonio: Gonio, *args: str) -> tuple[int, str, str]:
    """`gonio plan ARGS` in-process: (exit code, stdout, stderr)."""
    r = run_gonio("plan", *args)
    return r.returncode, r.stdout, r.stderr


def grid(counts: dict[str, int]) -> Callable[[dict[str, Any]], object]:
    return lambda d: d.update(sampling={"strategy": "grid", "counts": counts})


GOOD_COUNTS = {"hbar": 4, "k": 4, "phi_k_minus_phi_h": 4}

# (id, change, field path, keys locating the line, expected words)
CASES: list[tuple[str, Callable[[dict[str, Any]], object], str, tuple[str, ...], str]] = [
    (
        "unknown-parametrization",
        lambda d: d.update(parametrization="polar"),
        "parametrization",
        ("parametrization",),
        "unknown parametrization 'polar'; expected one of spherical, rusinkiewicz, "
        "orthographic, hybrid",
    ),
    (
        "negative-count",
        grid({**GOOD_COUNTS, "k": -3}),
        "sampling.counts.k",
        ("sampling", "counts", "k"),
        "expected a positive number of points, got -3",
    ),
    (
        "count-of-an-unknown-coordinate",
        grid({**GOOD_COUNTS, "theta": 3}),
        "sampling.counts.theta",
        ("sampling", "counts", "theta"),
        "not a coordinate; the coordinates of isotropic hybrid are hbar, k, phi_k_minus_phi_h",
    ),
    (
        "count-missing",
        grid({"hbar": 4, "k": 4}),
        "sampling.counts",
        ("sampling", "counts"),
        "expected a count for phi_k_minus_phi_h as well",
    ),
    (
        "anisotropic-counts-need-four",
        lambda d: (d.update(isotropic=False), grid(GOOD_COUNTS)(d)),
        "sampling.counts.phi_k_minus_phi_h",
        ("sampling", "counts", "phi_k_minus_phi_h"),
        "the coordinates of hybrid are hbar, phi_h, k, phi_k",
    ),
    (
        "zero-target",
        lambda d: d["sampling"].update(target=0),
        "sampling.target",
        ("sampling", "target"),
        "greater than 0 (got 0)",
    ),
    (
        "counts-and-target",
        lambda d: d["sampling"].update(strategy="grid", counts=GOOD_COUNTS),
        "sampling",
        ("sampling",),
        "give exactly one of counts (per coordinate) or target (a total)",
    ),
    (
        "counts-with-a-sequence",
        lambda d: d.update(sampling={"strategy": "sobol", "counts": GOOD_COUNTS}),
        "sampling.counts",
        ("sampling", "counts"),
        "counts apply to grid and stratified sampling, not sobol",
    ),
    (
        "unknown-strategy",
        lambda d: d["sampling"].update(strategy="latin"),
        "sampling.strategy",
        ("sampling", "strategy"),
        "Input should be 'grid', 'stratified', 'sobol', 'halton', 'random', 'adaptive' or 'fly' "
        "(got 'latin')",
    ),
    (
        "negative-warp",
        lambda d: d["sampling"].update(warps={"hbar": {"power": -1}}),
        "sampling.warps.hbar.power",
        ("sampling", "warps", "hbar", "power"),
        "greater than or equal to 0.1 (got -1)",
    ),
    (
        "warp-that-collapses-the-points",
        lambda d: d["sampling"].update(warps={"hbar": {"power": 1e300}}),
        "sampling.warps.hbar.power",
        ("sampling", "warps", "hbar", "power"),
        "less than or equal to 10 (got 1e+300)",
    ),
    (
        "kicks-beyond-any-budget",
        lambda d: d.update(kicks=9 * 10**18),
        "kicks",
        ("kicks",),
        "less than or equal to 10000000 (got 9000000000000000000)",
    ),
    (
        "moves-beyond-any-budget",
        lambda d: d.update(max_moves=10**12),
        "max_moves",
        ("max_moves",),
        "less than or equal to 1000000000 (got 1000000000000)",
    ),
    (
        "warp-of-an-unknown-coordinate",
        lambda d: d["sampling"].update(warps={"theta_h": {"power": 2}}),
        "sampling.warps.theta_h",
        ("sampling", "warps", "theta_h"),
        "not a coordinate",
    ),
    (
        "exposure-range-inverted",
        lambda d: d["exposure"].update(
            adapt={"material": {"name": "lambert"}, "min_s": 2.0, "max_s": 1.0}
        ),
        "exposure.adapt.min_s",
        ("exposure", "adapt", "min_s"),
        "expected at most max_s (1.0), got 2.0",
    ),
    (
        "unknown-material",
        lambda d: d["exposure"].update(
            adapt={"material": {"name": "velvet"}, "min_s": 0.1, "max_s": 1.0}
        ),
        "exposure.adapt.material.name",
        ("exposure", "adapt", "material", "name"),
        "unknown BRDF model 'velvet'",
    ),
    (
        "bad-material-parameter",
        lambda d: d["exposure"].update(
            adapt={"material": {"name": "cook_torrance", "alpha": -1}, "min_s": 0.1, "max_s": 1}
        ),
        "exposure.adapt.material.alpha",
        ("exposure", "adapt", "material", "alpha"),
        "parameter alpha must lie in",
    ),
    (
        "negative-exposure",
        lambda d: d["exposure"].update(seconds=-0.1),
        "exposure.seconds",
        ("exposure", "seconds"),
        "greater than 0 (got -0.1)",
    ),
    (
        "negative-move-budget",
        lambda d: d.update(max_moves=-1),
        "max_moves",
        ("max_moves",),
        "greater than or equal to 0 (got -1)",
    ),
    (
        "fractional-move-budget",
        lambda d: d.update(max_moves=2.5),
        "max_moves",
        ("max_moves",),
        "Input should be a valid integer",
    ),
    (
        "unknown-field",
        lambda d: d.update(colour="red"),
        "colour",
        ("colour",),
        "unknown field",
    ),
    (
        "missing-sampling",
        lambda d: d.pop("sampling"),
        "sampling",
        (),
        "Field required",
    ),
]


@pytest.mark.parametrize(
    ("change", "field", "keys", "expected"), [c[1:] for c in CASES], ids=[c[0] for c in CASES]
)
def test_invalid_field(
    tmp_path: Path,
    run_gonio: Gonio,
    change: Callable[[dict[str, Any]], object],
    field: str,
    keys: tuple[str, ...],
    expected: str,
) -> None:
    path = write(tmp_path, edit(change))
    code, out, err = run_plan(run_gonio, str(path))
    assert code == 2
    assert out == ""
    line = line_of_key(path, *keys) if keys else 1
    assert err.startswith(f"gonio: error: {path}:{line}: {field}: "), err
    assert expected in err
    assert err.count("\n") == 1


def test_a_misspelt_key_is_named_on_its_line_with_the_closest_known_one(
    tmp_path: Path, run_gonio: Gonio
) -> None:
    """Every problem on its own line with its own line number, sorted by line: the field
    the misspelling leaves missing, then the unknown key with a suggestion (also nested,
    and inside a mapping of models)."""
    text = (
        (CONFIGS / "plans" / "quick.yaml")
        .read_text()
        .replace("rig: ../rigs/arch.yaml", f"rig: {CONFIGS / 'rigs' / 'arch.yaml'}")
    )
    lines = text.splitlines()
    top = next(i for i, line in enumerate(lines) if line.startswith("name:")) + 1
    at = next(i for i, line in enumerate(lines) if line.startswith("sampling:")) + 1
    path = write(tmp_path, text.replace("\nsampling:", "\nsamplng:"))
    code, out, err = run_plan(run_gonio, str(path))
    assert code == 2 and out == ""
    assert err.splitlines() == [
        f"gonio: error: {path}:{top}: sampling: Field required",
        f"{path}:{at}: samplng: unknown field; did you mean 'sampling'?",
    ]
    path.write_text(text.replace("  strategy: sobol", "  strategi: sobol"))
    code, _, err = run_plan(run_gonio, str(path))
    assert code == 2
    assert f"{path}:{at + 1}: sampling.strategi: unknown field; did you mean 'strategy'?" in err
    rig = tmp_path / "rig.yaml"
    rig.write_text(
        (CONFIGS / "rigs" / "arch.yaml")
        .read_text()
        .replace("    max_velocity_deg_s:", "    max_velocity_deg:", 1)
    )
    with pytest.raises(ConfigError, match=r"did you mean 'max_velocity_deg_s'\?"):
        Rig.from_yaml(rig)
    path.write_text(text + "colour: red\n")
    code, _, err = run_plan(run_gonio, str(path))
    assert err.strip().endswith("colour: unknown field")  # nothing close: no suggestion


def test_not_yaml(tmp_path: Path, run_gonio: Gonio) -> None:
    path = write(tmp_path, "name: x\nsampling: {strategy: sobol, target: 3\n")
    code, _, err = run_plan(run_gonio, str(path))
    assert code == 2
    assert re.match(rf"gonio: error: {re.escape(str(path))}:\d+: not valid YAML: ", err), err


def test_yaml_cannot_construct_objects(tmp_path: Path, run_gonio: Gonio) -> None:
    marker = tmp_path / "constructed"
    path = write(tmp_path, f"name: !!python/object/apply:os.system ['touch {marker}']\n")
    code, _, err = run_plan(run_gonio, str(path))
    assert code == 2
    assert "not valid YAML" in err
    assert not marker.exists()


@pytest.mark.parametrize(("text", "kind"), [("- a\n- b\n", "list"), ("", "empty"), ("3\n", "int")])
def test_not_a_mapping(tmp_path: Path, run_gonio: Gonio, text: str, kind: str) -> None:
    path = write(tmp_path, text)
    code, _, err = run_plan(run_gonio, str(path))
    assert code == 2
    assert (
        err == f"gonio: error: {path}: expected a mapping of fields at the top level, got {kind}\n"
    )


def test_missing_plan_file(tmp_path: Path, run_gonio: Gonio) -> None:
    code, _, err = run_plan(run_gonio, str(tmp_path / "nowhere.yaml"))
    assert code == 2
    assert err.startswith(f"gonio: error: {tmp_path / 'nowhere.yaml'}: cannot read the file")


def test_missing_rig_file(tmp_path: Path, run_gonio: Gonio) -> None:
    path = write(tmp_path, edit(lambda d: d.update(rig="no-such-rig.yaml")))
    code, _, err = run_plan(run_gonio, str(path))
    assert code == 2
    assert err.startswith(f"gonio: error: {tmp_path / 'no-such-rig.yaml'}: cannot read the file")


def test_no_rig_named(tmp_path: Path, run_gonio: Gonio) -> None:
    data = edit(lambda d: d.pop("rig"))
    path = tmp_path / "plan.yaml"
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    code, _, err = run_plan(run_gonio, str(path))
    assert code == 2
    assert err == f"gonio: error: {path}: rig: no rig file named; give one here or with --rig\n"
    # --rig supplies it.
    code, out, _ = run_plan(run_gonio, str(path), "--rig", ARCH)
    assert code == 0 and "kept" in out


def test_rig_that_reaches_nothing(tmp_path: Path, run_gonio: Gonio) -> None:
    rig = yaml.safe_load(Path(ARCH).read_text())
    rig["constraints"]["beam_diameter_mm"] = 40  # wider than the 30 mm sample
    rig_path = tmp_path / "rig.yaml"
    rig_path.write_text(yaml.safe_dump(rig), encoding="utf-8")
    plan = write(tmp_path, edit(lambda d: None))
    code, _, err = run_plan(run_gonio, str(plan), "--rig", str(rig_path))
    assert code == 2
    assert err.startswith(f"gonio: error: {rig_path}: constraints: leave no direction pair")
    assert "footprint" in err and err.count("\n") == 1


def test_real_process_exit_code_and_no_traceback(tmp_path: Path) -> None:
    path = write(tmp_path, edit(lambda d: d.update(parametrization="polar")))
    r = subprocess.run(
        [str(GONIO), "plan", str(path)],
        capture_output=True,
        text=True,
        timeout=120,
        stdin=subprocess.DEVNULL,
    )
    assert r.returncode == 2
    assert r.stdout == ""
    assert "Traceback" not in r.stderr
    assert r.stderr.count("\n") == 1
    assert f"{path}:" in r.stderr and "parametrization: unknown parametrization" in r.stderr


def test_duplicate_key_is_refused(tmp_path: Path, run_gonio: Gonio) -> None:
    path = write(tmp_path, f"name: a\nrig: {ARCH}\nname: b\nsampling: {{strategy: sobol}}\n")
    code, _, err = run_plan(run_gonio, str(path))
    assert code == 2
    assert err == (
        f"gonio: error: {path}:3: name: this key is given twice in the same mapping; "
        "expected each key once\n"
    )


@pytest.mark.parametrize(
    ("change", "field"),
    [
        (lambda d: d["exposure"].update(seconds=float("inf")), "exposure.seconds"),
        (
            lambda d: d["sampling"].update(warps={"hbar": {"power": float("nan")}}),
            "sampling.warps.hbar.power",
        ),
        (lambda d: d.update(time_budget_s=float("inf")), "time_budget_s"),
    ],
    ids=["infinite-exposure", "nan-warp", "infinite-budget"],
)
def test_infinities_and_nans_are_refused(
    tmp_path: Path,
    run_gonio: Gonio,
    change: Callable[[dict[str, Any]], object],
    field: str,
) -> None:
    path = write(tmp_path, edit(change))
    code, _, err = run_plan(run_gonio, str(path))
    assert code == 2
    assert f": {field}: Input should be a finite number" in err


def test_rig_that_is_a_folder(tmp_path: Path, run_gonio: Gonio) -> None:
    path = write(tmp_path, edit(lambda d: d.update(rig=str(tmp_path))))
    code, _, err = run_plan(run_gonio, str(path))
    assert code == 2
    line = line_of_key(path, "rig")
    assert err == f"gonio: error: {path}:{line}: rig: {tmp_path} is a folder; expected a rig file\n"


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["-o", "{tmp}"], "-o {tmp}: is a directory; expected a file name"),
        (["--plot", "{tmp}/none/c.png"], "--plot {tmp}/none/c.png: the folder {tmp}/none does not"),
    ],
    ids=["output-is-a-folder", "plot-folder-missing"],
)
def test_output_paths_are_checked_before_planning(
    tmp_path: Path, run_gonio: Gonio, args: list[str], message: str
) -> None:
    plan = CONFIGS / "plans" / "quick.yaml"
    code, out, err = run_plan(run_gonio, str(plan), *(a.format(tmp=tmp_path) for a in args))
    assert code == 2 and out == ""
    assert err.startswith("gonio: error: " + message.format(tmp=tmp_path))


@pytest.mark.parametrize(
    ("exposure", "field", "message"),
    [
        ({"seconds": 100}, "exposure.seconds", "100 s is outside the detector's exposure range "
         "[0.0001, 60] s (the rig file's detector.exposure_range_s)"),
        ({"seconds": 0.1, "averages": 100}, "exposure.averages", "up to 100 averages; the "
         "detector takes at most 64 (the rig file's detector.max_averages)"),
        ({"seconds": 0.1, "adapt": {"material": {"name": "lambert", "albedo": 0.5},
          "min_s": 1e-6, "max_s": 1.0}}, "exposure.adapt.min_s",
         "1e-06 s is outside the detector's exposure range"),
    ],
)  # fmt: skip
def test_exposures_the_detector_cannot_take_are_refused_before_planning(
    tmp_path: Path, run_gonio: Gonio, exposure: dict[str, Any], field: str, message: str
) -> None:
    path = write(tmp_path, edit(lambda d: d.update(exposure=exposure)))
    code, out, err = run_plan(run_gonio, str(path))
    assert code == 2 and out == ""
    assert err.startswith(f"gonio: error: {path}:") and f": {field}: {message}" in err
    assert err.count("\n") == 1


def test_a_long_unknown_name_and_an_unreadable_rig_path_are_one_short_line(
    tmp_path: Path,
) -> None:
    plan = tmp_path / "plan.yaml"
    for field in ("parametrization", "rig"):
        fields = {"parametrization": "rusinkiewicz", "rig": "../rigs/arch.yaml"}
        fields[field] = "x" * 5000  # longer than a file name may be
        plan.write_text(
            f"name: long\nrig: {fields['rig']}\nparametrization: {fields['parametrization']}\n"
            "sampling: {strategy: sobol, target: 10}\n"
        )
        with pytest.raises(ConfigError) as info:
            load_plan_source(plan)
        assert len(str(info.value)) < 600 and "\n" not in str(info.value)
