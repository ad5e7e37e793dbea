"""Representative parameter sets of every model, and the albedo survey of docs/explanations/brdf.md.

`EXAMPLES` covers sharp and broad lobes, every Fresnel option, RGB parameters and
the grazing-heavy cases; the tests run their properties over it. `albedo_table`
prints the directional-albedo measurements the documentation quotes
(``python -m studies.brdf.examples`` from the repository root).
"""

from __future__ import annotations

import numpy as np

from gonio.brdf import BRDF, blinn_normalization, create, directional_albedo

#: Gold-like complex index at roughly 650, 550 and 450 nm (illustrative values).
GOLD_IOR = (0.18, 0.42, 1.37)
GOLD_K = (3.42, 2.35, 1.77)

EXAMPLES: tuple[tuple[str, dict[str, object]], ...] = (
    ("lambert", {"albedo": 0.8}),
    ("lambert", {"albedo": (0.2, 0.5, 0.9)}),
    ("phong", {"n": 1.0}),
    ("phong", {"n": 10.0}),
    ("phong", {"n": 1000.0}),
    ("phong", {"n": 50.0, "ks": 0.6, "kd": (0.1, 0.2, 0.4)}),
    ("blinn_phong", {"n": 1.0}),
    ("blinn_phong", {"n": 10.0}),
    ("blinn_phong", {"n": 1000.0}),
    ("blinn_phong", {"n": 50.0, "ks": (0.5, 0.4, 0.3), "kd": 0.5}),
    ("cosine_quadratic", {"n": 100.0}),
    ("cosine_quadratic_modified", {"n": 100.0}),
    ("cosine_quadratic_modified", {"n": 100.0, "xi": "29/64"}),
    ("cosine_quadratic_modified", {"n": 16.0, "xi": 0.47}),
    ("schlick_lobe", {"n": 100.0}),
    ("cook_torrance", {"alpha": 0.05, "fresnel": "none"}),
    ("cook_torrance", {"alpha": 0.3}),
    ("cook_torrance", {"alpha": 1.0, "fresnel": "none"}),
    ("cook_torrance", {"alpha": 0.05, "distribution": "beckmann", "fresnel": "none"}),
    ("cook_torrance", {"alpha": 0.3, "distribution": "beckmann", "fresnel": "dielectric"}),
    ("cook_torrance", {"alpha": 1.0, "distribution": "beckmann", "fresnel": "none"}),
    ("cook_torrance", {"alpha": 0.2, "fresnel": "conductor", "ior": GOLD_IOR, "k": GOLD_K}),
    ("cook_torrance", {"alpha": 0.2, "fresnel": "schlick", "f0": 0.04, "kd": 0.5}),
    ("ggx_anisotropic", {"alpha_x": 0.05, "alpha_y": 0.3, "fresnel": "none"}),
    ("ggx_anisotropic", {"alpha_x": 0.3, "alpha_y": 0.3}),
    ("ggx_anisotropic", {"alpha_x": 0.1, "alpha_y": 0.5, "fresnel": "dielectric", "ior": 1.5}),
    ("fresnel_test_function", {}),
    ("specular_test_function", {}),
    ("grazing_test_function", {}),
    (
        "sum",
        {
            "components": [
                {"name": "lambert", "albedo": 0.5},
                {"name": "cook_torrance", "alpha": 0.2, "f0": 0.04},
            ]
        },
    ),
    (
        "sum",
        {
            "components": [
                {"name": "lambert", "albedo": (0.05, 0.1, 0.15)},
                {"name": "cook_torrance", "alpha": 0.05, "distribution": "beckmann"},
            ]
        },
    ),
)


def example_models() -> list[BRDF]:
    """Every entry of `EXAMPLES`, created."""
    return [create(name, **params) for name, params in EXAMPLES]


def label(model: BRDF) -> str:
    """A short, readable id: ``name(key=value, ...)``."""
    args = ", ".join(f"{k}={v}" for k, v in model.params.items())
    return f"{model.name}({args})"


#: Incidence angles of the albedo survey, degrees.
SURVEY_DEG = (0.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0, 85.0, 89.0)


def albedo_table() -> str:
    """Max (and argmax) over θi of the directional albedo of the examples, as markdown."""
    theta = np.radians(SURVEY_DEG)
    lines = [
        "| model | physically based | max a(θi) | at θi | a(0°) | a(60°) | a(89°) |",
        "|---|---|---|---|---|---|---|",
    ]
    for model in example_models():
        a = directional_albedo(model, theta)
        if model.is_rgb:
            a = a.max(axis=-1)  # the largest channel
        j = int(np.argmax(np.round(a, 9)))  # first of the maxima, ignoring rounding
        lines.append(
            f"| `{label(model)}` | {'yes' if model.physically_based else 'no'} "
            f"| {a[j]:.6f} | {SURVEY_DEG[j]:g}° | {a[0]:.6f} | {a[6]:.6f} | {a[-1]:.6f} |"
        )
    return "\n".join(lines)


#: Shininess values of the survey of Romanyuk et al.'s lobe family.
FAMILY_N = (0.5, 1.0, 2.0, 4.0, 16.0, 64.0, 256.0, 1000.0)
FAMILY = ("blinn_phong", "cosine_quadratic", "cosine_quadratic_modified", "schlick_lobe")


def family_table() -> str:
    """Albedo at normal incidence (the maximum over θi) of the C(n)-normalized lobes."""
    lines = [
        "| model | " + " | ".join(f"n = {n:g}" for n in FAMILY_N) + " |",
        "|---|" + "---|" * len(FAMILY_N),
    ]
    for name in FAMILY:
        a = [float(directional_albedo(create(name, n=n), [0.0])[0]) for n in FAMILY_N]
        lines.append(f"| {name} | " + " | ".join(f"{x:.4f}" for x in a) + " |")
    return "\n".join(lines)


def blinn_overshoot(n: float) -> float:
    """Albedo at normal incidence of cos^n θh normalized by (n + 8)/(8π) instead of C(n)."""
    return float((n + 8.0) / (8.0 * np.pi * blinn_normalization(n)))


if __name__ == "__main__":  # pragma: no cover - documentation generator
    print(albedo_table())
    print()
    print(family_table())
    print()
    print("| n | albedo at θi = 0 with (n+8)/(8π) |")
    print("|---|---|")
    for n in (0.5, 1, 2, 4, 8, 16, 64, 256, 1000):
        print(f"| {n:g} | {blinn_overshoot(n):.4f} |")
