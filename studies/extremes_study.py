"""Numerical stability at the extremes, measured: conditioning, round trip, position error.

For each parametrization and each extreme (gonio.params.cases.EXTREMES), along 16
one-parameter paths approaching it at distances 1e-1 … 1e-12 rad (two per decade):
the tangent Jacobian's singular values and condition number (gonio.params.conditioning)
and the worst float64 round-trip error (studies.params.accuracy.path_study). Then, for
the shipped arch and in-plane rigs, the joint errors (one encoder tick through each
gear, σ = tick/√12, and the brushed_metal scene's repeatability) propagated into each
parametrization's coordinates and into a GGX BRDF value (gonio.rig.sensitivity).
Prints the markdown tables of docs/explanations/extremes.md and writes docs/img/extremes_*.png.
Run: .venv/bin/python studies/extremes_study.py [--samples N] [--bound] [--no-plots]
"""

from __future__ import annotations

import argparse
import io
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # _report
sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # studies
import _report
from _machine import describe

from gonio import brdf, params
from gonio.output import reserve_output
from gonio.params import cases, singular_values, tangent_jacobian
from gonio.plots import require_matplotlib
from gonio.rig import Reason, Rig, sensitivity
from gonio.scene import load_scene
from studies.params.accuracy import PATH_DISTANCES, PathRow, measured_errors, path_study

ROOT = Path(__file__).resolve().parent.parent
IMG = ROOT / "docs" / "img"
SCENE = "configs/scenes/brushed_metal.yaml"
RIGS = {"arch": "configs/rigs/arch.yaml", "in_plane": "configs/rigs/in_plane.yaml"}
TABLE_DISTANCES = (1e-1, 1e-3, 1e-6, 1e-9, 1e-12)
#: Position-error distances: a tick is 1.5e-3 rad, so 1e-3 is "within a tick".
POSITION_DISTANCES = tuple(float(10.0 ** (-i / 4)) for i in range(4, 21))  # 1e-1 … 1e-5
POSITION_TABLE = (1e-1, 1e-2, 1e-3, 1e-4)
ALPHAS = (0.05, 0.1)


def cell(rows: list[PathRow], name: str, extreme: str, distance: float) -> PathRow:
    (r,) = [
        r
        for r in rows
        if r.parametrization == name and r.extreme == extreme and math.isclose(r.distance, distance)
    ]
    return r


def law(rows: list[PathRow], name: str, extreme: str) -> str:
    """Which singular value drives the growth, from the two ends of the paths."""
    a, b = cell(rows, name, extreme, 1e-3), cell(rows, name, extreme, 1e-12)
    up = math.log10(b.sigma_max / a.sigma_max) / 9
    down = math.log10(a.sigma_min / b.sigma_min) / 9
    if up > 0.5:
        return "σmax ∝ 1/d"
    if down > 0.5:
        return "σmin ∝ d"
    return "bounded"


def conditioning_tables(rows: list[PathRow], names: list[str]) -> None:
    print("\n### Condition number (median over the paths) and its law as d → 0\n")
    print("| extreme | " + " | ".join(names) + " |")
    print("| --- | " + " | ".join(["---"] * len(names)) + " |")
    for extreme in cases.EXTREMES:
        cells = [
            f"{cell(rows, n, extreme, 1e-3).cond:.1e} → {cell(rows, n, extreme, 1e-12).cond:.1e}"
            f" ({law(rows, n, extreme)})"
            for n in names
        ]
        print(f"| {extreme} | " + " | ".join(cells) + " |")
    print("\n(cells: at d = 1e-3 → at d = 1e-12)")
    print("\n### Worst round-trip error along the paths\n")
    print("| extreme | " + " | ".join(names) + " |")
    print("| --- | " + " | ".join(["---:"] * len(names)) + " |")
    for extreme in cases.EXTREMES:
        cells = [
            " / ".join(f"{cell(rows, n, extreme, d).roundtrip:.0e}" for d in TABLE_DISTANCES)
            for n in names
        ]
        print(f"| {extreme} | " + " | ".join(cells) + " |")
    print(f"\n(cells: at d = {' / '.join(f'{d:g}' for d in TABLE_DISTANCES)})")
    eps = float(np.finfo(np.float64).eps)
    print("\nround trip / (ε/σmin), pair by pair, where σmin ∝ d and 1e-14 < ε/σmin < 1e-9:")
    for n in names:
        ratios = []
        for extreme in cases.EXTREMES:
            if law(rows, n, extreme) != "σmin ∝ d":
                continue
            for d in PATH_DISTANCES:
                wi, wo = cases.near(extreme, d, rows[0].samples, 0)
                s_min = singular_values(tangent_jacobian(n, wi, wo))[:, -1]
                keep = (eps / s_min > 1e-14) & (eps / s_min < 1e-9)
                ratios.extend((measured_errors(n, wi, wo) * s_min / eps)[keep])
        if ratios:
            print(
                f"  {n:13s} median {np.median(ratios):.2f}, 5 % … 95 % "
                f"{np.percentile(ratios, 5):.2f} … {np.percentile(ratios, 95):.2f}, "
                f"max {np.max(ratios):.2f} ({len(ratios)} pairs)"
            )
    bounded = [r for r in rows if not math.isnan(r.bound)]
    if bounded:
        print("\nworst measured / worst bound per cell, over every extreme and distance:")
        for n in names:
            ratio = max(r.roundtrip / r.bound for r in bounded if r.parametrization == n)
            print(f"  {n:13s} {ratio:.2f}")


Study = dict[tuple[str, float], dict[str, np.ndarray]]


def position_study(rig: Rig, names: list[str], sigma: np.ndarray, samples: int, seed: int) -> Study:
    """Per (extreme, distance): the pair's RMS direction error, each parametrization's
    largest coordinate standard error, σ_f/f per GGX α, and the reachable fraction."""
    models = {a: brdf.create("cook_torrance", alpha=a, f0=0.04) for a in ALPHAS}
    out = {}
    for extreme in cases.EXTREMES:
        for d in POSITION_DISTANCES:
            wi, wo = cases.near(extreme, d, samples, seed)
            solution = rig.solve(wi, wo)
            q = solution.angles  # the kinematic solution, also where constraints refuse
            r: dict[str, np.ndarray] = {
                "direction": sensitivity.direction_sigma(rig, q, sigma),
                "reachable": np.asarray(solution.reasons == Reason.OK, dtype=np.float64),
                "lowest": np.minimum(wi[:, 2], wo[:, 2]),
            }
            for n in names:
                r[n] = sensitivity.coordinate_sigma(n, rig, q, sigma).max(axis=-1)
            for a, m in models.items():
                r[f"ggx{a}"] = sensitivity.brdf_sigma(m, rig, q, sigma) / m.eval(*rig.forward(q))
            out[extreme, d] = r
    return out


def position_tables(label: str, study: Study, names: list[str]) -> None:
    print(f"\n### {label}: largest coordinate standard error / the direction's RMS error\n")
    print("| extreme | σω (°) | " + " | ".join(names) + " | reachable |")
    print("| --- | ---: | " + " | ".join(["---:"] * len(names)) + " | ---: |")
    for extreme in cases.EXTREMES:
        rows = [study[extreme, d] for d in POSITION_TABLE]
        sd = np.degrees(np.median(rows[-1]["direction"]))
        cells = [" / ".join(amplification(r, n) for r in rows) for n in names]
        reach = f"{100 * np.mean([r['reachable'].mean() for r in rows]):.0f} %"
        print(f"| {extreme} | {sd:.3f} | " + " | ".join(cells) + f" | {reach} |")
    print(
        f"\n(cells: median over the paths at d = {' / '.join(f'{d:g}' for d in POSITION_TABLE)};"
        " ‡: the coordinate's σ exceeds π, an azimuth there is undetermined)"
    )
    print(f"\n### {label}: relative BRDF error σf/f of GGX (median; worst in brackets)\n")
    head = " | ".join(f"α = {a}" for a in ALPHAS)
    print(f"| extreme | {head} |")
    print("| --- | " + " | ".join(["---"] * len(ALPHAS)) + " |")
    for extreme in cases.EXTREMES:
        cells = []
        for a in ALPHAS:
            rows = [study[extreme, d] for d in POSITION_TABLE]
            cells.append(
                " / ".join(
                    f"{np.median(r[f'ggx{a}']):.1e} [{np.max(r[f'ggx{a}']):.0e}]"
                    + ("†" if np.median(r["lowest"] / r["direction"]) < 3 else "")
                    for r in rows
                )
            )
        print(f"| {extreme} | " + " | ".join(cells) + " |")
    print(
        "\n(†: the lower direction is within 3 σω of the horizon, where f changes on the scale"
        " of its elevation: first order no longer holds)"
    )


def amplification(r: dict[str, np.ndarray], name: str) -> str:
    ratio = f"{np.median(r[name] / r['direction']):.2g}"
    return ratio + ("‡" if np.median(r[name]) > math.pi else "")


def save(fig: Any, name: str) -> None:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=72)
    with reserve_output(IMG / name, "image") as out:
        out.write_bytes(buffer.getvalue())
    _report.figure(IMG / name, name.removesuffix(".png").replace("_", " "))


def grid(plt: Any, title: str) -> tuple[Any, np.ndarray]:
    fig, axes = plt.subplots(2, 5, figsize=(13, 5.4), sharex=True, sharey=True)
    fig.suptitle(title, fontsize=10)
    for ax, extreme in zip(axes.flat, cases.EXTREMES, strict=True):
        ax.set_title(extreme, fontsize=8)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.tick_params(labelsize=7)
        ax.grid(True, which="major", lw=0.3)
    for ax in axes[-1]:
        ax.set_xlabel("distance d to the extreme (°)", fontsize=7)
    axes.flat[0].invert_xaxis()  # once: the panels share it (the extreme on the right)
    return fig, axes


def plots(rows: list[PathRow], names: list[str], studies: dict[str, Study]) -> None:
    plt = require_matplotlib()
    d = np.array(PATH_DISTANCES)
    for key, title, fname in (
        ("cond", "condition number of the tangent Jacobian (median of 16 paths)", "condition"),
        ("roundtrip", "worst float64 round-trip error (16 paths)", "roundtrip"),
    ):
        fig, axes = grid(plt, title)
        for ax, extreme in zip(axes.flat, cases.EXTREMES, strict=True):
            for n in names:
                y = [max(getattr(cell(rows, n, extreme, x), key), 1e-17) for x in d]
                ax.plot(np.degrees(d), y, lw=1.2, label=n)
        axes.flat[0].legend(fontsize=7)
        fig.tight_layout()
        save(fig, f"extremes_{fname}.png")
        plt.close(fig)
    for rig_name, study in studies.items():
        fig, axes = grid(
            plt,
            f"{rig_name} rig, tick + 0.02° repeatability: largest coordinate σ / direction σ "
            "(solid), GGX σf/f (dashed)",
        )
        p = np.array(POSITION_DISTANCES)
        for ax, extreme in zip(axes.flat, cases.EXTREMES, strict=True):
            for n in names:
                y = [np.median(study[extreme, x][n] / study[extreme, x]["direction"]) for x in p]
                ax.plot(np.degrees(p), y, lw=1.2, label=n)
            for a, style in zip(ALPHAS, ("--", ":"), strict=True):
                y = [np.median(study[extreme, x][f"ggx{a}"]) for x in p]
                ax.plot(np.degrees(p), y, style, color="k", lw=1, label=f"GGX α={a} σf/f")
            reach = float(np.median(study[extreme, p[-1]]["direction"]))
            # d = σω: the error reaches the extreme
            ax.axvline(math.degrees(reach), color="grey", lw=0.8)
        axes.flat[0].legend(fontsize=6)
        fig.tight_layout()
        save(fig, f"extremes_position_{rig_name}.png")
        plt.close(fig)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=16, help="paths per extreme")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--bound", action="store_true", help="also the mpmath bound (slow)")
    ap.add_argument("--no-plots", action="store_true")
    args = ap.parse_args()
    names = params.names()
    print(f"machine: {describe()}")
    rows = path_study(names, samples=args.samples, seed=args.seed, with_bound=args.bound)
    conditioning_tables(rows, names)
    position = load_scene(ROOT / SCENE).effects.position_error
    assert position is not None
    repeatability = math.radians(position.repeatability_deg)
    studies = {}
    for label, path in RIGS.items():
        rig = Rig.from_yaml(ROOT / path)
        errors = sensitivity.axis_errors(rig, repeatability)
        ticks = ", ".join(
            f"{a} {math.degrees(t):.4f}°" for a, t in zip(rig.axes, errors.tick, strict=True)
        )
        print(f"\n{label} rig: one tick = {ticks}; repeatability {position.repeatability_deg}°")
        studies[label] = position_study(rig, names, errors.total, args.samples, args.seed)
        position_tables(label, studies[label], names)
    if not args.no_plots:
        plots(rows, names, studies)


if __name__ == "__main__":
    _report.run(main, __file__, __doc__, title="Conditioning and position error at the extremes")
