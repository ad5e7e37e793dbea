"""The shipped study's noise-free parts (docs/explanations/tradeoff.md "The study").

Uniform Sobol plans of each shipped scene's material (as its detector's band sees it), in
each parametrization, from 250 to 30 000 samples, synthesized without the engine
(`studies.reconstruct.synthetic`: the planner's placement, the rig's reach, exact values),
reconstructed by name (`gonio.reconstruct.methods`, as `gonio tradeoff` does) and scored
by log-RMSE on log(1 + f) over the default test set (20 000 pairs, seed 14). The engine
sweeps (configs/sweeps/study_*.yaml) give the noisy curves and the instrument time.

    curves   error against sample count, by region; the counts needed for 0.01 and 0.03
    where    where the error sits at one count: by region, by ‖k‖, by max(θi, θo), and the
             share of samples each region gets against its share of the test set
    budget   the 8 θi × 32 θo × 32 Δφ grid of measured-material databases (8 192
             samples) against Sobol plans of each parametrization
    lobes    Romanyuk et al.'s lobes as stand-ins for Blinn-Phong cos^n θh: time against error

Run: .venv/bin/python studies/study.py curves -o runs/study [--scenes matte ...]
[--counts 250 ... 30000] [--methods linear rbf] [--sampling sobol adaptive]
[--adaptive-model survey]; `where`, `budget`, `lobes` likewise. `--sampling adaptive`:
the two-pass plans of docs/explanations/adaptive.md
(`studies.reconstruct.synthetic.synthesize_adaptive`).
`curves` appends to OUT/curves.csv and skips the rows it holds (resumable).
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import itertools
import math
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # _report
sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # studies
import _curves_figure
import _report
from _machine import describe

from gonio import brdf, params
from gonio.analysis import Measured
from gonio.planner import PlanSpec, directions, place
from gonio.radiometry import band_eval
from gonio.reconstruct import NAMES as REGIONS
from gonio.reconstruct import Reconstruction, evaluate, reconstruction, regions, testset
from gonio.rig import Rig
from gonio.scene import load_scene
from gonio.types import BrdfEval
from studies.reconstruct.synthetic import synthesize, synthesize_adaptive

ROOT = Path(__file__).resolve().parent.parent
#: scene file stem → (rig file stem, planned isotropically)
SCENES = {
    "matte": ("arch", True),
    "glossy_metal": ("arch", True),
    "brushed_metal": ("arch", False),
    "seed000_specular": ("arch_point", True),
}
COUNTS = (250, 500, 1000, 2000, 4000, 8000, 16000, 30000)
TARGETS = (0.01, 0.03)
SEED = 3
COLUMNS = (
    "scene",
    "sampling",
    "parametrization",
    "method",
    "samples",
    "measured",
    "log_rmse",
    "answered",
    "log_rmse_nearest",
    *(f"{r}_log_rmse" for r in REGIONS),
    "wall_s",
)


def setting(scene: str) -> tuple[Rig, bool, BrdfEval]:
    """The scene's rig, whether it is planned isotropically, and its truth f(wi, wo)."""
    rig_stem, isotropic = SCENES[scene]
    rig = Rig.from_yaml(ROOT / f"configs/rigs/{rig_stem}.yaml")
    loaded = load_scene(ROOT / f"configs/scenes/{scene}.yaml", rig)
    return rig, isotropic, band_eval(loaded.material.model(), loaded.detector.band)


def score(measured: Measured, method: str, truth: BrdfEval, rig: Rig, iso: bool) -> dict[str, Any]:
    """log-RMSE as the study sweeps score it (only the pairs inside the reconstruction's
    support; ``answered`` is their share), by region, and
    over every pair with the nearest sample's value filled in (``log_rmse_nearest``)."""
    pairs = testset.draw(rig, isotropic=iso)
    candidate = reconstruction(measured, method, None)
    result = evaluate(candidate, truth, rig, isotropic=iso, test_set=pairs, only_supported=True)
    out: dict[str, Any] = {"log_rmse": result.regions["all"].scores.log_rmse}
    out.update({f"{r}_log_rmse": result.regions[r].scores.log_rmse for r in REGIONS})
    out["answered"] = result.regions["all"].scores.count / result.regions["all"].pairs
    if isinstance(candidate, Reconstruction) and out["answered"] < 1.0:
        filled = dataclasses.replace(candidate, extrapolate="nearest")
        everywhere = evaluate(filled, truth, rig, isotropic=iso, test_set=pairs)
        out["log_rmse_nearest"] = everywhere.regions["all"].scores.log_rmse
    else:
        out["log_rmse_nearest"] = out["log_rmse"]
    return out


def needed(counts: list[int], errors: list[float], target: float) -> float:
    """The count reaching ``target``, log-log between the bracketing counts (inf: none)."""
    for (n0, e0), (n1, e1) in itertools.pairwise(zip(counts, errors, strict=True)):
        if e0 > target >= e1:
            t = math.log(e0 / target) / math.log(e0 / e1)
            return math.exp(math.log(n0) + t * math.log(n1 / n0))
    return counts[0] if errors and errors[0] <= target else math.inf


def fmt_needed(value: float, counts: list[int]) -> str:
    if math.isinf(value):
        return f"> {counts[-1]:,}"
    return f"≤ {counts[0]:,}" if value == counts[0] else f"{value:,.0f}"


def curves(args: argparse.Namespace) -> None:
    out = Path(args.out) / "curves.csv"
    out.parent.mkdir(parents=True, exist_ok=True)
    done: set[tuple[str, ...]] = set()
    if out.exists():
        with out.open(encoding="utf-8") as fh:
            done = {
                (r["scene"], r["sampling"], r["parametrization"], r["method"], r["samples"])
                for r in csv.DictReader(fh)
            }
    new = not out.exists()
    computed = 0
    with out.open("a", encoding="utf-8", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=COLUMNS)
        if new:
            writer.writeheader()
        for scene in args.scenes:
            rig, iso, truth = setting(scene)
            for kind, name, n in itertools.product(args.sampling, args.params, args.counts):
                todo = [m for m in args.methods if (scene, kind, name, m, str(n)) not in done]
                if not todo:
                    continue
                if kind == "adaptive":
                    samples = synthesize_adaptive(
                        truth, rig, name, iso, n, seed=args.seed, adaptive=args.adaptive
                    )
                else:
                    samples = synthesize(truth, rig, name, iso, n, seed=args.seed)
                for method in todo:
                    started = time.perf_counter()
                    row = {
                        "scene": scene,
                        "sampling": kind,
                        "parametrization": name,
                        "method": method,
                        "samples": n,
                        "measured": len(samples.f),
                        **score(samples, method, truth, rig, iso),
                    }
                    row["wall_s"] = round(time.perf_counter() - started, 3)
                    writer.writerow(row)
                    fh.flush()
                    computed += 1
                    # progress on stderr: the page holds the report
                    print(scene, kind, name, method, n, f"{row['log_rmse']:.4f}", file=sys.stderr)
    print(f"{computed} rows computed in this run, {len(done)} read from {out} (resumed)")
    report(out, tuple(args.targets), figure_of(args))


def figure_of(args: argparse.Namespace) -> Path:
    """The figure of the curves page ``args`` write (docs/img/study-curves*.png)."""
    suffix = "-adaptive" if "adaptive" in args.sampling else ""  # as `adaptive` names the page
    return ROOT / "docs" / "img" / f"study-{args.part}{suffix}.png"


def report(path: Path, targets: tuple[float, ...] = TARGETS, figure: Path | None = None) -> None:
    """The figure of curves.csv (``figure``: its path; `_curves_figure`), then markdown
    tables: error by count, then the counts for each target; where adaptive plans were
    measured too, the best of each kind against the other."""
    with path.open(encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    for r in rows:
        r.setdefault("sampling", "sobol")  # a curves.csv of uniform plans only
    if figure is not None:
        _curves_figure.draw(rows, figure, targets)
        _report.figure(figure, _curves_figure.alt_text(rows))
    for scene in dict.fromkeys(r["scene"] for r in rows):
        mine = [r for r in rows if r["scene"] == scene]
        counts = sorted({int(r["samples"]) for r in mine})
        print(f"\n### {scene} (noise-free, log-RMSE)\n")
        heads = " | ".join(f"{n:,}" for n in counts)
        needs = " | ".join(f"n for {t}" for t in targets)
        print(f"| sampling | parametrization | method | {heads} | {needs} |")
        print("|---|---|---|" + "---:|" * (len(counts) + len(targets)))
        plans = dict.fromkeys((r["sampling"], r["parametrization"], r["method"]) for r in mine)
        for kind, name, method in plans:
            by_n = {
                int(r["samples"]): float(r["log_rmse"])
                for r in mine
                if (r["sampling"], r["parametrization"], r["method"]) == (kind, name, method)
            }
            ns = [n for n in counts if n in by_n]
            errs = [by_n[n] for n in ns]
            cells = " | ".join(f"{by_n[n]:.4f}" if n in by_n else "—" for n in counts)
            need = " | ".join(fmt_needed(needed(ns, errs, t), ns) for t in targets)
            print(f"| {kind} | {name} | {method} | {cells} | {need} |")
        if {r["sampling"] for r in mine} >= {"sobol", "adaptive"}:
            compare(mine, counts, targets)


def compare(rows: list[dict[str, str]], counts: list[int], targets: tuple[float, ...]) -> None:
    """The best uniform plan against the best adaptive one (over the parametrizations and
    methods measured), at each count and in the samples each needs for each target."""
    best = {
        kind: {
            n: min(
                float(r["log_rmse"])
                for r in rows
                if r["sampling"] == kind and int(r["samples"]) == n
            )
            for n in counts
        }
        for kind in ("sobol", "adaptive")
    }
    ratios = ", ".join(f"{best['sobol'][n] / best['adaptive'][n]:.2f}×" for n in counts)
    print(
        f"\nbest uniform / best adaptive error at {', '.join(f'{n:,}' for n in counts)}: {ratios}"
    )
    for t in targets:
        u = needed(counts, [best["sobol"][n] for n in counts], t)
        a = needed(counts, [best["adaptive"][n] for n in counts], t)
        ratio = "" if math.isinf(u) or math.isinf(a) else f" (adaptive / uniform {a / u:.2f})"
        print(
            f"samples for {t}: best uniform {fmt_needed(u, counts)}, best adaptive "
            f"{fmt_needed(a, counts)}{ratio}"
        )


def where(args: argparse.Namespace) -> None:
    """Where the error sits at ``args.count`` samples (method ``args.methods[0]``)."""
    method = args.methods[0]
    for scene in args.scenes:
        rig, iso, truth = setting(scene)
        pairs = testset.draw(rig, isotropic=iso)
        wi, wo = pairs.wi, pairs.wo
        t = np.asarray(truth(wi, wo), dtype=np.float64)
        hybrid = params.get("hybrid")
        k = hybrid.forward(wi, wo)[..., 2]
        theta = np.degrees(np.arccos(np.minimum(np.minimum(wi[:, 2], wo[:, 2]), 1.0)))
        test_regions = regions(wi, wo)
        print(
            f"\n### {scene}: {args.count:,} samples, {method}; the error's share "
            "(mean square, % of the total; outside the samples' hull the nearest sample's value) "
            "and the samples' density against the test set's\n"
        )
        bins = {
            "‖k‖": (k, (0.0, 0.25, 0.5, 0.75, 1.0)),
            "max θ (°)": (theta, (0.0, 30.0, 50.0, 70.0, 80.0)),
        }
        heads = [
            *REGIONS,
            *(
                f"{lab} {a:g}–{b:g}"
                for lab, (_, e) in bins.items()
                for a, b in itertools.pairwise(e)
            ),
        ]
        print("| parametrization | log-RMSE | " + " | ".join(heads) + " |")
        print("|---|---:|" + "---:|" * len(heads))
        share_test = [float(np.mean(test_regions[r])) for r in REGIONS]
        for name in params.names():
            samples = synthesize(truth, rig, name, iso, args.count, seed=SEED)
            candidate = reconstruction(samples, method, None)
            if isinstance(candidate, Reconstruction):
                candidate = dataclasses.replace(candidate, extrapolate="nearest")
            c = np.asarray(candidate.eval(wi, wo), dtype=np.float64)
            sq = np.square(np.log1p(np.maximum(c, 0)) - np.log1p(np.maximum(t, 0)))
            sq = sq.reshape(len(wi), -1).mean(axis=1)
            total = float(np.sum(sq))
            sample_regions = regions(samples.wi, samples.wo)
            cells = [
                f"{100 * np.sum(sq[test_regions[r]]) / total:.0f} "
                f"({float(np.mean(sample_regions[r])) / s:.2f}×)"
                for r, s in zip(REGIONS, share_test, strict=True)
            ]
            ks = hybrid.forward(samples.wi, samples.wo)[..., 2]
            ths = np.degrees(np.arccos(np.minimum(samples.wi[:, 2], samples.wo[:, 2])))
            for (values, edges), svals in zip(bins.values(), (ks, ths), strict=True):
                for a, b in itertools.pairwise(edges):
                    inside = (values >= a) & (values < b) if b < edges[-1] else values >= a
                    s_in = (svals >= a) & (svals < b) if b < edges[-1] else svals >= a
                    ratio = float(np.mean(s_in)) / max(float(np.mean(inside)), 1e-12)
                    cells.append(f"{100 * np.sum(sq[inside]) / total:.0f} ({ratio:.2f}×)")
            print(f"| {name} | {math.sqrt(total / len(sq)):.4f} | " + " | ".join(cells) + " |")


def merl_grid(rig: Rig) -> tuple[np.ndarray, np.ndarray]:
    """The kept pairs of an isotropic spherical grid of 8 θi × 32 θo × 32 Δφ."""
    spec = PlanSpec.model_validate(
        {
            "name": "merl",
            "parametrization": "spherical",
            "isotropic": True,
            "sampling": {
                "strategy": "grid",
                "counts": {"theta_i": 8, "theta_o": 32, "phi_o_minus_phi_i": 32},
            },
        }
    )
    coords, _ = place(spec, rig, "merl")
    _, wi, wo = directions(spec, coords)
    ok = rig.solve(wi, wo, isotropic=True).ok
    return wi[ok], wo[ok]


def budget(args: argparse.Namespace) -> None:
    print("\n| scene | plan | samples kept | " + " | ".join(args.methods) + " |")
    print("|---|---|---:|" + "---:|" * len(args.methods))
    for scene in args.scenes:
        rig, iso, truth = setting(scene)
        if not iso:
            continue
        wi, wo = merl_grid(rig)
        values = np.asarray(truth(wi, wo), dtype=np.float64)
        grid = Measured(
            wi=wi,
            wo=wo,
            f=values,
            sigma=0.01 * np.abs(values),
            parametrization="spherical",
            isotropic=True,
            rig=rig,
            scene_text=None,
            band="luminance",
            source="8 × 32 × 32 spherical grid",
        )
        plans = [("8 θi × 32 θo × 32 Δφ grid", grid)]
        plans += [
            (f"Sobol {name}", synthesize(truth, rig, name, True, 8192, seed=SEED))
            for name in params.names()
        ]
        for label, samples in plans:
            errs = [f"{score(samples, m, truth, rig, True)['log_rmse']:.4f}" for m in args.methods]
            print(
                f"| {scene} | {label} | {len(samples.f):,} | " + " | ".join(errs) + " |", flush=True
            )


def lobes(args: argparse.Namespace) -> None:
    """Romanyuk et al.'s lobes as stand-ins for Blinn-Phong (ks = 0.8, kd = 0.2), next to linear
    reconstructions of Blinn-Phong from uniform hybrid samples, on the arch rig's test
    set (`evaluate`: pairs a reconstruction leaves NaN outside its hull are not scored):
    log-RMSE, the 95th percentile of the relative error, the share answered, ns per pair
    of `eval`."""
    rig = Rig.from_yaml(ROOT / "configs/rigs/arch.yaml")
    pairs = testset.draw(rig, isotropic=True)
    wi, wo = pairs.wi, pairs.wo
    names = ("blinn_phong", "cosine_quadratic", "cosine_quadratic_modified", "schlick_lobe")
    print("\n| n | stand-in | log-RMSE | rel. p95 | answered | ns per pair |")
    print("|---:|---|---:|---:|---:|---:|")
    for n in args.shininess:
        exact = brdf.create("blinn_phong", n=n, ks=0.8, kd=0.2)
        stand_ins: list[tuple[str, Any]] = [
            (name, brdf.create(name, n=n, ks=0.8, kd=0.2)) for name in names
        ]
        stand_ins += [
            (
                f"linear, {m:,} hybrid samples",
                reconstruction(
                    synthesize(exact.eval, rig, "hybrid", True, m, seed=SEED), "linear", None
                ),
            )
            for m in args.lobe_samples
        ]
        for name, model in stand_ins:
            value = np.asarray(model.eval(wi, wo), dtype=np.float64)
            runs = []
            for _ in range(5):
                started = time.perf_counter()
                model.eval(wi, wo)
                runs.append(time.perf_counter() - started)
            scored = evaluate(model, exact.eval, rig, isotropic=True, test_set=pairs)
            overall = scored.regions["all"]
            print(
                f"| {n:g} | {name} | {overall.scores.log_rmse:.4f} | "
                f"{overall.scores.rel_p95:.4f} | {np.mean(np.isfinite(value)):.3f} | "
                f"{1e9 * min(runs) / len(wi):,.0f} |",
                flush=True,
            )


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("part", choices=("curves", "report", "where", "budget", "lobes"))
    parser.add_argument("-o", "--out", default="runs/study")
    parser.add_argument("--scenes", nargs="+", default=list(SCENES), choices=list(SCENES))
    parser.add_argument("--counts", type=int, nargs="+", default=list(COUNTS))
    parser.add_argument("--params", nargs="+", default=list(params.names()))
    parser.add_argument(
        "--sampling",
        nargs="+",
        default=["sobol"],
        choices=("sobol", "adaptive"),
        help="uniform Sobol plans, or adaptive ones (`curves`)",
    )
    parser.add_argument(
        "--adaptive-model",
        default=None,
        help="the adaptive plans' steering (a fit family, or 'survey'; default the planner's)",
    )
    parser.add_argument("--seed", type=int, default=SEED, help="the Sobol seed of `curves`")
    parser.add_argument("--targets", type=float, nargs="+", default=list(TARGETS))
    parser.add_argument("--count", type=int, default=4000, help="samples of `where`")
    parser.add_argument("--methods", nargs="+", default=["linear", "rbf"])
    parser.add_argument("--lobe-samples", type=int, nargs="+", default=[2000, 8000])
    parser.add_argument("--shininess", type=float, nargs="+", default=[20.0, 100.0, 500.0])
    args = parser.parse_args()
    args.adaptive = {} if args.adaptive_model is None else {"model": args.adaptive_model}
    print(describe())
    if args.part == "report":
        report(Path(args.out) / "curves.csv", tuple(args.targets), figure_of(args))
        return
    {"curves": curves, "where": where, "budget": budget, "lobes": lobes}[args.part](args)


def adaptive(argv: Sequence[str]) -> str | None:
    """Curves of adaptive plans have their own page: study-curves-adaptive.md."""
    return "adaptive" if "adaptive" in _report.option(argv, "--sampling") else None


#: Each part's page title.
TITLES = {
    "curves": "Noise-free error against sample count, per parametrization and method",
    "curves-adaptive": "Noise-free error of adaptive against uniform plans",
    "report": "Noise-free error against sample count: the report of curves.csv",
    "where": "Where the error of a uniform plan sits",
    "budget": "Against the 8 192-sample budget of measured-material databases",
    "lobes": "Romanyuk et al.'s lobes as stand-ins for Blinn-Phong, in the study's metric",
}


def title(argv: Sequence[str]) -> str:
    part = argv[0] if argv else ""
    key = f"{part}-{adaptive(argv)}" if adaptive(argv) else part
    return TITLES.get(key, "The study, noise-free")


if __name__ == "__main__":
    _report.run(main, __file__, __doc__, title=title, part=True, variant=adaptive)
