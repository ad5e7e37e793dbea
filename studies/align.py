"""How well `gonio align` measures a misaligned rig, and what its alignment file gives
back in the recovered BRDF.

**Recovery.** Random misalignments of the arch rig (`configs/rigs/arch.yaml`): every
axis's zero offset uniform in ±1°, a sample wedge of 0.5° toward a random azimuth,
0.5 mm of sample height of random sign, pointing errors of 0.3° on the light and on the
detector in random directions. Each is put in a mirror scene (the glossy gold of
`configs/scenes/glossy_metal.yaml` made a mirror, GGX α 0.005, its noise on) as the
``misalignment`` effect, and `gonio align` runs on the simulator (in-process, seeded)
and writes its alignment file. For every parameter the file states as determined:
|estimate − truth| and that over its stated standard error. A mirror is symmetric about
its normal, so the sample rotation's zero offset only turns the sample frame about the
normal (the reference mark's orientation): the truth is compared in the estimate's
gauge (the offset moved into the tilt's azimuth, the same optics exactly). For what the
scan leaves undetermined (an axis's zero offset and a pointing error about the same
axis act alike; the height with a collimated beam), what matters instead: the angle
between each measured direction (ωi and ωo, forward kinematics at the joint angles of
the quick plan's 500 poses, `configs/plans/quick.yaml`) under the estimated alignment
and under the truth, both in that gauge. A few draws on the point-source rig
(`configs/rigs/arch_point.yaml`) ask whether the height becomes determined.

**The BRDF.** For the first draws, the glossy gold (α 0.05) measured with the quick
plan through the acquisition engine on the simulator: (a) a rig as its file says,
(b) the misaligned rig recorded with its file's geometry, (c) the misaligned rig with
the alignment file `gonio align` wrote, acquired with a rig file naming it (the plan
solved in the measured geometry) and (c′) run (b) re-derived with it (``--alignment``,
`gonio.analysis.realign`). Each run of a draw has the same noise seed (paired). Scores:
the log-RMSE `gonio evaluate` prints (the default reconstruction, ``linear`` with its
nearest fill, on the default test set of 20 000 pairs drawn from the rig file, the same
pairs for every run) and the log-RMSE of the calibrated samples against the scene's
BRDF at the pairs the run records (the misalignment's bias undiluted by the
reconstruction's own error).

The scan's instrument time is the simulated clock from the first reading to the last;
its wall time is that of `gonio align` in-process.

Run: .venv/bin/python studies/align.py [--draws 20] [--point-draws 3] [--paired 5] [--quick]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import math
import sqlite3
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # _report

import _report
import numpy as np
import yaml
from _machine import describe

from gonio.analysis.measured import Measured
from gonio.cli import main as gonio
from gonio.planner import Plan, load_plan_source
from gonio.reconstruct import testset
from gonio.reconstruct.evaluate import DEFAULT_FILL, evaluate
from gonio.reconstruct.methods import DEFAULT_METHOD, reconstruction
from gonio.reconstruct.truth import truth_from_spec
from gonio.rig import Rig
from gonio.rig.alignment_file import AlignmentFile, load_alignment
from gonio.rig.alignment_fit import miss, parameters, vector
from gonio.rig.alignment_spec import AlignmentSpec
from gonio.scene import Scene, load_scene
from gonio.types import FloatArray
from gonio.workflows.align_plan import ScanSettings, nominal_poses, reachable
from gonio.workflows.simulate import simulate_plan

ROOT = Path(__file__).resolve().parents[1]
ARCH = ROOT / "configs" / "rigs" / "arch.yaml"
POINT = ROOT / "configs" / "rigs" / "arch_point.yaml"
PLAN = ROOT / "configs" / "plans" / "quick.yaml"
GOLD = ROOT / "configs" / "scenes" / "glossy_metal.yaml"
#: The mirror: the gold's GGX roughness made this small.
MIRROR_ALPHA = 0.005
#: A point source's intensity (W/sr) giving the collimated scenes' 1 W/m² at 300 mm.
POINT_INTENSITY = 0.09
#: The draws: each zero offset uniform in ±ZERO_DEG; the tilt, |height| and each
#: pointing error's size fixed, their directions (and the height's sign) random.
ZERO_DEG, TILT_DEG, HEIGHT_MM, POINTING_DEG = 1.0, 0.5, 0.5, 0.3
#: What an alignment is for: each determined parameter within these (°, mm) ...
WITHIN_DEG, WITHIN_MM = 0.03, 0.05
#: ... and within this many of its stated standard errors.
WITHIN_SE = 3.0
#: The target on the BRDF: (c)/(a) of gonio evaluate's log-RMSE at most this.
TARGET_RATIO = 1.1


def draw(rng: np.random.Generator, axes: tuple[str, ...]) -> AlignmentSpec:
    """A random misalignment (see the module): zero offsets uniform in ±`ZERO_DEG`, a
    tilt of `TILT_DEG` toward a uniform azimuth, a height of ±`HEIGHT_MM`, pointing
    errors of `POINTING_DEG` toward uniform directions."""
    zero = rng.uniform(-ZERO_DEG, ZERO_DEG, len(axes))
    azimuth, light, detector = rng.uniform(0.0, 2.0 * math.pi, 3)
    sign = float(rng.choice((-1.0, 1.0)))
    return AlignmentSpec(
        zero_offset_deg=dict(zip(axes, zero.tolist(), strict=True)),
        tilt_deg=TILT_DEG,
        tilt_azimuth_deg=math.degrees(azimuth),
        height_mm=sign * HEIGHT_MM,
        light_pointing_deg=(POINTING_DEG * math.cos(light), POINTING_DEG * math.sin(light)),
        detector_pointing_deg=(
            POINTING_DEG * math.cos(detector),
            POINTING_DEG * math.sin(detector),
        ),
    )


def stage_axis(rig: Rig) -> str:
    """The sample stage's rotation about the normal: the sample chain's first axis,
    which must turn about z (`ValueError` otherwise)."""
    name = rig.spec.sample.axes[0]
    if list(rig.spec.axes[name].axis) != [0, 0, 1]:
        raise ValueError(f"{name}: the sample chain's first axis does not turn about z")
    return name


def gauged(spec: AlignmentSpec, stage: str, zero_deg: float = 0.0) -> AlignmentSpec:
    """``spec`` with the ``stage`` axis's zero offset set to ``zero_deg`` and the
    difference moved into the tilt's azimuth: the same optics, the sample frame turned
    about its normal by the difference (what a mirror and an isotropic BRDF cannot see)."""
    shift = spec.zero_offset_deg.get(stage, 0.0) - zero_deg
    azimuth = (spec.tilt_azimuth_deg + shift + 180.0) % 360.0 - 180.0
    zero = {**spec.zero_offset_deg, stage: zero_deg}
    return spec.model_copy(update={"zero_offset_deg": zero, "tilt_azimuth_deg": azimuth})


def angle_deg(a: FloatArray, b: FloatArray) -> FloatArray:
    """The angle (°) between unit vectors ``a`` and ``b`` (..., 3)."""
    cross = np.linalg.norm(np.cross(a, b), axis=-1)
    return np.asarray(np.degrees(np.arctan2(cross, np.sum(a * b, axis=-1))), dtype=np.float64)


def direction_errors(
    rig: Rig, poses: FloatArray, estimate: AlignmentSpec, truth: AlignmentSpec
) -> FloatArray:
    """(N, 2): the angles (°) between ωi and between ωo measured at the joint angles
    ``poses`` (N, A) under ``estimate`` and under ``truth``, both with the stage's zero
    offset moved into the tilt's azimuth (`gauged`)."""
    stage = stage_axis(rig)
    est = rig.forward(poses, gauged(estimate, stage).alignment(rig.axes))
    true = rig.forward(poses, gauged(truth, stage).alignment(rig.axes))
    return np.stack([angle_deg(est[0], true[0]), angle_deg(est[1], true[1])], axis=-1)


def truth_vector(rig: Rig, truth: AlignmentSpec, estimate: AlignmentSpec) -> FloatArray:
    """The truth as a parameter vector (`gonio.rig.alignment_fit.parameters` order; rad,
    mm) in the estimate's gauge: its stage zero offset the estimate's."""
    stage = stage_axis(rig)
    same = gauged(truth, stage, estimate.zero_offset_deg.get(stage, 0.0))
    return vector(rig, same.alignment(rig.axes))


def in_units(names: tuple[str, ...], values: FloatArray) -> FloatArray:
    """Parameter values in ° (mm for the height) from rad (mm)."""
    return np.where(np.array([n == "height_mm" for n in names]), values, np.degrees(values))


def peak_offsets(rig: Rig, truth: AlignmentSpec) -> FloatArray:
    """(M, 2) (°): where each mirror peak of the default scan lies under ``truth``, from
    its scan's centre, in detector elevation and azimuth (the scanned joints): the zero
    of the first-order miss (`gonio.rig.alignment_fit.miss`) by Newton steps, the light
    and the stage where the centre puts them."""
    settings = ScanSettings()
    centres = nominal_poses(rig, settings)
    centres = centres[reachable(rig, centres, settings)]
    alignment = truth.alignment(rig.axes)
    scanned = [rig.axes.index("detector_elevation"), rig.axes.index("detector_azimuth")]

    def missed(delta: FloatArray) -> FloatArray:
        poses = centres.copy()
        poses[:, scanned] += delta
        return miss(rig, poses, alignment)

    delta, step = np.zeros((len(centres), 2)), 1e-6
    for _ in range(8):
        jac = np.stack(
            [(missed(delta + step * e) - missed(delta - step * e)) / (2 * step) for e in np.eye(2)],
            axis=-1,
        )
        delta = delta - np.linalg.solve(jac, missed(delta)[..., None])[..., 0]
    return np.asarray(np.degrees(delta), dtype=np.float64)


@dataclass(frozen=True)
class Aligned:
    """One `gonio align`: the file, where it is, the scan's instrument and wall time (s)."""

    file: AlignmentFile
    path: Path
    instrument_s: float
    wall_s: float


def mirror_scene(base: dict[str, Any], truth: AlignmentSpec, folder: Path) -> Path:
    """The scene ``base`` (YAML data) made a mirror, misaligned by ``truth``."""
    data = {**base, "material": {**base["material"], "alpha": MIRROR_ALPHA}}
    data["effects"] = {**data["effects"], "misalignment": truth.model_dump(mode="json")}
    path = folder / "mirror.yaml"
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    return path


def align(rig_path: Path, scene: Path, seed: int, folder: Path) -> Aligned | str:
    """`gonio align` in-process on the simulator; the line it refused with, if it did."""
    output = folder / f"{rig_path.stem}.alignment.yaml"
    out, err = io.StringIO(), io.StringIO()
    started = time.perf_counter()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = gonio(["align", str(rig_path), "--scene", str(scene), "-o", str(output),
                      "--overwrite", "--seed", str(seed)])  # fmt: skip
    wall = time.perf_counter() - started
    if code != 0:
        return err.getvalue().strip().removeprefix("gonio: error: ") or f"exit {code}"
    sidecar = output.with_name(f"{output.stem}.scan.sqlite")
    with contextlib.closing(sqlite3.connect(sidecar)) as db:
        span = db.execute("SELECT MAX(ended_s) - MIN(ended_s) FROM reading").fetchone()[0]
    return Aligned(load_alignment(output), output, float(span), wall)


@dataclass(frozen=True)
class Recovery:
    """One draw's recovery: per parameter (`parameters` order) whether determined, the
    error (°, mm) and the standard error; the direction errors (N, 2) (°) under the
    estimate and under no alignment (the rig file's)."""

    determined: np.ndarray
    error: FloatArray
    se: FloatArray
    directions: FloatArray
    unaligned: FloatArray
    aligned: Aligned


def recover(rig: Rig, truth: AlignmentSpec, aligned: Aligned, poses: FloatArray) -> Recovery:
    names = parameters(rig)
    assert aligned.file.fit is not None
    values = vector(rig, aligned.file.alignment.alignment(rig.axes))
    errors = np.zeros(len(names))  # rad (mm), 0 where not determined
    for name, fitted in aligned.file.fit.parameters.items():
        errors[names.index(name)] = fitted.error * (1.0 if name == "height_mm" else np.pi / 180)
    true = truth_vector(rig, truth, aligned.file.alignment)
    determined = np.array([n in aligned.file.fit.parameters for n in names])
    return Recovery(
        determined=determined,
        error=np.abs(in_units(names, values - true)),
        se=in_units(names, errors),
        directions=direction_errors(rig, poses, aligned.file.alignment, truth),
        unaligned=direction_errors(rig, poses, AlignmentSpec(), truth),
        aligned=aligned,
    )


@dataclass(frozen=True)
class Draw:
    """One draw: its truth, where its peaks lie from their scans' centres ((M, 2) °,
    `peak_offsets`), and the recovery, or the line `gonio align` refused with."""

    truth: AlignmentSpec
    offsets: FloatArray
    outcome: Recovery | str


def recovery_tables(rig: Rig, draws: list[Draw]) -> None:
    """The per-draw table, then the per-parameter one and the worst case."""
    settings = ScanSettings()
    half, edge = settings.coarse_half_deg, settings.coarse_half_deg - settings.coarse_step_deg / 2
    print(
        "| draw | determined | χ²/dof | direction error max (°) | p95 (°) | "
        "with no alignment: max (°) | peaks' largest offset: elevation, azimuth (°) | "
        "instrument time (min) | wall (s) |"
    )
    print("| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for i, d in enumerate(draws):
        el, az = np.abs(d.offsets).max(axis=0)
        where = f"{el:.2f}, {az:.2f}"
        r = d.outcome
        if isinstance(r, str):
            print(f"| {i} | refused: {r} | | | | | {where} | | |")
            continue
        fit = r.aligned.file.fit
        assert fit is not None
        print(
            f"| {i} | {int(r.determined.sum())} | {fit.chi2 / max(fit.dof, 1):.3g} | "
            f"{r.directions.max():.4f} | {np.percentile(r.directions, 95):.4f} | "
            f"{r.unaligned.max():.3f} | {where} | {r.aligned.instrument_s / 60:.1f} | "
            f"{r.aligned.wall_s:.1f} |"
        )
    done = [(i, d.outcome) for i, d in enumerate(draws) if not isinstance(d.outcome, str)]
    refused = [i for i, d in enumerate(draws) if isinstance(d.outcome, str)]
    if refused:
        far = [i for i in refused if np.abs(draws[i].offsets).max() > edge]
        print(
            f"\n{len(refused)} of {len(draws)} draws refused (draws "
            f"{', '.join(map(str, refused))}); "
            f"in {len(far)} of them a peak lies nearer the coarse scan's last point (±{half:g}°) "
            f"than the one before it (beyond {edge:g}° from its centre)."
        )
    if not done:
        return
    names = parameters(rig)
    print(
        f"\n| parameter | determined in | median error | max error | within {WITHIN_DEG}° "
        f"({WITHIN_MM} mm) | median error / SE | max / SE | within {WITHIN_SE:g} SE |"
    )
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    worst = (0.0, "", -1)
    for k, name in enumerate(names):
        rows = [(i, r) for i, r in done if r.determined[k]]
        if not rows:
            print(f"| {name} | 0 of {len(done)} | — | — | — | — | — | — |")
            continue
        err = np.array([r.error[k] for _, r in rows])
        z = err / np.array([r.se[k] for _, r in rows])
        bound = WITHIN_MM if name == "height_mm" else WITHIN_DEG
        unit = " mm" if name == "height_mm" else "°"
        print(
            f"| {name} | {len(rows)} of {len(done)} | {np.median(err):.4f}{unit} | "
            f"{err.max():.4f}{unit} | {np.mean(err <= bound):.0%} | {np.median(z):.2f} | "
            f"{z.max():.2f} | {np.mean(z <= WITHIN_SE):.0%} |"
        )
        j = int(np.argmax(err / bound))
        if err[j] / bound > worst[0]:
            worst = (float(err[j] / bound), f"{name} {err[j]:.4f}{unit}", rows[j][0])
    d = np.stack([r.directions for _, r in done])
    chi = np.array(
        [
            r.aligned.file.fit.chi2 / max(r.aligned.file.fit.dof, 1)
            for _, r in done
            if r.aligned.file.fit is not None
        ]
    )
    print(
        f"\nWorst determined parameter: {worst[1]} (draw {worst[2]}). Direction error over "
        f"the {len(done)} fitted draws and every pose: max {d.max():.4f}° (ωi "
        f"{d[..., 0].max():.4f}°, ωo {d[..., 1].max():.4f}°), p95 {np.percentile(d, 95):.4f}°. "
        f"Median χ²/dof {np.median(chi):.3g}: the peaks scatter √(χ²/dof) = "
        f"{np.sqrt(np.median(chi)):.2f} times the location error the fit assumes."
    )


def recoveries(
    rig: Rig,
    rig_path: Path,
    scene: dict[str, Any],
    truths: list[AlignmentSpec],
    poses: FloatArray,
    folder: Path,
) -> list[Draw]:
    """`gonio align` of ``rig_path`` in the mirror made of ``scene``, for each truth."""
    out = []
    for i, truth in enumerate(truths):
        where = folder / f"{rig_path.stem}-{i}"
        where.mkdir()
        aligned = align(rig_path, mirror_scene(scene, truth, where), 1 + i, where)
        outcome = aligned if isinstance(aligned, str) else recover(rig, truth, aligned, poses)
        out.append(Draw(truth, peak_offsets(rig, truth), outcome))
    return out


@dataclass(frozen=True)
class Scores:
    """A run's log-RMSE as `gonio evaluate` prints it (all, mirror region) and its
    calibrated samples' log-RMSE at the pairs it records."""

    test: float
    mirror: float
    samples: float


def score(measured: Measured, pairs: testset.TestSet) -> Scores:
    truth = truth_from_spec(None, measured)
    candidate = reconstruction(measured, DEFAULT_METHOD, None, extrapolate=DEFAULT_FILL)
    e = evaluate(candidate, truth, measured.rig, isotropic=measured.isotropic, test_set=pairs)
    t = np.asarray(truth.eval(measured.wi, measured.wo), dtype=np.float64).reshape(measured.f.shape)
    ok = (measured.f > 0) & (t > 0)
    ratio = np.log(measured.f[ok] / t[ok])
    return Scores(
        e.regions["all"].scores.log_rmse or math.nan,
        e.regions["mirror"].scores.log_rmse or math.nan,
        float(np.sqrt(np.mean(ratio**2))),
    )


def with_misalignment(scene: Scene, truth: AlignmentSpec | None) -> Scene:
    effects = scene.effects.model_dump()
    if truth is None:
        return scene
    return scene.with_effects({**effects, "misalignment": truth.model_dump()})


def paired(
    plain: Plan,
    gold: Scene,
    truth: AlignmentSpec,
    aligned: Aligned,
    seed: int,
    pairs: testset.TestSet,
) -> dict[str, Scores]:
    """(a), (b), (c) and (c′) of one draw, every run with the noise ``seed``."""
    rig_file = aligned.path.parent / ARCH.name  # beside the alignment file it names
    rig_file.write_text(f"{ARCH.read_text()}\nalignment: {aligned.path.name}\n")
    with_file = load_plan_source(PLAN, rig_file).build()
    misaligned = with_misalignment(gold, truth)
    a = simulate_plan(plain, gold, seed)
    b = simulate_plan(plain, misaligned, seed)
    c = simulate_plan(with_file, misaligned, seed)
    return {
        "a": score(Measured.from_run(a.run, a.calibrated), pairs),
        "b": score(Measured.from_run(b.run, b.calibrated), pairs),
        "c": score(Measured.from_run(c.run, c.calibrated), pairs),
        "c′": score(Measured.from_run(b.run, alignment=aligned.path), pairs),
    }


def brdf_table(rows: list[dict[str, Scores]]) -> None:
    print(
        "| draw | (a) aligned | (b) misaligned | (c) with the file | (c′) re-derived | "
        "(b)/(a) | (c)/(a) | (c′)/(a) | samples (a) | (b) | (c) | (c′) |"
    )
    print("| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for i, s in enumerate(rows):
        a = s["a"].test
        print(
            f"| {i} | {a:.4f} | {s['b'].test:.4f} | {s['c'].test:.4f} | {s['c′'].test:.4f} | "
            f"{s['b'].test / a:.3f} | {s['c'].test / a:.3f} | {s['c′'].test / a:.3f} | "
            + " | ".join(f"{s[k].samples:.4f}" for k in ("a", "b", "c", "c′"))
            + " |"
        )
    print("\n| draw | mirror region log-RMSE (a) | (b) | (c) | (c′) |")
    print("| ---: | ---: | ---: | ---: | ---: |")
    for i, s in enumerate(rows):
        print(f"| {i} | " + " | ".join(f"{s[k].mirror:.4f}" for k in ("a", "b", "c", "c′")) + " |")
    ratios = {k: np.array([s[k].test / s["a"].test for s in rows]) for k in ("b", "c", "c′")}
    samples = {k: np.array([s[k].samples / s["a"].samples for s in rows]) for k in ("b", "c", "c′")}
    held = all(np.all(ratios[k] <= TARGET_RATIO) for k in ("c", "c′"))
    print(
        f"\nOver {len(rows)} draws, gonio evaluate's log-RMSE: (b)/(a) mean "
        f"{ratios['b'].mean():.3f} (max {ratios['b'].max():.3f}); (c)/(a) max "
        f"{ratios['c'].max():.3f}, (c′)/(a) max {ratios['c′'].max():.3f}: the target "
        f"(c)/(a) ≤ {TARGET_RATIO} {'holds' if held else 'FAILS'}. The samples' log-RMSE: "
        f"(b)/(a) mean {samples['b'].mean():.1f}, (c)/(a) mean {samples['c'].mean():.2f} "
        f"(max {samples['c'].max():.2f}), (c′)/(a) mean {samples['c′'].mean():.2f} "
        f"(max {samples['c′'].max():.2f})."
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--draws", type=int, default=20, help="random draws on the arch rig")
    parser.add_argument("--point-draws", type=int, default=3, help="draws on the point rig")
    parser.add_argument("--paired", type=int, default=5, help="draws measuring the gold")
    parser.add_argument("--seed", type=int, default=2027, help="the draws' seed")
    parser.add_argument("--quick", action="store_true", help="3 draws, 1 point, 1 paired")
    args = parser.parse_args()
    if args.quick:
        args.draws, args.point_draws, args.paired = 3, 1, 1
    print(describe())
    rng = np.random.default_rng(args.seed)
    arch = Rig.from_yaml(ARCH)
    source = load_plan_source(PLAN, ARCH)
    plain = source.build()
    poses = plain.angles
    base = yaml.safe_load(GOLD.read_text())
    gold = load_scene(GOLD, arch)
    pairs = testset.draw(arch, isotropic=True)
    truths = [draw(rng, arch.axes) for _ in range(args.draws)]
    with tempfile.TemporaryDirectory() as tmp:
        draws = recoveries(arch, ARCH, base, truths, poses, Path(tmp))
        print(f"\n== Recovery on the arch rig: {args.draws} draws\n")
        recovery_tables(arch, draws)
        rows: list[dict[str, Scores]] = []
        for i, d in enumerate(draws):
            if isinstance(d.outcome, Recovery) and len(rows) < args.paired:
                rows.append(paired(plain, gold, d.truth, d.outcome.aligned, 100 + i, pairs))
        if rows:
            print(
                f"\n== The glossy gold through the misaligned rig: {len(rows)} draws, "
                f"the quick plan ({len(plain)} targets)\n"
            )
            brdf_table(rows)
        point = Rig.from_yaml(POINT)
        lamp = {**base, "source": {"intensity_w_sr": POINT_INTENSITY}}
        seen = poses[point.pose_reasons(poses)[1]]  # the plan's poses the point rig measures
        spots = recoveries(point, POINT, lamp, truths[: args.point_draws], seen, Path(tmp))
        print(
            f"\n== Recovery on the point-source rig: {args.point_draws} draws, the "
            f"directions at the {len(seen)} of the plan's poses it measures\n"
        )
        recovery_tables(point, spots)
        fits = [d.outcome.aligned.file.fit for d in spots if isinstance(d.outcome, Recovery)]
        print(
            "\nThe height is determined in "
            f"{sum('height_mm' in f.parameters for f in fits if f is not None)} of "
            f"{len(fits)} fitted point-source draws."
        )


if __name__ == "__main__":
    _report.run(main, __file__, __doc__, title="Aligning the rig: recovery and its BRDF")
