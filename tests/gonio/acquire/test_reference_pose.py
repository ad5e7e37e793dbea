"""`gonio.acquire.reference`'s reference geometry: the rig file's, where the reading of
the standard is what the calibration assumes, else the rig refused at the field."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gonio import radiometry
from gonio.acquire.reference import geometry_label, reference_geometry, reference_pose
from gonio.config import ConfigError
from gonio.rig.model import Rig
from tests.conftest import ARCH_POINT_FILE
from tests.support.rigs import rig_with


def test_the_shipped_rigs_keep_their_geometry(arch_point: Rig, rigs: dict[str, Rig]) -> None:
    for rig in (*rigs.values(), arch_point):
        wi, wo = reference_geometry(rig)
        expected = rig.reference_directions()
        np.testing.assert_array_equal(wi, expected[0])
        np.testing.assert_array_equal(wo, expected[1])
        assert geometry_label(rig) == "0°/45°"
        np.testing.assert_allclose(rig.forward(reference_pose(rig)), (wi, wo), atol=1e-12)
    assert (arch_point.reference_diameter_mm, rigs["arch"].reference_diameter_mm) == (50.8, 50.8)
    assert rigs["in_plane"].reference_diameter_mm == 30  # the sample's: no diameter_mm


def test_a_point_source_view_past_the_standard_is_refused_at_its_line(tmp_path: Path) -> None:
    """The point-source rig with a 30 mm standard (the sample's size) at 0°/45°: the
    25 mm view spans 35.4 mm, so the reference would read ~10 % low; refused, naming the
    file, the line and the field, with the limits that would do."""
    text = ARCH_POINT_FILE.read_text().replace("  diameter_mm: 50.8", "  diameter_mm: 30")
    path = tmp_path / "rig.yaml"
    path.write_text(text)
    rig = Rig.from_yaml(path)
    line = text.splitlines().index("  theta_o_deg: 45") + 1
    for call in (reference_geometry, reference_pose, geometry_label):
        with pytest.raises(ConfigError) as info:
            call(rig)
        assert str(info.value) == (
            f"{path}:{line}: reference.theta_o_deg: the detector's 25 mm field of view spans "
            "35.4 mm of the 30 mm reference standard at θo = 45°, past its edge (a point "
            "source's calibration assumes the view lies on the standard); expected "
            "θo ≤ 33.5°, or a standard at least 35.4 mm across (reference.diameter_mm)"
        )


def test_the_quoted_limits_are_valid(arch_point: Rig) -> None:
    """θo at the quoted 33.5° and a standard of the quoted 35.4 mm both pass; 33.6° and
    35.3 mm do not (arccos(25/30) = 33.56°, 25/cos 45° = 35.36 mm)."""
    small = {"diameter_mm": None}  # the sample's 30 mm
    reference_geometry(rig_with(arch_point, reference={**small, "theta_o_deg": 33.5}))
    reference_geometry(rig_with(arch_point, reference={"diameter_mm": 35.4}))
    for bad in ({**small, "theta_o_deg": 33.6}, {"diameter_mm": 35.3}):
        with pytest.raises(ConfigError, match=r"^rig 'arch-point-4axis': reference\.theta_o_deg"):
            reference_geometry(rig_with(arch_point, reference=bad))


def test_a_view_wider_than_the_standard_has_no_valid_angle(arch_point: Rig) -> None:
    rig = rig_with(arch_point, reference={"diameter_mm": 20})
    with pytest.raises(ConfigError, match=r"expected no θo, or a standard at least 35\.4 mm"):
        reference_geometry(rig)


def test_a_collimated_beam_needs_its_lit_spot_on_the_standard_and_in_view(
    rigs: dict[str, Rig],
) -> None:
    """For a beam the view may overhang the standard (it is dark there), but the lit
    spot must lie on the standard and in the view: exactly where the footprint fraction
    is 1. Each failure names its field and how low the reading would be."""
    arch = rigs["arch"]
    # The 30 mm standard at 0°/45° (the view spans 35.4 mm of it): the lit spot is 6 mm.
    reference_geometry(rig_with(arch, reference={"diameter_mm": None}))
    grazing = rig_with(arch, reference={"theta_i_deg": 85, "theta_o_deg": 5, "diameter_mm": 60})
    wi, wo = grazing.reference_directions()
    eta = float(radiometry.footprint_fraction(6, 25, 60, wi, wo))
    with pytest.raises(ConfigError) as info:
        reference_geometry(grazing)
    assert str(info.value) == (
        "rig 'arch-4axis': reference.theta_i_deg: the 6 mm beam lights 68.8 mm of the 60 mm "
        f"reference standard at θi = 85°, past its edge (the reference would read "
        f"{100 * (1 - eta):.1f} % low); expected θi ≤ 84.2°, or a standard at least 68.8 mm "
        "across (reference.diameter_mm)"
    )
    narrow = rig_with(
        arch, constraints={"detector_fov_mm": 8}, reference={"theta_i_deg": 60, "theta_o_deg": 0}
    )
    eta = float(radiometry.footprint_fraction(6, 8, 50.8, *narrow.reference_directions()))
    with pytest.raises(ConfigError) as info:
        reference_geometry(narrow)
    assert str(info.value) == (
        "rig 'arch-4axis': reference.theta_o_deg: the detector's 8 mm field of view (8.0 mm "
        "along the standard at θo = 0°) misses part of the 12.0 mm lit spot (the reference "
        f"would read {100 * (1 - eta):.1f} % low); expected a geometry whose view takes in "
        "the whole spot"
    )
