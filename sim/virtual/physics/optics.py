"""The simulated measurement's forward chain: geometry and time → radiant power at the
detector → expected photo-electrons, with the scene's optical effects.

The instrument's facts come from the rig (the light's kind and distance, the beam, sample
and field-of-view sizes, the detector's aperture, the reference standard's albedo and
diameter);
what the simulation adds from the scene (the material, the source's power, the
sensor's responsivity and band, the effects).

The ideal chain is `gonio.radiometry`'s: Φ = K(source, ωi) · f(ωi, ωo) · c(ωo) · Ω.
Effects, each computed only when the scene lists it:

- ``aperture_integration``: K · ∫cap f(ωi, ω) c(ω) dω over the detector's solid angle
  instead of K · f · c · Ω (a sharp peak is lowered and widened);
- ``footprint``: for a collimated beam, × the part of the lit ellipse that is on the
  sample and in the detector's view; for a point source, the power integrated over the
  seen part of the sample with the irradiance and the incidence varying across the
  spot (with ``aperture_integration`` too, the aperture average nested inside the spot
  integral: exact, and slow — about 40 ms a pair at the default orders);
- ``source_drift``: the source's power × (1 + rate·t/3600 + amplitude·sin(2πt/P + φ))
  at the middle of each exposure (never below 0);
- ``stray_light``: + a constant power while the source is on (drifting with it);
- ``misalignment``: the optics see the pairs of the true geometry at the rig file's
  joint angles (`gonio.rig.Rig.geometry`, `at_poses`); a point source's irradiance
  scales with its true distance (r / r')² (first order: the spatial integral keeps r);
  the spots' shifts on the surface are not applied (the footprint stays centred).

The sensor (`sim.virtual.physics.sensor`) turns the expected electrons into counts.
"""

from __future__ import annotations

import math

import numpy as np

from drivers.base import StageTarget
from gonio import brdf, radiometry
from gonio.radiometry import band_eval
from gonio.rig import Rig
from gonio.scene import Scene
from gonio.types import BrdfEval, FloatArray


def source_of(scene: Scene, rig: Rig) -> radiometry.Source:
    """The rig's light with the scene's power (`ConfigError` if they do not match)."""
    scene.check_rig(rig)
    light, beam = rig.spec.light, rig.spec.constraints.beam_diameter_mm
    if light.kind == "point":
        assert light.distance_mm is not None  # required by the rig file
        return radiometry.PointSource(scene.source.power, light.distance_mm)
    assert beam is not None  # required by the rig file
    return radiometry.CollimatedSource(scene.source.power, beam)


class SceneOptics:
    """The chain of ``scene`` on ``rig``, vectorized over pairs (N, 3) and exposures
    (N, A)."""

    def __init__(self, scene: Scene, rig: Rig) -> None:
        self.scene = scene
        self.source = source_of(scene, rig)
        c, band = rig.spec.constraints, scene.detector.band
        self.optics = radiometry.DetectorOptics(rig.spec.detector.aperture_sr, c.detector_fov_mm)
        self.diameters_mm: dict[StageTarget, float] = {
            "sample": c.sample_diameter_mm,
            "reference": rig.reference_diameter_mm,
        }
        albedo = rig.spec.reference.albedo
        self.models: dict[StageTarget, BrdfEval] = {
            "sample": band_eval(scene.material.model(), band),
            "reference": band_eval(brdf.create("lambert", albedo=albedo), band),
        }
        self.effects = scene.effects
        self.rig = rig
        misalignment = scene.effects.misalignment
        #: The rig's true misalignment (None: as its file says).
        self.alignment = None if misalignment is None else misalignment.alignment(rig.axes)
        self._distance_mm = rig.spec.light.distance_mm

    def pairs(self, poses: FloatArray) -> tuple[FloatArray, FloatArray]:
        """(ωi, ωo) the optics see at true joint angles ``poses`` (..., A) as the rig file
        reads them (through the scene's ``misalignment``)."""
        return self.rig.forward(poses, self.alignment)

    def at_poses(
        self, poses: FloatArray, target: StageTarget = "sample"
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """(ωi, ωo, power) at true joint angles ``poses`` (N, A) as the rig file reads
        them: the pairs the optics see (through the scene's ``misalignment``) and the
        radiant power there (W, (N,), `geometric_power`); a point source's irradiance
        × (r / r')² when the sample's height moves it to r' (`gonio.rig.Geometry`)."""
        if self.alignment is None:
            wi, wo = self.rig.forward(poses)
            return wi, wo, self.geometric_power(wi, wo, target)
        g = self.rig.geometry(np.asarray(poses, dtype=np.float64), self.alignment)
        power = self.geometric_power(g.wi, g.wo, target)
        if g.light_distance_mm is not None and self._distance_mm is not None:
            power = power * (self._distance_mm / g.light_distance_mm) ** 2
        return g.wi, g.wo, power

    def geometric_power(
        self, wi: FloatArray, wo: FloatArray, target: StageTarget = "sample"
    ) -> FloatArray:
        """Radiant power (W, shape (N,)) from the source at its nominal strength, before
        drift and stray light (`gonio.radiometry.detector_power` with the scene's
        optical effects)."""
        e = self.effects
        aperture = e.aperture_integration
        return np.asarray(
            radiometry.detector_power(
                self.source,
                self.optics,
                self.models[target],
                wi,
                wo,
                footprint=e.footprint is not None,
                aperture_integration=aperture is not None,
                sample_diameter_mm=self.diameters_mm[target],
                aperture_order=aperture.order if aperture is not None else 6,
            ),
            dtype=np.float64,
        )

    def drift(self, t: FloatArray) -> FloatArray:
        """The source's relative power at virtual times t (s): 1 without drift."""
        spec = self.effects.source_drift
        if spec is None:
            return np.ones_like(np.asarray(t, dtype=np.float64))
        phase = math.radians(spec.phase_deg)
        factor = (
            1.0
            + spec.rate_per_hour * t / 3600.0
            + spec.amplitude * np.sin(2.0 * math.pi * t / spec.period_s + phase)
        )
        return np.asarray(np.maximum(factor, 0.0), dtype=np.float64)  # a lamp dims to dark

    def power(
        self,
        geometric: FloatArray,
        t_mid: FloatArray,
        *,
        light_on: bool = True,
    ) -> FloatArray:
        """Power (W, (N, A)) during each exposure, whose middles are at ``t_mid`` (N, A)."""
        t_mid = np.asarray(t_mid, dtype=np.float64)
        if not light_on:
            return np.zeros_like(t_mid)
        power = np.asarray(geometric, dtype=np.float64)[:, None]
        stray = self.effects.stray_light
        if stray is not None:  # light from the source: it drifts with the source
            power = power + stray.power_w
        return np.asarray(power * self.drift(t_mid), dtype=np.float64)

    def electrons(self, power: FloatArray, exposure_s: FloatArray) -> FloatArray:
        """Expected signal electrons (N, A) of exposures of ``exposure_s`` (N,) s (checked
        positive by the caller; the responsivity by the scene): Φ t R / q."""
        rate = self.scene.detector.responsivity_a_w / radiometry.ELEMENTARY_CHARGE
        return np.asarray(power * (np.asarray(exposure_s)[:, None] * rate), dtype=np.float64)
