"""A fly plan's section (``sampling.fly``): what sweeps, at what rate, within what
blur budget (`FlySpec`), and the bounds of its fields."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import Field, model_validator

from gonio import brdf
from gonio.config import Strict, field_error
from gonio.planner.blur import DEFAULT_TOLERANCE, blur_budget_of_width
from gonio.planner.material import flat_material, material_model

#: The smallest blur budget (°) a fly plan may ask for: a reading's pose is known only to
#: the quantization of its encoders, one tick / √12 (a 4096-tick encoder: 0.025°, 0.013°
#: through a 2:1 gear; `gonio.rig.sensitivity`), so a smear far below that buys no
#: accuracy, while the sweep's velocity (blur / integration) and the readings a line
#: streams (its travel / smear) grow without bound as the budget shrinks. The rig's own
#: floor (`gonio.planner.fly.limits.blur_floor_deg`) is checked before planning.
MIN_BLUR_DEG = 0.01
#: The smallest relative bias a blur budget may be fitted to: a bias of 1e-6 is the shot
#: noise of a single reading of 10¹² photoelectrons (1 / √N), beyond the full well of any
#: photometer (a 16-bit reading resolves 1.5e-5 of its range): no measurement could see
#: a smaller one, and the budget (∝ √tolerance) would shrink toward zero for nothing.
MIN_TOLERANCE = 1e-6
#: The slowest stream a fly plan may ask for (readings a second): below one a second, a
#: sweep at the axes' speeds (tens of °/s) passes tens of degrees between two readings,
#: and the lines needed for the target grow as the readings per line shrink.
MIN_RATE_HZ = 1.0


class FlySpec(Strict):
    """The fly strategy (docs/reference/planner.md, "Fly plans"): readings taken while one
    axis sweeps at constant velocity, ``rate_hz`` readings a second, each integrating
    ``integration_s``. The sweep's velocity keeps the angular smear of a reading (the
    path its directions cover while it integrates) within ``blur_deg``, or within the
    blur budget of ``lobe_width_deg`` (the material's expected lobe width: the smear
    whose bias stays within ``blur_tolerance``, `gonio.planner.blur`; or
    ``lobe_fraction`` of the width when given), and within the axis's max velocity.
    Sweeps run through anchor points drawn (Sobol) in the parametrization until about
    ``sampling.target`` readings are laid out."""

    segment: Literal["detector_arc", "light_arc", "theta_h_line"] = Field(
        "detector_arc",
        description="What sweeps: detector_arc (the detector's last axis, the light and the "
        "sample still), light_arc (the light's last axis, the detector and sample still), or "
        "theta_h_line (lines along θh at fixed θd, φd of Rusinkiewicz's coordinates, every "
        "axis following a streamed trajectory; isotropic plans).",
    )
    rate_hz: float = Field(
        100.0,
        ge=MIN_RATE_HZ,
        le=10_000,
        description="Readings per second the detector streams; at least 1: slower, a sweep "
        "at the axes' speeds passes tens of degrees between two readings (stop-and-go "
        "measures as few, without the blur).",
    )
    integration_s: float | None = Field(
        None,
        gt=0,
        description="Integration time of each reading (s), at most 1 / rate_hz (none: "
        "1 / rate_hz, no dead time).",
    )
    blur_deg: float | None = Field(
        None,
        ge=MIN_BLUR_DEG,
        le=30,
        description="The most angular smear of one reading (degrees; none: the blur budget "
        "of lobe_width_deg if given, else 0.5); at least 0.01°, below which the encoders' "
        "quantization (one tick / √12) hides the smear, and at least the rig's own "
        "quantization of the axes that sweep.",
    )
    lobe_width_deg: float | None = Field(
        None,
        ge=MIN_BLUR_DEG,
        le=180,
        description="The material's expected lobe width (degrees, full width); the blur "
        "budget is then the smear whose bias stays within blur_tolerance on such a lobe, "
        "or lobe_fraction of it (not with blur_deg); the budget it gives is held to "
        "blur_deg's bounds.",
    )
    lobe_fraction: float | None = Field(
        None,
        gt=0,
        le=1,
        description="The share of lobe_width_deg one reading may smear (none: the blur "
        "budget of the lobe, gonio.planner.blur: about 0.11 of the width at a 0.5 % bias).",
    )
    material: dict[str, Any] | None = Field(
        None,
        description="theta_h_line only: the expected material (name, a gonio.brdf model, and "
        "its parameters beside it), whose variation across the lines sets their density over "
        "(θd, φd) (none: lines denser toward grazing θd, 1 / cos θd).",
        json_schema_extra=flat_material,
    )  # checked by gonio.brdf.material
    fill: int = Field(
        0,
        ge=0,
        le=100_000,
        description="theta_h_line only: stop-and-go targets measured after the lines where "
        "they leave the largest gaps (a mixed plan; the plan's exposure applies to them).",
    )
    blur_tolerance: float = Field(
        DEFAULT_TOLERANCE,
        ge=MIN_TOLERANCE,
        le=0.05,
        description="The relative bias motion blur may leave on the lobe when the budget "
        "comes from lobe_width_deg without lobe_fraction (0.005: 0.5 %); at least 1e-6, the "
        "shot noise of one reading of 10¹² photoelectrons, more than any detector holds: "
        "no measurement sees a smaller bias.",
    )

    @model_validator(mode="after")
    def _consistent(self) -> FlySpec:
        if self.integration_s is not None and self.integration_s > 1.0 / self.rate_hz * (1 + 1e-12):
            raise field_error(
                "integration_s",
                f"expected at most 1 / rate_hz = {1.0 / self.rate_hz:g} s, got "
                f"{self.integration_s:g}",
            )
        if self.blur_deg is not None and self.lobe_width_deg is not None:
            raise field_error("blur_deg", "give blur_deg or lobe_width_deg, not both")
        if self.material is not None:
            if self.segment != "theta_h_line":
                raise field_error("material", "only theta_h_line lines take a material")
            self.model()
        if self.fill and self.segment != "theta_h_line":
            raise field_error("fill", "only theta_h_line lines are filled with stop-and-go targets")
        if self.lobe_width_deg is not None and self.blur < MIN_BLUR_DEG:
            field = "blur_tolerance" if self.lobe_fraction is None else "lobe_fraction"
            got = getattr(self, field)
            raise field_error(
                field,
                f"expected a blur budget of at least {MIN_BLUR_DEG:g}° on the lobe of "
                f"lobe_width_deg {self.lobe_width_deg:g}°, got {self.blur:.3g}° "
                f"(got {field} {got:g}); a wider lobe or a larger {field}",
            )
        return self

    def model(self) -> brdf.BRDF | None:
        """The expected material as a `gonio.brdf` model (None when not given)."""
        return None if self.material is None else material_model(self.material)

    @property
    def period_s(self) -> float:
        """Time between the starts of two readings (s)."""
        return 1.0 / self.rate_hz

    @property
    def integration(self) -> float:
        """The integration time of a reading (s)."""
        return self.period_s if self.integration_s is None else self.integration_s

    @property
    def blur(self) -> float:
        """The blur budget (degrees)."""
        if self.blur_deg is not None:
            return self.blur_deg
        if self.lobe_width_deg is not None:
            if self.lobe_fraction is None:
                return blur_budget_of_width(self.lobe_width_deg, self.blur_tolerance)
            return self.lobe_fraction * self.lobe_width_deg
        return 0.5
