"""The blur budget of a fly plan: the largest smear a reading may integrate over for the
bias of mid-time attribution to stay within a tolerance, from the lobe's GGX width.

A reading taken while moving averages the BRDF over the arc its directions travel
during the integration (the smear, ° = angular velocity × integration) and is attributed
to the pose at the window's middle. Over a GGX lobe of width α that bias grows as
(smear / α)²; studies/fly_blur.py measures it on the simulator's optics (a detector arc
in the plane of incidence, α from 0.02 to 0.5, windows anywhere on the lobe, peak and
flanks) and fits the largest smear for a bias within ``tolerance`` as

    smear_max = K · α · √tolerance,

K the smallest ratio over every α and tolerance measured (docs/results/fly_blur.md).

A plan names its material's lobe by its full width at half maximum in degrees (the angle
the reflected direction spans where the GGX distribution is above half its peak): for a
small α that width is 2 · 2 · α · √(√2 − 1) rad = `WIDTH_PER_ALPHA_DEG` · α, so a plan's
default budget is ``blur_budget_deg(width / WIDTH_PER_ALPHA_DEG, tolerance)`` — about
0.11 of the width at 0.5 % (`blur_budget_of_width`).
"""

from __future__ import annotations

import math

from gonio.errors import DomainError

#: K of smear_max = K · α · √tolerance (°), fitted by studies/fly_blur.py.
BLUR_K_DEG = 233.0
#: The full width at half maximum (°, of the reflected direction) of a GGX lobe per unit
#: α, for a small α: the half vector's half width α · √(√2 − 1), doubled on reflection,
#: on both sides.
WIDTH_PER_ALPHA_DEG = math.degrees(4.0 * math.sqrt(math.sqrt(2.0) - 1.0))
#: The relative bias a plan's default blur budget allows (0.5 %).
DEFAULT_TOLERANCE = 0.005


def blur_budget_deg(alpha: float, tolerance: float = DEFAULT_TOLERANCE) -> float:
    """The largest smear (°) a reading may integrate over on a GGX lobe of width ``alpha``
    for the bias of mid-time attribution to stay within ``tolerance``.

    Parameters
    ----------
    alpha : float
        The lobe's GGX (Trowbridge–Reitz) width, > 0 (a material's expected roughness).
    tolerance : float
        The relative bias allowed, in (0, 0.05] (0.005: 0.5 %).

    Returns
    -------
    float
        The smear budget in degrees: K · α · √tolerance.
    """
    if not (isinstance(alpha, int | float) and 0 < alpha < math.inf):
        raise DomainError(f"alpha must be a positive number (a GGX width), got {alpha!r}")
    if not (isinstance(tolerance, int | float) and 0 < tolerance <= 0.05):
        raise DomainError(f"tolerance must be in (0, 0.05] (a relative bias), got {tolerance!r}")
    return BLUR_K_DEG * float(alpha) * math.sqrt(float(tolerance))


def blur_budget_of_width(width_deg: float, tolerance: float = DEFAULT_TOLERANCE) -> float:
    """The blur budget (°) of a lobe named by its full width at half maximum.

    Parameters
    ----------
    width_deg : float
        The lobe's full width at half maximum (°, of the reflected direction), > 0.
    tolerance : float
        The relative bias allowed, in (0, 0.05].

    Returns
    -------
    float
        `blur_budget_deg` of α = width / `WIDTH_PER_ALPHA_DEG` (about 0.11 × width at
        0.5 %).
    """
    if not (isinstance(width_deg, int | float) and 0 < width_deg < math.inf):
        raise DomainError(f"width_deg must be a positive number (degrees), got {width_deg!r}")
    return blur_budget_deg(float(width_deg) / WIDTH_PER_ALPHA_DEG, tolerance)
