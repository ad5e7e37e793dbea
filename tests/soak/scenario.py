"""What a soak runs: its fault rules (rates of the order users report), its plan and
its scene."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

ROOT = Path(__file__).resolve().parents[2]
ARCH = ROOT / "configs" / "rigs" / "arch.yaml"


def realistic_faults(targets: int) -> list[dict[str, Any]]:
    """The soak's fault rules for a run of ``targets`` samples: rates per sample of the
    order users report (a status packet lost in a thousand, a detector timeout in two
    thousand, a motor's hardware error a few times a week), bursts longer than the
    plan's retries, two health pauses that last hours (one clears within the plan's
    pause timeout, the other outlasts it) and brief supply sags."""
    return [
        {"kind": "comm_error", "packet": "lost", "rate": 1e-3},
        {"kind": "comm_error", "packet": "corrupt", "rate": 5e-4, "burst": 2},
        {"kind": "comm_error", "packet": "lost", "rate": 3e-5, "burst": 5},
        {"kind": "detector_error", "rate": 5e-4},
        {"kind": "detector_error", "rate": 2e-5, "burst": 4},
        {"kind": "saturated", "rate": 1e-3},
        {"kind": "motor_fault", "rate": 2e-5, "axis": "detector_elevation", "flags": ["overload"]},
        {"kind": "motor_fault", "rate": 1e-5, "axis": "light_elevation", "flags": ["overheating"]},
        {"kind": "motion_timeout", "rate": 1e-5},
        {"kind": "overheat", "at": [int(0.3 * targets)], "axis": "detector_azimuth",
         "temperature_c": 74.0, "for_s": 2.5 * 3600},
        {"kind": "supply_sag", "at": [int(0.6 * targets)], "voltage_v": 9.2, "for_s": 5 * 3600},
        {"kind": "supply_sag", "rate": 2e-5, "voltage_v": 9.6, "for_s": 600.0},
    ]  # fmt: skip


#: How the plan runs: a calibration every hour, health every 100 targets or 5 min, a
#: paused run checks again every 30 s and gives up (resumable) after 4 h.
ACQUISITION: dict[str, Any] = {
    "calibration": {"every_minutes": 60, "averages": 4},
    "on_fault": {"retries": 2, "then": "skip"},
    "health": {"every_samples": 100, "every_minutes": 5, "poll_s": 30,
               "pause_timeout_minutes": 240},
}  # fmt: skip


def sobol_plan(
    name: str, rig: Path, targets: int, exposure: dict[str, Any], acquisition: dict[str, Any],
    **search: int,
) -> str:  # fmt: skip
    """A soak's plan file: a Sobol plan of ``targets`` on ``rig`` (hybrid, isotropic,
    ``exposure`` in seconds and averages, ``search``: the planner's ordering options),
    acquired as ``acquisition`` says."""
    spec = {
        "name": name,
        "rig": str(rig),
        "parametrization": "hybrid",
        "isotropic": True,
        "sampling": {"strategy": "sobol", "target": targets, "seed": 1},
        "exposure": exposure,
        **search,
        "time_budget_s": 5,
        "acquisition": acquisition,
    }
    return yaml.safe_dump(spec, sort_keys=False)


def plan_yaml(targets: int, acquisition: dict[str, Any] | None = None) -> str:
    """A Sobol plan of ``targets`` on the arch rig (ordered without local search: the
    soak is of the acquisition, not of the planner)."""
    return sobol_plan(
        "soak", ARCH, targets, {"seconds": 0.5, "averages": 4}, acquisition or ACQUISITION,
        max_moves=0, kicks=0,
    )  # fmt: skip


def scene_yaml(faults: list[dict[str, Any]], seed: int) -> str:
    """Brushed metal with noise, drift, backlash and repeatability (every random stream
    and the motors' state matter to a resume), and ``faults``."""
    spec = {
        "name": "soak",
        "material": {"name": "ggx_anisotropic", "alpha_x": 0.05, "alpha_y": 0.25,
                     "fresnel": "conductor", "ior": 1.2, "k": 7.0},
        "source": {"irradiance_w_m2": 1.0},
        "detector": {"responsivity_a_w": 0.5, "dark_current_e_s": 2.0e5, "read_noise_e": 30,
                     "full_well_e": 1.0e10, "adc_bits": 24},
        "effects": {"shot_noise": None, "read_noise": None, "quantization": None,
                    "saturation": None,
                    "source_drift": {"rate_per_hour": 0.02, "amplitude": 0.005, "period_s": 900},
                    "position_error": {"ticks": True, "backlash_deg": 0.1,
                                       "repeatability_deg": 0.02}},
        "faults": faults,
        "seed": seed,
    }  # fmt: skip
    return yaml.safe_dump(spec, sort_keys=False)
