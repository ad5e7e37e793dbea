"""The SPEC grammar: names, presets, fixed and freed parameters, channels, errors."""

from __future__ import annotations

import numpy as np
import pytest

from gonio.brdf.composite import Sum
from gonio.brdf.family import BOUNDS, FAMILIES, parse
from gonio.errors import DomainError, UnknownNameError


def test_a_sum_of_terms_with_unique_labels():
    family = parse("lambert+ggx+ggx")
    assert [t.label for t in family.terms] == ["lambert", "ggx", "ggx_2"]
    assert [t.free for t in family.terms] == [("albedo",), ("alpha", "f0"), ("alpha", "f0")]
    slots = family.slots(rgb=False)
    names = [s.name(family.terms) for s in slots]
    assert names == ["lambert.albedo", "ggx.alpha", "ggx.f0", "ggx_2.alpha", "ggx_2.f0"]
    model = family.model(slots, [0.3, 0.1, 0.04, 0.5, 0.02])
    assert isinstance(model, Sum) and len(model.components) == 3


def test_the_fresnel_option_decides_its_free_parameters():
    assert parse("ggx:fresnel=conductor").terms[0].free == ("alpha", "ior", "k")
    assert parse("ggx:fresnel=dielectric").terms[0].free == ("alpha", "ior")
    assert parse("ggx:fresnel=none").terms[0].free == ("alpha",)
    fixed = parse("ggx_anisotropic:fresnel=conductor,ior=1.2,k=7").terms[0]
    assert fixed.free == ("alpha_x", "alpha_y")
    assert fixed.fixed["ior"] == 1.2 and fixed.fixed["k"] == 7.0


def test_fixing_freeing_and_choices():
    beckmann = parse("cook_torrance:distribution=beckmann,alpha=0.3").terms[0]
    assert beckmann.fixed["distribution"] == "beckmann" and beckmann.free == ("f0",)
    assert parse("phong:kd=free").terms[0].free == ("n", "ks", "kd")
    rgb = parse("ggx:f0=0.9/0.6/0.3").terms[0]
    assert rgb.fixed["f0"] == (0.9, 0.6, 0.3) and rgb.free == ("alpha",)


def test_colour_parameters_take_a_value_per_channel_geometry_is_shared():
    family = parse("lambert+ggx")
    slots = family.slots(rgb=True)
    assert [s.name(family.terms) for s in slots] == [
        "lambert.albedo[r]",
        "lambert.albedo[g]",
        "lambert.albedo[b]",
        "ggx.alpha",
        "ggx.f0[r]",
        "ggx.f0[g]",
        "ggx.f0[b]",
    ]
    model = family.model(slots, [0.1, 0.2, 0.3, 0.2, 0.5, 0.6, 0.7])
    assert model.is_rgb
    value = model.eval([0.0, 0.0, 1.0], [0.0, 0.6, 0.8])
    assert value.shape == (3,) and np.all(np.diff(value) > 0)


def test_every_family_builds_at_its_typical_start():
    for name in FAMILIES:
        family = parse(name)
        slots = family.slots(rgb=False)
        for s in slots:
            assert (s.low, s.high) == BOUNDS[s.param]
        assert family.model(slots, family.typical(slots)).eval([0, 0, 1.0], [0, 0, 1.0]) > 0


@pytest.mark.parametrize(
    ("spec", "error", "words"),
    [
        ("gx", UnknownNameError, "unknown family 'gx'"),
        ("lambert+", DomainError, "expected NAME"),
        ("", DomainError, "expected NAME"),
        ("ggx:alpha", DomainError, "expected KEY=VALUE"),
        ("ggx:alpha=1/2", DomainError, "expected a number or r/g/b"),
        ("ggx:foo=1", DomainError, "unknown parameter(s) foo"),
        ("ggx:distribution=free", DomainError, "distribution cannot be fitted"),
        ("ggx:fresnel=conductor,f0=0.5", DomainError, "does not take f0"),
    ],
)
def test_mistakes_are_one_line_naming_the_term(spec, error, words):
    with pytest.raises(error) as caught:
        parse(spec)
    assert words in str(caught.value) and "\n" not in str(caught.value)
