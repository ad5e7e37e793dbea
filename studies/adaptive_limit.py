"""How far placing samples by a density can go (docs/explanations/adaptive.md
"The limit of density placement"), noise-free, on GGX α 0.1 over kd 0.2 (F0 0.04), arch rig,
Rusinkiewicz coordinates, rbf reconstruction, log-RMSE on log(1 + f) over the default
test set.

Plans at each count, each reconstructed the same way:

    uniform    Sobol, the best uniform plan of studies/adaptive.py
    shipped    the adaptive strategy as shipped: a 128-target survey, a lambert+beckmann
               fit of it steering one second pass (`synthesize_adaptive`)
    own error  a 64-target survey, then passes doubling the samples, each placed by the
               reconstruction's own error: the discrepancy between the rbf of all samples
               and the rbf of a random half, per cell of the density grid
    oracle     the same passes placed by the reconstruction's true error (the scene is
               known here: no instrument can do this; it bounds every indicator)
    simulated  a 128-target survey; a lambert+beckmann fit of it; a uniform plan of the
               same count simulated on the fit and reconstructed; the rest placed in one
               pass by that simulated plan's error per cell (the cell shares below, 8³)
    oracle cells  one pass placed by the uniform plan's true error per cell (16³), with
               the shares below: the best a density can do, measured

The passes' density is the optimal total density for the indicator e² (error of the
current density ρ₀, falling as ρ^(−2/d)) minus the samples already there:
ρ* ∝ (w e² ρ₀^(4/d))^(d/(d+4)), new samples ∝ max(ρ* − ρ₀, 0), a share 0.2 uniform.
Then where the oracle's error sits at the largest count, by θh; and the ceiling of
any density: with the uniform plan's squared error E_c per cell of a grid on the
coordinate box (test pairs' error, weighted by their share of the test measure), its
share of the samples v_c, and a local error falling as ρ^(−β) (β fitted to the
uniform curve: error ∝ N^(−β)), the best sample shares s_c ∝ v_c^(2β/(1+2β))
E_c^(1/(1+2β)) give Σ E_c (v_c/s_c)^(2β) = (Σ (E_c v_c^(2β))^(1/(1+2β)))^(1+2β): the
uniform error over that is the largest gain a density can give at that count (finer
cells see more of the error's concentration, and a noisier estimate of it).

Run: .venv/bin/python studies/adaptive_limit.py [--alpha 0.1] [--counts 250 ... 4000]
[--plans shipped 'own error' oracle] (about 15 minutes on 2 cores)
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # _report
sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # studies

import _report
import numpy as np
from _machine import describe
from adaptive import ggx
from scipy import ndimage

from gonio import params
from gonio.analysis import Measured
from gonio.brdf import pair
from gonio.planner import PlanSpec, adaptive, draw_kept, draw_points
from gonio.reconstruct import evaluate, fit, reconstruct, testset
from gonio.rig import Rig
from gonio.types import BrdfEval, FloatArray
from studies.reconstruct.synthetic import measured_at, placed, synthesize, synthesize_adaptive

ROOT = Path(__file__).resolve().parent.parent
PARAMETRIZATION = "rusinkiewicz"
SEED = 3
SURVEY = 64
FLOOR = 0.2
#: The exponent of the uniform curve, error ∝ N^−β (the fit this script prints, α 0.1).
BETA = 0.86
#: Gaussian smoothing of the indicator, in cells of the density grid.
SMOOTH = 1.0
#: Gaussian smoothing of the samples' counts per cell (ρ₀), in cells.
SPREAD = 2.0
#: Indicator: (samples, cell-centre pairs wi, wo, rbf of all samples at them) → e² per pair.
Indicator = Callable[[Measured, FloatArray, FloatArray, FloatArray], FloatArray]


def own_error(m: Measured, wi: FloatArray, wo: FloatArray, full: FloatArray) -> FloatArray:
    half = np.sort(np.random.default_rng(0).permutation(len(m))[: len(m) // 2])
    other = reconstruct(m.subset(half), method="rbf", extrapolate="nearest").eval(wi, wo)
    return np.asarray((full - np.log1p(np.maximum(other, 0.0))) ** 2, dtype=np.float64)


def oracle(truth: BrdfEval) -> Indicator:
    def true_error(m: Measured, wi: FloatArray, wo: FloatArray, full: FloatArray) -> FloatArray:
        return np.asarray((full - np.log1p(truth(wi, wo))) ** 2, dtype=np.float64)

    return true_error


def passes(truth: BrdfEval, rig: Rig, n: int, indicator: Indicator) -> Measured:
    """A survey of `SURVEY` Sobol targets, then passes doubling the samples up to ``n``,
    each placed by the density the indicator gives (module docstring)."""
    m = synthesize(truth, rig, PARAMETRIZATION, True, SURVEY, seed=SEED)
    p = params.get(PARAMETRIZATION)
    bounds = np.asarray(p.iso_bounds, dtype=np.float64)
    shape = (adaptive.CELLS[3],) * 3
    w = adaptive.measure_density(rig, PARAMETRIZATION, True, shape)
    reached = (w > 0) / np.count_nonzero(w)
    box = bounds[:, 0] + adaptive.centres(shape) * (bounds[:, 1] - bounds[:, 0])
    valid = p.valid_iso(box)
    wi, wo = p.inverse_iso(box[valid])
    step = 0
    while len(m) < n:
        step += 1
        following = min(n, 2 * len(m))
        full = np.log1p(
            np.maximum(reconstruct(m, method="rbf", extrapolate="nearest").eval(wi, wo), 0)
        )
        e2 = np.zeros(len(box))
        e2[valid] = indicator(m, wi, wo, full)
        _, nearest = ndimage.distance_transform_edt(~valid.reshape(shape), return_indices=True)
        e2 = ndimage.gaussian_filter(e2.reshape(shape)[tuple(nearest)], SMOOTH, mode="nearest")
        rho0 = ndimage.gaussian_filter(counts(m, shape, bounds), SPREAD, mode="nearest").ravel()
        rho0 *= len(m) / rho0.sum()
        best = np.power(w * e2.ravel() * np.power(rho0, 4.0 / 3.0), 3.0 / 7.0)
        new = np.maximum(best * following / best.sum() - rho0, 0.0)
        shaped = new / new.sum() if new.sum() > 0 else reached
        density = adaptive.Density(shape, (1 - FLOOR) * shaped + FLOOR * reached)
        m = m.joined(drawn(truth, rig, density, following - len(m), SEED + step))
    return m


def cell_of(
    wi: FloatArray, wo: FloatArray, shape: tuple[int, ...], bounds: FloatArray
) -> np.ndarray:
    """The flat index of each pair's cell in a grid of ``shape`` on the coordinate box."""
    unit = (params.get(PARAMETRIZATION).forward_iso(wi, wo) - bounds[:, 0]) / (
        bounds[:, 1] - bounds[:, 0]
    )
    return adaptive.cell_index(unit, shape)


def counts(m: Measured, shape: tuple[int, ...], bounds: FloatArray) -> FloatArray:
    """The samples per cell of the density grid (shape)."""
    flat = cell_of(m.wi, m.wo, shape, bounds)
    return np.bincount(flat, minlength=math.prod(shape)).astype(np.float64).reshape(shape)


def error_cells(
    truth: BrdfEval,
    rig: Rig,
    pairs: testset.TestSet,
    n: int,
    cells: int,
    volume: tuple[FloatArray, FloatArray],
) -> tuple[FloatArray, FloatArray]:
    """Per cell of a ``cells``³ grid on the coordinate box: the squared log error E_c of
    the uniform plan of ``n`` samples of ``truth`` (rbf), each test pair weighted by its
    share of the test measure; and the share v_c of a uniform plan's samples."""
    bounds = np.asarray(params.get(PARAMETRIZATION).iso_bounds, dtype=np.float64)
    uniform = synthesize(truth, rig, PARAMETRIZATION, True, n, seed=SEED)
    got = reconstruct(uniform, method="rbf", extrapolate="nearest").eval(pairs.wi, pairs.wo)
    square = (np.log1p(got) - np.log1p(truth(pairs.wi, pairs.wo))) ** 2
    shape = (cells,) * 3
    mass = np.bincount(cell_of(pairs.wi, pairs.wo, shape, bounds), square, minlength=cells**3)
    share = np.bincount(cell_of(*volume, shape, bounds), minlength=cells**3) / len(volume[0])
    return mass / len(square), share


def best_shares(mass: FloatArray, share: FloatArray, beta: float) -> FloatArray:
    """The sample shares s_c ∝ v_c^(2β/(1+2β)) E_c^(1/(1+2β)) (module docstring), summing to 1."""
    best = np.where(share > 0, (share ** (2 * beta) * mass) ** (1 / (1 + 2 * beta)), 0.0)
    return np.asarray(best / best.sum(), dtype=np.float64)


def cell_shares(
    truth: BrdfEval,
    rig: Rig,
    pairs: testset.TestSet,
    n: int,
    cells: int,
    beta: float,
    volume: tuple[FloatArray, FloatArray],
) -> adaptive.Density:
    """The density on ``cells``³ cells whose kept samples follow `best_shares` for
    `error_cells` of ``truth``, 10 % of them as a uniform plan's."""
    mass, share = error_cells(truth, rig, pairs, n, cells, volume)
    wanted = 0.9 * best_shares(mass, share, beta) + 0.1 * share
    # Points are uniform in a cell's box: the kept share of a cell is p·v_c.
    p = np.where(share > 0, wanted / np.maximum(share, 1e-300), 0.0)
    return adaptive.Density((cells,) * 3, p / p.sum())


def drawn(truth: BrdfEval, rig: Rig, density: adaptive.Density, count: int, seed: int) -> Measured:
    """``count`` kept samples of ``truth`` drawn from ``density`` (a stream seeded by
    ``seed``), noise-free, σ = 1 % of f."""
    spec = PlanSpec.model_validate(
        {
            "name": "limit",
            "parametrization": PARAMETRIZATION,
            "isotropic": True,
            "sampling": {"strategy": "sobol", "target": count, "seed": SEED},
        }
    )
    bounds = np.asarray(params.get(PARAMETRIZATION).iso_bounds, dtype=np.float64)
    stream = adaptive.Stream(density, seed)
    points = draw_kept(
        spec,
        rig,
        "limit",
        lambda k: draw_points(stream, k, bounds, rig, PARAMETRIZATION, True, False),
        count,
    )
    return measured_at(truth, spec, rig, points)


def simulated(
    truth: BrdfEval,
    rig: Rig,
    pairs: testset.TestSet,
    n: int,
    beta: float,
    volume: tuple[FloatArray, FloatArray],
) -> Measured:
    survey = synthesize(truth, rig, PARAMETRIZATION, True, 128, seed=SEED)
    model = fit(survey, "lambert+beckmann").model.eval
    density = cell_shares(model, rig, pairs, n, 8, beta, volume)
    return survey.joined(drawn(truth, rig, density, n - len(survey), SEED + 7))


def theta_h(wi: FloatArray, wo: FloatArray) -> FloatArray:
    """θh in degrees."""
    return np.asarray(np.degrees(np.arccos(np.clip(pair(wi, wo).cos_theta_h(), -1.0, 1.0))))


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--alpha", type=float, default=0.1)
    parser.add_argument("--counts", type=int, nargs="+", default=[250, 500, 1000, 2000, 4000])
    parser.add_argument(
        "--plans",
        nargs="+",
        default=["shipped", "own error", "oracle", "simulated", "oracle cells"],
        help="besides uniform: shipped, 'own error', oracle, simulated, 'oracle cells'",
    )
    args = parser.parse_args()
    print(describe())
    truth = ggx(args.alpha)
    rig = Rig.from_yaml(ROOT / "configs/rigs/arch.yaml")
    pairs = testset.draw(rig, isotropic=True)
    volume = placed(rig, PARAMETRIZATION, True, 1 << 16, seed=SEED + 1)
    # The uniform curve's exponent (error ∝ N^−β), measured with this module's defaults.
    beta = BETA
    plans: dict[str, Callable[[int], Measured]] = {
        "uniform": lambda n: synthesize(truth, rig, PARAMETRIZATION, True, n, seed=SEED),
        "shipped": lambda n: synthesize_adaptive(truth, rig, PARAMETRIZATION, True, n, seed=SEED),
        "own error": lambda n: passes(truth, rig, n, own_error),
        "oracle": lambda n: passes(truth, rig, n, oracle(truth)),
        "simulated": lambda n: simulated(truth, rig, pairs, n, beta, volume),
        "oracle cells": lambda n: drawn(
            truth, rig, cell_shares(truth, rig, pairs, n, 16, beta, volume), n, SEED + 7
        ),
    }
    print(f"\nGGX α {args.alpha}, {PARAMETRIZATION}, rbf; log-RMSE (uniform / plan)\n")
    print("| plan | " + " | ".join(f"{n:,}" for n in args.counts) + " |")
    print("|---|" + "---:|" * len(args.counts))
    errors: dict[str, list[float]] = {}
    last: Measured | None = None
    for name, make in plans.items():
        if name != "uniform" and name not in args.plans:
            continue
        errors[name] = []
        for n in args.counts:
            samples = make(n)
            candidate = reconstruct(samples, method="rbf", extrapolate="nearest")
            result = evaluate(candidate, truth, rig, isotropic=True, test_set=pairs)
            value = result.regions["all"].scores.log_rmse
            assert value is not None
            errors[name].append(value)
            if name == "oracle" and n == args.counts[-1]:
                last = samples
        cells = [
            f"{e:.4f}" if name == "uniform" else f"{e:.4f} ({u / e:.1f}×)"
            for e, u in zip(errors[name], errors["uniform"], strict=True)
        ]
        print(f"| {name} | " + " | ".join(cells) + " |", flush=True)
    if len(args.counts) > 1:  # the ceiling needs the uniform curve's slope
        beta = -np.polyfit(np.log(args.counts), np.log(errors["uniform"]), 1)[0]
        print(
            f"\nThe ceiling of any density (uniform error ∝ N^−{beta:.2f}): uniform log-RMSE / "
            "the best a density can give\n"
        )
        print("| cells | " + " | ".join(f"{n:,}" for n in args.counts) + " |")
        print("|---|" + "---:|" * len(args.counts))
        for cells in (4, 8, 16):
            gains = []
            for n in args.counts:
                mass, share = error_cells(truth, rig, pairs, n, cells, volume)
                used = share > 0
                best = np.sum((mass[used] * share[used] ** (2 * beta)) ** (1 / (1 + 2 * beta)))
                gains.append(math.sqrt(mass.sum() / best ** (1 + 2 * beta)))
            print(f"| {cells}³ | " + " | ".join(f"{g:.1f}×" for g in gains) + " |", flush=True)
    if last is None:
        return
    candidate = reconstruct(last, method="rbf", extrapolate="nearest")
    got = np.log1p(candidate.eval(pairs.wi, pairs.wo))
    square = (got - np.log1p(truth(pairs.wi, pairs.wo))) ** 2
    test_h, sample_h = theta_h(pairs.wi, pairs.wo), theta_h(last.wi, last.wo)
    uniform = synthesize(truth, rig, PARAMETRIZATION, True, args.counts[-1], seed=SEED)
    uniform_h = theta_h(uniform.wi, uniform.wo)
    print(
        f"\nThe oracle's plan at {args.counts[-1]:,}: where its squared error sits, by θh "
        "(and the uniform plan's samples)\n"
    )
    print("| θh | test pairs | uniform plan's samples | oracle's samples | its squared error |")
    print("|---|---:|---:|---:|---:|")
    for lo, hi in ((0, 2.5), (2.5, 5), (5, 10), (10, 20), (20, 90)):
        t = (test_h >= lo) & (test_h < hi)
        s = (sample_h >= lo) & (sample_h < hi)
        u = (uniform_h >= lo) & (uniform_h < hi)
        print(
            f"| {lo}°–{hi}° | {t.mean():.1%} | {u.mean():.1%} | {s.mean():.1%} | "
            f"{square[t].sum() / square.sum():.1%} |"
        )


if __name__ == "__main__":
    _report.run(main, __file__, __doc__, title="The limit of density placement")
