"""UTIA round trips: a `gonio.brdf` model tabulated on the UTIA BRDF database's grid
(θ every 15° to 75°, φ every 7.5°; `gonio.brdf.utia.write`), read back
(`create("utia", ...)`, quadrilinear in θi, φi, θv, φv) and compared with the model: at
the nodes, and between them on 200 000 pairs uniform in solid angle with both θ ≤ 75°
(and, apart, with both θ in (75°, 90°), where the table is constant in θ). Errors are per
channel, as a fraction of the largest tabulated value (the lobe's peak on the grid) and
relative to the model's own value. "Estimate" is the linear-interpolation error at a GGX
peak the grid implies, (h²/8)·Σ|∂²f/∂x²|/f over the four axes, ≈ 0.021/α² for h = 15° in
θ and 7.5°·sin 75° in φ (α: the lobe's narrowest roughness). Writes
docs/img/utia_slices.png: the model and its table along the plane of incidence and along
φv.

Run: .venv/bin/python studies/utia.py [--pairs 200000]
"""

from __future__ import annotations

import argparse
import io
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # _report
sys.path.insert(0, str(Path(__file__).resolve().parent))
import _report
from _machine import describe

from gonio import brdf
from gonio.brdf import utia
from gonio.output import reserve_output
from gonio.plots import require_matplotlib

ROOT = Path(__file__).resolve().parent.parent
IMG = ROOT / "docs" / "img"
H_THETA, H_PHI = np.radians(15.0), np.radians(7.5) * np.sin(np.radians(75.0))
#: (label, model name, parameters, narrowest roughness or None)
MODELS: list[tuple[str, str, dict[str, object], float | None]] = [
    ("Lambert, albedo 0.5", "lambert", {"albedo": 0.5}, None),
    ("GGX α 0.1, f0 0.9", "cook_torrance", {"alpha": 0.1, "f0": 0.9}, 0.1),
    ("GGX α 0.2, f0 0.9", "cook_torrance", {"alpha": 0.2, "f0": 0.9}, 0.2),
    ("GGX α 0.3, f0 0.9", "cook_torrance", {"alpha": 0.3, "f0": 0.9}, 0.3),
    ("GGX α 0.5, f0 0.9", "cook_torrance", {"alpha": 0.5, "f0": 0.9}, 0.5),
    ("GGX α 0.8, f0 0.9, kd (0.3, 0.2, 0.1)¹", "cook_torrance",
     {"alpha": 0.8, "f0": 0.9, "kd": (0.3, 0.2, 0.1)}, 0.8),
    ("GGX α 1.0, f0 0.9", "cook_torrance", {"alpha": 1.0, "f0": 0.9}, 1.0),
    ("anisotropic GGX αx 0.1, αy 0.3", "ggx_anisotropic",
     {"alpha_x": 0.1, "alpha_y": 0.3, "f0": 0.9}, 0.1),
    ("anisotropic GGX αx 0.3, αy 0.6, f0 0.9¹", "ggx_anisotropic",
     {"alpha_x": 0.3, "alpha_y": 0.6, "f0": 0.9}, 0.3),
    ("anisotropic GGX αx 0.5, αy 1.0", "ggx_anisotropic",
     {"alpha_x": 0.5, "alpha_y": 1.0, "f0": 0.9}, 0.5),
]  # fmt: skip


def pairs(n: int, low_deg: float, high_deg: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """``n`` pairs uniform in solid angle with both θ in [low, high]."""
    rng = np.random.default_rng(seed)
    z = rng.uniform(np.cos(np.radians(high_deg)), np.cos(np.radians(low_deg)), (2, n))
    phi = rng.uniform(0.0, 2 * np.pi, (2, n))
    s = np.sqrt(1 - z * z)
    v = np.stack([s * np.cos(phi), s * np.sin(phi), z], axis=-1)
    return v[0], v[1]


def rgb(model: brdf.BRDF, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
    value = np.asarray(model.eval(wi, wo))
    return value if model.is_rgb else np.repeat(value[..., None], 3, axis=-1)


def slices(folder: Path) -> None:
    """The anisotropic model of the tests and its table: θv across the plane of
    incidence (θi 30°, φi 0°; φv = 180° is the mirror side, plotted as negative θv), and
    φv at θi = θv = 45°, φi = 0°."""
    plt = require_matplotlib()
    label, name, params, _ = MODELS[8]
    model = brdf.create(name, **params)
    table = brdf.create("utia", path=str(utia.write(folder / "slice.bin", model)))
    fig, (left, right) = plt.subplots(1, 2, figsize=(10, 3.6))
    theta = np.radians(np.linspace(-89, 89, 721))
    wi = np.broadcast_to([np.sin(np.radians(30)), 0.0, np.cos(np.radians(30))], (721, 3))
    wo = np.stack([np.sin(theta), np.zeros_like(theta), np.cos(theta)], axis=-1)
    for target, style, what in ((model, "-", "model"), (table, "--", "UTIA table")):
        left.plot(np.degrees(-theta), rgb(target, wi, wo)[:, 0], style, label=what)
    left.set_xlabel("θv (°), negative: φv = 0°, positive: φv = 180°")
    left.set_ylabel("f (sr⁻¹)")
    left.set_title("θi 30°, φi 0° (plane of incidence)", fontsize=9)
    for x in range(-75, 76, 15):
        left.axvline(x, color="0.85", lw=0.6, zorder=0)
    phi = np.radians(np.linspace(0, 360, 721))
    s = np.sin(np.radians(45))
    wi = np.broadcast_to([s, 0.0, s], (721, 3))
    wo = np.stack([s * np.cos(phi), s * np.sin(phi), np.full_like(phi, s)], axis=-1)
    for target, style, what in ((model, "-", "model"), (table, "--", "UTIA table")):
        right.plot(np.degrees(phi), rgb(target, wi, wo)[:, 0], style, label=what)
    right.set_xlabel("φv (°)")
    right.set_title("θi = θv = 45°, φi 0°", fontsize=9)
    right.legend(fontsize=8)
    fig.suptitle(label.rstrip("¹"), fontsize=10)
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=72)
    plt.close(fig)
    with reserve_output(IMG / "utia_slices.png", "image") as out:
        out.write_bytes(buffer.getvalue())
    _report.figure(IMG / "utia_slices.png", "utia slices")


def main_() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--pairs", type=int, default=200_000)
    args = parser.parse_args()
    print(describe())
    inside = pairs(args.pairs, 0.0, 75.0, 3)
    rim = pairs(args.pairs // 4, 75.0, 90.0, 4)
    nodes = utia.grid_directions()
    print(
        "\n| model | peak on the grid (sr⁻¹) | at the nodes: max relative | θ ≤ 75°: max / peak "
        "| 99 % / peak | median relative | 99 % relative | estimate / peak "
        "| θ in (75°, 90°): median relative |"
    )
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    timing: list[float] = []
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for label, name, params, alpha in MODELS:
            model = brdf.create(name, **params)
            started = time.perf_counter()
            path = utia.write(folder / "m.bin", model)
            table = brdf.create("utia", path=str(path))
            written = time.perf_counter() - started
            peak = utia.tabulate(model).max(axis=(1, 2, 3, 4))
            want = rgb(model, *nodes)
            at_nodes = np.max(np.abs(table.eval(*nodes) - want) / np.maximum(want, 1e-300))
            started = time.perf_counter()
            got = table.eval(*inside)
            timing.append((time.perf_counter() - started, written))
            want = rgb(model, *inside)
            error = np.abs(got - want)
            relative = error / np.maximum(want, 1e-300)
            rim_want = rgb(model, *rim)
            rim_error = np.abs(table.eval(*rim) - rim_want) / np.maximum(rim_want, 1e-300)
            estimate = "—" if alpha is None else f"{min(1.0, 0.021 / alpha**2):.3g}"
            print(
                f"| {label} | {peak.max():.3g} | {at_nodes:.1e} "
                f"| {np.max(error.max(axis=0) / peak):.3g} "
                f"| {np.max(np.quantile(error, 0.99, axis=0) / peak):.3g} "
                f"| {np.median(relative):.2g} | {np.quantile(relative, 0.99):.3g} "
                f"| {estimate} | {np.median(rim_error):.2g} |",
                flush=True,
            )
        print(
            "\n¹ the models of tests/gonio/brdf/test_utia.py (bounds stated there: 0.06 and "
            "0.15 of the peak)."
        )
        evals = np.median([t for t, _ in timing])
        writes = np.median([w for _, w in timing])
        print(
            f"\nTimes (median over the models): eval of {args.pairs:,} pairs {evals:.2f} s, "
            f"tabulating, writing and reading a file {writes:.2f} s; a file is "
            f"{utia.FILE_SIZE:,} bytes."
        )
        slices(folder)


if __name__ == "__main__":
    _report.run(main_, __file__, __doc__, title="UTIA round trips")
