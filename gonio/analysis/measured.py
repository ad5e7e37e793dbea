"""A run's samples as BRDF measurements: the direction pairs from the read-back angles,
the calibrated values and their 1σ uncertainty, the rig that measured them and, for a
simulated run, the scene it measured (the truth to compare with).

A run is one channel (the detector's band). An RGB measurement is three runs of the
same plan seen in the r, g and b bands, combined with `Measured.rgb`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from gonio.analysis.calibrated import Calibrated, calibrate
from gonio.analysis.realign import realigned
from gonio.analysis.scene import scene_band, scene_truth
from gonio.errors import GonioError
from gonio.rig import Rig
from gonio.store import Run, open_run
from gonio.types import BoolArray, BrdfEval, FloatArray


@dataclass(frozen=True)
class Measured:
    """Measured samples (N of them).

    wi, wo: (N, 3) unit directions (sample frame, z = normal, away from the surface).
    f, sigma: (N,) BRDF values and 1σ uncertainties in sr⁻¹, or (N, 3) for RGB.
    parametrization, isotropic: the plan's (the reconstruction's defaults).
    rig: the rig that measured them (its measurable domain bounds a reconstruction).
    scene_text: the simulated scene's YAML (None for a run on hardware).
    scene_path: where that scene file was (a material's relative ``path`` resolves
        against it).
    band: the detector's band(s) ("luminance", "r", "g", "b", or "rgb").
    """

    wi: FloatArray
    wo: FloatArray
    f: FloatArray
    sigma: FloatArray
    parametrization: str
    isotropic: bool
    rig: Rig
    scene_text: str | None
    band: str
    source: str
    scene_path: str | None = None

    def __len__(self) -> int:
        return len(self.wi)

    @property
    def is_rgb(self) -> bool:
        return self.f.ndim == 2

    def subset(self, index: np.ndarray | slice) -> Measured:
        """The samples at ``index`` (a mask, indices or a slice), in that order."""
        return replace(
            self, wi=self.wi[index], wo=self.wo[index], f=self.f[index], sigma=self.sigma[index]
        )

    def joined(self, other: Measured) -> Measured:
        """These samples, then ``other``'s (the rest of the measurement is this one's)."""
        return replace(
            self,
            wi=np.concatenate([self.wi, other.wi]),
            wo=np.concatenate([self.wo, other.wo]),
            f=np.concatenate([self.f, other.f]),
            sigma=np.concatenate([self.sigma, other.sigma]),
        )

    @classmethod
    def from_run(
        cls,
        run: Run | str,
        calibrated: Calibrated | None = None,
        *,
        alignment: str | Path | None = None,
    ) -> Measured:
        """The calibrated samples of a run (a `Run` or a run file's path; ``calibrated``:
        its `calibrate`, when the caller has it already) that have a finite value and σ
        (`kept`); `GonioError` (one line) when it has no sample or no calibration.
        ``alignment``: an alignment file to re-derive the run's pairs with (`realigned`;
        ``calibrated`` is then recomputed)."""
        if not isinstance(run, Run):
            run = open_run(run)
        if alignment is not None:
            run, calibrated = realigned(run, alignment), None
        if len(run) == 0:
            raise GonioError(f"{run.path}: the run has no sample yet")
        calibrated = calibrate(run) if calibrated is None else calibrated
        wi, wo = run.directions()
        aligned = run.meta.get("alignment_text")
        rig = (
            run.plan.rig
            if alignment is not None
            else Rig.from_yaml(
                str(run.meta.get("rig_path", run.path)),
                raw=_bytes(run.meta["rig_text"]),
                alignment_raw=None if aligned is None else _bytes(aligned),
            )
        )
        scene_text = run.meta.get("scene_text")
        band = "luminance"
        if scene_text is not None:
            band = scene_band(scene_text)
        ok = kept(calibrated)
        return cls(
            wi=wi[ok],
            wo=wo[ok],
            f=calibrated.brdf[ok],
            sigma=calibrated.sigma[ok],
            parametrization=run.plan.spec.parametrization,
            isotropic=run.plan.spec.isotropic,
            rig=rig,
            scene_text=scene_text,
            scene_path=run.meta.get("scene_path"),
            band=band,
            source=str(run.path),
        )

    @classmethod
    def rgb(cls, red: Measured, green: Measured, blue: Measured) -> Measured:
        """Three single-band measurements of the same pairs as one RGB measurement
        (`GonioError` unless their bands are r, g, b and their pairs agree to 1e-9)."""
        parts = (red, green, blue)
        if tuple(m.band for m in parts) != ("r", "g", "b"):
            raise GonioError(
                "an RGB measurement needs three runs seen in the r, g and b bands, in that "
                f"order; got {', '.join(m.band for m in parts)}"
            )
        for m in (green, blue):
            if len(m) != len(red) or not (
                np.allclose(m.wi, red.wi, atol=1e-9, rtol=0)
                and np.allclose(m.wo, red.wo, atol=1e-9, rtol=0)
            ):
                raise GonioError(f"{m.source}: its pairs differ from {red.source}'s")
        return replace(
            red,
            f=np.stack([m.f for m in parts], axis=-1),
            sigma=np.stack([m.sigma for m in parts], axis=-1),
            band="rgb",
            source=" + ".join(m.source for m in parts),
        )

    def scene_truth(self) -> BrdfEval:
        """f(ωi, ωo) of the simulated scene's material as this measurement's band sees
        it (RGB: the three channels). `GonioError` for a run on hardware."""
        if self.scene_text is None:
            raise GonioError(f"{self.source}: a run on hardware has no scene to compare with")
        return scene_truth(self.scene_text, self.scene_path, self.band)


def kept(calibrated: Calibrated) -> BoolArray:
    """The samples a measurement keeps, in the run's order: a finite value and σ."""
    return np.isfinite(calibrated.brdf) & np.isfinite(calibrated.sigma)


def _bytes(text: str | bytes) -> bytes:
    return text if isinstance(text, bytes) else text.encode()
