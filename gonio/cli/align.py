"""`gonio align RIG.yaml`: measure the rig's misalignment with a first-surface mirror
seated as the sample (`gonio.workflows.align`), fit it (`gonio.rig.alignment_fit`) and
write the alignment file (``RIG.alignment.yaml``) with the scan's readings beside it
(``RIG.alignment.scan.sqlite``); ``--check FILE``: a short scan and a verdict on whether
an alignment file still holds."""

from __future__ import annotations

import argparse
import math
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING

from gonio.cli import arguments

if TYPE_CHECKING:  # imported when the command runs
    from gonio.workflows import Scan, Verdict

#: Exit code of a check that ran and found the alignment no longer holds.
EXIT_DRIFTED = 1
#: How the printed summary names the scan's mode (`gonio.workflows.align`).
_MODE = {"fly": "fly scans", "stop_and_go": "stop-and-go"}


def _speedup(text: str) -> float:
    """A speed-up of the emulated rig, 1 (real time) to 1e6."""
    value = arguments.positive(text, "a speed-up", 1e6)
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a speed-up of at least 1, got {text!r}")
    return value


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser], help_: str) -> None:
    p = sub.add_parser(
        "align",
        help=help_,
        description="Measure the rig's misalignment: with a first-surface mirror in the "
        "sample holder, cross scans of the detector locate the specular peak at poses "
        "within the rig's limits (where the detector streams, flown: the scanned joint "
        "sweeps while the detector streams readings; a rehearsal flies at --speedup 1 "
        "only; stop-and-go with --stop-and-go); the fit "
        "gives each axis's zero offset, the sample's tilt and the pointing errors it "
        "determines, with standard errors, and names what would determine the rest. "
        "Writes the alignment file and the scan's readings beside it "
        "(docs/how-to/align.md). With --check: a short scan and a verdict on whether an "
        "existing alignment file still holds.",
        exit_codes={
            0: "the alignment written (or, with --check, it still holds)",
            EXIT_DRIFTED: "--check: the alignment no longer holds (the numbers are printed)",
            2: "bad input: the rig, the scene, an option, the output or the scan refused, "
            "in one line; nothing written",
        },
    )
    p.add_argument("rig", type=Path, help="the rig file (RIG.yaml)")
    p.add_argument(
        "--scene", type=Path, help="the scene file (where the detector is simulated: the mirror)"
    )
    p.add_argument(
        "-o",
        "--output",
        type=Path,
        help="the alignment file to write (default RIG.alignment.yaml beside the rig file); "
        "the readings go beside it (.scan.sqlite)",
    )
    p.add_argument("--overwrite", action="store_true", help="replace existing output files")
    p.add_argument(
        "--check",
        type=Path,
        metavar="ALIGNMENT.yaml",
        help="check this alignment file with a short scan instead of fitting a new one",
    )
    p.add_argument(
        "--exposure",
        type=arguments.positive_seconds,
        default=1e-3,
        metavar="S",
        help="each reading's exposure (default 1 ms: a mirror's peak is bright)",
    )
    p.add_argument(
        "--stop-and-go",
        action="store_true",
        help="stop at each angle of a cross scan (move, settle, read) even where the "
        "detector streams (default there: fly scans, 2.8 min against 7.3 on the simulated "
        "arch rig)",
    )
    p.add_argument("--seed", type=arguments.seed, help="the scan's seed (default: the scene's)")
    p.add_argument(
        "--rehearse",
        action="store_true",
        help="run the hardware path against emulated devices on pseudo-terminals",
    )
    p.add_argument(
        "--speedup",
        type=_speedup,
        default=50.0,
        help="--rehearse: how many times faster than real time the emulated rig runs "
        "(default 50; the scans fly at 1 only, else stop-and-go)",
    )
    p.set_defaults(func=cmd_align)


def default_output(rig: Path) -> Path:
    """``RIG.alignment.yaml`` beside ``RIG.yaml``."""
    return rig.with_name(f"{rig.stem}.alignment.yaml")


def readings_path(output: Path) -> Path:
    """The scan's readings beside the alignment file: ``X.alignment.scan.sqlite``."""
    return output.with_name(f"{output.stem}.scan.sqlite")


def cmd_align(args: argparse.Namespace) -> int:
    import dataclasses

    import numpy as np

    from gonio.config import ConfigError
    from gonio.output import reserve_output
    from gonio.rig import Rig, fit, from_fit, text
    from gonio.scene import load_scene
    from gonio.workflows import align, align_check, backends

    rig = Rig.from_yaml(args.rig)
    kind = backends.kind_of(rig, args.rehearse)
    if args.scene is not None and not backends.needs_scene(rig, kind):
        raise ConfigError(
            f"--scene {args.scene}: the rig's hardware measures the real mirror; a scene "
            "is for the simulated backend or --rehearse"
        )
    if args.scene is None and backends.needs_scene(rig, kind):
        raise ConfigError(f"{args.rig}: the detector is simulated: give --scene")
    scene = None if args.scene is None else load_scene(args.scene, rig)
    if args.check is not None:
        if args.output is not None or args.overwrite:
            raise ConfigError("--check writes nothing: drop -o and --overwrite")
        checked = rig.realigned(args.check)
        settings = dataclasses.replace(align.CHECK, exposure_s=args.exposure)
        result = align.run_scan(
            rig,
            scene,
            kind,
            settings,
            seed=args.seed,
            speedup=args.speedup,
            stop_and_go=args.stop_and_go,
        )
        return _print_verdict(align_check.verdict(checked, result.peaks), result, args.check)
    output = args.output or default_output(args.rig)
    sidecar = readings_path(output)
    for path in (output, sidecar):
        if (path.exists() or path.is_symlink()) and not args.overwrite:
            raise ConfigError(f"-o {path}: exists; give --overwrite to replace it")
    inputs = [args.rig, args.scene]
    with (
        reserve_output(output, "-o", inputs=inputs) as out,
        reserve_output(sidecar, "-o", inputs=inputs) as readings_out,
    ):
        settings = dataclasses.replace(align.ScanSettings(), exposure_s=args.exposure)
        result = align.run_scan(
            rig,
            scene,
            kind,
            settings,
            seed=args.seed,
            speedup=args.speedup,
            stop_and_go=args.stop_and_go,
        )
        fitted = fit(
            rig, result.peaks, np.full(len(result.peaks), math.radians(align.PEAK_SIGMA_DEG))
        )
        readings_out.write_with(lambda path: align.write_readings(path, result.readings))
        date = datetime.now(UTC).isoformat(timespec="seconds").replace("+00:00", "Z")
        made = from_fit(fitted, rig, args.rig.read_bytes(), sidecar, sidecar.read_bytes(), date)
        out.write_bytes(text(made).encode("utf-8"))
    assert made.fit is not None
    print(
        f"mirror scan: {len(result.peaks)} peaks, {len(result.readings.value)} readings "
        f"({_MODE[result.mode]}), instrument time {result.seconds / 60:.1f} min ({kind})"
    )
    print("determined:")
    for name, p in made.fit.parameters.items():
        unit = "mm" if name == "height_mm" else "°"
        print(f"  {name:<32} {p.value:+.4f} ± {p.error:.4f} {unit}")
    if made.fit.undetermined:
        print("undetermined (the least-norm share of what they do together is kept):")
        for name, hint in made.fit.undetermined.items():
            print(f"  {name:<32} {hint}")
    print(
        f"residuals: rms {made.fit.residual_rms_deg:.4f}°, max {made.fit.residual_max_deg:.4f}°"
        f"; χ² {made.fit.chi2:.3g} for {made.fit.dof} degrees of freedom"
    )
    print(f"wrote {output} (readings: {sidecar})")
    return 0


def _print_verdict(verdict: Verdict, result: Scan, check: Path) -> int:
    print(
        f"check of {check}: {len(result.peaks)} peaks ({_MODE[result.mode]}), "
        f"instrument time {result.seconds / 60:.1f} min"
    )
    for i, (miss, bound) in enumerate(verdict.rows_deg()):
        mark = "ok  " if miss[0] <= bound[0] and miss[1] <= bound[1] else "MISS"
        print(
            f"  {mark} peak {i + 1}: miss ({miss[0]:.4f}°, {miss[1]:.4f}°), "
            f"3σ ({bound[0]:.4f}°, {bound[1]:.4f}°)"
        )
    if verdict.holds:
        print(f"holds: every peak is where {check} puts it, within 3σ")
        return 0
    print(f"drifted: {check} no longer holds; measure again (gonio align)")
    return EXIT_DRIFTED
