"""Motion blur in fly scans: the bias it leaves in the recovered BRDF, and the largest
smear a lobe width allows.

A reading taken while the detector sweeps integrates the BRDF along the arc it travels
during the integration; a reconstruction attributes it to the pose at the window's
middle. The bias is (mean power along the arc) / (power at the middle) − 1, computed with
the simulator's optics directly (`sim.virtual.physics.optics.SceneOptics`, no engine, no noise, no
aperture or footprint effect, so the bias is the blur's alone): the arch rig, the light at
30° incidence, the detector sweeping in the plane of incidence, the gold material of the
glossy scene with GGX widths α from 0.02 to 0.5. The arc mean is a 96-node
Gauss–Legendre rule (converged: the page's last line compares it with 48 nodes). The
smear is the angle the detector direction travels during one integration (° = angular
velocity × integration).

On the peak: the window centred on the specular direction. Over the lobe: the largest
|bias| of windows centred anywhere from 60° before to 55° after the peak (0.05° steps
near it). The rule: for each α and tolerance, the largest smear whose bias over the lobe
stays within the tolerance (bisection); a window's bias grows as smear², so the rule is
fitted as smear_max = K · α · √tolerance (`gonio.planner.blur.blur_budget_deg`).
Run: .venv/bin/python studies/fly_blur.py
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # _report
sys.path.insert(0, str(Path(__file__).resolve().parent))
import _report

from gonio.planner import BLUR_K_DEG, blur_budget_deg
from gonio.rig import Rig
from gonio.scene import Scene, load_scene
from sim.virtual import SceneOptics

ROOT = Path(__file__).resolve().parents[1]
ALPHAS = (0.02, 0.05, 0.1, 0.2, 0.5)
SMEARS_DEG = (0.05, 0.1, 0.2, 0.5, 1.0, 2.0, 5.0)
TOLERANCES = (0.001, 0.005, 0.02)
THETA_I_DEG = 30.0
NODES = 96


def optics(rig: Rig, alpha: float) -> SceneOptics:
    """The glossy gold scene's chain with GGX width ``alpha`` and no effects."""
    base = load_scene(ROOT / "configs" / "scenes" / "glossy_metal.yaml")
    material = {"name": "cook_torrance", **base.model_dump()["material"]["params"]}
    data = {**base.model_dump(), "material": {**material, "alpha": alpha}, "effects": []}
    return SceneOptics(Scene.model_validate(data), rig)


def power(rig: Rig, chain: SceneOptics, theta_o_deg: np.ndarray) -> np.ndarray:
    """Geometric power (W) with the detector at ``theta_o_deg`` (any shape) in the plane."""
    t = np.radians(np.asarray(theta_o_deg, dtype=np.float64)).ravel()
    poses = np.zeros((len(t), len(rig.axes)))
    poses[:, 0], poses[:, 2] = math.radians(THETA_I_DEG), -t
    return chain.geometric_power(*rig.forward(poses)).reshape(np.shape(theta_o_deg))


def bias(rig: Rig, chain: SceneOptics, centres_deg: np.ndarray, smear_deg: float) -> np.ndarray:
    """Mid-time attribution's relative bias of windows centred at ``centres_deg``."""
    x, w = np.polynomial.legendre.leggauss(NODES)
    arc = centres_deg[:, None] + 0.5 * smear_deg * x[None, :]
    mean = (power(rig, chain, arc) * (0.5 * w)).sum(axis=1)
    return mean / power(rig, chain, centres_deg) - 1.0


def peak_deg(rig: Rig, chain: SceneOptics) -> float:
    grid = np.arange(THETA_I_DEG - 5.0, THETA_I_DEG + 5.0, 1e-3)
    return float(grid[np.argmax(power(rig, chain, grid))])


def lobe_centres(peak: float) -> np.ndarray:
    near = np.arange(peak - 10.0, peak + 10.0, 0.05)
    far = np.arange(peak - 60.0, peak + 55.0, 0.5)
    return np.unique(np.concatenate([near, far]))


def worst(rig: Rig, chain: SceneOptics, peak: float, smear_deg: float) -> float:
    centres = lobe_centres(peak)
    centres = centres[np.abs(centres) + smear_deg / 2 < 88.0]
    return float(np.abs(bias(rig, chain, centres, smear_deg)).max())


def budget(rig: Rig, chain: SceneOptics, peak: float, tolerance: float) -> float:
    """The largest smear (°) whose worst bias over the lobe is within ``tolerance``."""
    lo, hi = 0.0, 30.0
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if worst(rig, chain, peak, mid) <= tolerance else (lo, mid)
    return lo


def main() -> None:
    rig = Rig.from_yaml(ROOT / "configs" / "rigs" / "arch.yaml")
    chains = {a: optics(rig, a) for a in ALPHAS}
    peaks = {a: peak_deg(rig, chains[a]) for a in ALPHAS}
    print("## Bias on the specular peak (mid-time attribution), %\n")
    print("| smear ° \\ α | " + " | ".join(f"{a:g}" for a in ALPHAS) + " |")
    print("| ---: |" + " ---: |" * len(ALPHAS))
    for s in SMEARS_DEG:
        cells = [f"{100 * bias(rig, chains[a], np.array([peaks[a]]), s)[0]:+.3g}" for a in ALPHAS]
        print(f"| {s:g} | " + " | ".join(cells) + " |")
    print("\n## Largest |bias| over the lobe (windows centred anywhere on it), %\n")
    print("| smear ° \\ α | " + " | ".join(f"{a:g}" for a in ALPHAS) + " |")
    print("| ---: |" + " ---: |" * len(ALPHAS))
    for s in SMEARS_DEG:
        cells = [f"{100 * worst(rig, chains[a], peaks[a], s):.3g}" for a in ALPHAS]
        print(f"| {s:g} | " + " | ".join(cells) + " |")
    print("\n## The rule: the largest smear for a bias within a tolerance\n")
    print("| tolerance | " + " | ".join(f"α = {a:g}" for a in ALPHAS) + " | K = smear / (α √tol) |")
    print("| ---: |" + " ---: |" * (len(ALPHAS) + 1))
    ks = []
    for tol in TOLERANCES:
        smax = np.array([budget(rig, chains[a], peaks[a], tol) for a in ALPHAS])
        k = smax / (np.array(ALPHAS) * math.sqrt(tol))
        ks.append(k)
        cells = [f"{v:.3g}°" for v in smax]
        print(f"| {100 * tol:g} % | " + " | ".join(cells) + f" | {k.min():.0f}–{k.max():.0f}° |")
    k_all = np.concatenate(ks)
    print(
        f"\nFitted: smear_max ≈ K · α · √tolerance with K = {k_all.min():.0f}° (the smallest "
        f"over every α and tolerance above, so the rule holds for each; largest "
        f"{k_all.max():.0f}°). At 0.5 %: smear_max ≈ {k_all.min() * math.sqrt(0.005):.1f}° × α."
    )
    print(
        f"`gonio.planner.blur.blur_budget_deg` uses K = {BLUR_K_DEG:g}°: "
        + ", ".join(f"α = {a:g} → {blur_budget_deg(a, 0.005):.3g}°" for a in ALPHAS)
        + " at 0.5 %."
    )
    check = bias(rig, chains[0.02], np.array([peaks[0.02]]), 1.0)[0]
    x, w = np.polynomial.legendre.leggauss(48)
    arc = peaks[0.02] + 0.5 * x
    coarse = (power(rig, chains[0.02], arc) * 0.5 * w).sum()
    coarse = coarse / power(rig, chains[0.02], np.array([peaks[0.02]]))[0] - 1
    print(
        f"\nQuadrature check (α = 0.02, 1° on the peak): {NODES} nodes {100 * check:+.8f} %, "
        f"48 nodes {100 * coarse:+.8f} %."
    )


if __name__ == "__main__":
    _report.run(main, __file__, __doc__, title="Motion blur in fly scans")
