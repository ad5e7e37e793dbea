"""Model families to fit: the SPEC grammar of ``gonio fit --model`` (docs/explanations/fitting.md).

    SPEC  := TERM ("+" TERM)*                  e.g. lambert+ggx, lambert+ggx+ggx
    TERM  := NAME [":" KEY "=" VALUE ("," KEY "=" VALUE)*]
    VALUE := a number | r/g/b (three numbers) | a word (a choice) | free

Each NAME (`FAMILIES`) is a `gonio.brdf` model with some parameters preset; its free
parameters follow from the model and its choices (``fresnel=conductor`` frees ior and
k instead of f0). ``KEY=number`` fixes a parameter, ``KEY=word`` sets a choice,
``KEY=free`` frees a preset one (e.g. ``phong:kd=free``). A family of several terms is
their `gonio.brdf.composite.Sum`. Free parameters are bounded (`BOUNDS`); colour
parameters (`COLOURS`) take one value per channel in an RGB fit, the others are shared.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

from gonio.brdf.base import BRDF
from gonio.brdf.composite import Sum
from gonio.brdf.registry import create, model_class
from gonio.errors import DomainError, GonioError, UnknownNameError

#: name → (gonio.brdf model, preset parameters).
FAMILIES: dict[str, tuple[str, dict[str, Any]]] = {
    "lambert": ("lambert", {}),
    "ggx": ("cook_torrance", {"distribution": "ggx", "fresnel": "schlick", "kd": 0.0}),
    "beckmann": ("cook_torrance", {"distribution": "beckmann", "fresnel": "schlick", "kd": 0.0}),
    "cook_torrance": ("cook_torrance", {"distribution": "ggx", "fresnel": "schlick", "kd": 0.0}),
    "ggx_anisotropic": ("ggx_anisotropic", {"fresnel": "schlick", "kd": 0.0}),
    "phong": ("phong", {"kd": 0.0}),
    "blinn_phong": ("blinn_phong", {"kd": 0.0}),
    "cosine_quadratic": ("cosine_quadratic", {"kd": 0.0}),
    "cosine_quadratic_modified": ("cosine_quadratic_modified", {"kd": 0.0}),
    "schlick_lobe": ("schlick_lobe", {"kd": 0.0}),
}
#: The shape parameters each model fits (before its Fresnel option's).
SHAPE = {
    "lambert": ("albedo",),
    "cook_torrance": ("alpha",),
    "ggx_anisotropic": ("alpha_x", "alpha_y"),
}
LOBE_SHAPE = ("n", "ks")  # phong, blinn_phong and Romanyuk et al.'s lobes
#: The parameters a Fresnel option fits.
FRESNEL = {"none": (), "schlick": ("f0",), "dielectric": ("ior",), "conductor": ("ior", "k")}
#: Bounds of each parameter a fit may free (roughness kept where a few hundred samples
#: still resolve the lobe; shininess up to a 0.3° lobe).
BOUNDS: dict[str, tuple[float, float]] = {
    "albedo": (0.0, 1.0),
    "ks": (0.0, 1.0),
    "kd": (0.0, 1.0),
    "f0": (0.0, 1.0),
    "alpha": (2e-3, 2.0),
    "alpha_x": (2e-3, 2.0),
    "alpha_y": (2e-3, 2.0),
    "n": (0.0, 1e5),
    "ior": (0.05, 10.0),
    "k": (0.0, 20.0),
    "xi": (1e-3, 1.0),
}
#: Parameters with one value per channel in an RGB fit.
COLOURS = frozenset({"albedo", "ks", "kd", "f0", "ior", "k"})
#: A start inside the bounds for a free parameter (the moment estimate refines most).
TYPICAL = {"alpha": 0.2, "alpha_x": 0.2, "alpha_y": 0.2, "n": 20.0, "ior": 1.5, "k": 1.0}
TYPICAL_DEFAULT = 0.5
CHANNELS = "rgb"

_NUMBER = re.compile(r"^[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$")


@dataclass(frozen=True)
class Term:
    """One model of a family: ``label`` (unique in the family), the `gonio.brdf` model,
    its fixed parameters and choices, and its free parameters in order."""

    label: str
    model: str
    fixed: dict[str, Any]
    free: tuple[str, ...]


@dataclass(frozen=True)
class Slot:
    """One entry of the fitted vector: a term's parameter, for one channel or all."""

    term: int
    param: str
    channel: int | None  # 0, 1, 2 in an RGB fit of a colour parameter; else None
    low: float
    high: float

    def name(self, terms: tuple[Term, ...]) -> str:
        """``label.param`` or ``label.param[r]``."""
        base = f"{terms[self.term].label}.{self.param}"
        return base if self.channel is None else f"{base}[{CHANNELS[self.channel]}]"


@dataclass(frozen=True)
class Family:
    """A parsed SPEC: its terms; `slots` lays out the fitted vector, `model` builds it."""

    spec: str
    terms: tuple[Term, ...]

    def slots(self, rgb: bool) -> tuple[Slot, ...]:
        """The fitted vector's entries: colour parameters per channel when ``rgb``."""
        out: list[Slot] = []
        for j, term in enumerate(self.terms):
            for param in term.free:
                low, high = BOUNDS[param]
                channels: tuple[int | None, ...] = (
                    (0, 1, 2) if rgb and param in COLOURS else (None,)
                )
                out.extend(Slot(j, param, c, low, high) for c in channels)
        return tuple(out)

    def params(self, slots: tuple[Slot, ...], x: Any) -> list[dict[str, Any]]:
        """Each term's parameters (fixed and free) for the vector ``x``."""
        params: list[dict[str, Any]] = [dict(t.fixed) for t in self.terms]
        for slot, value in zip(slots, x, strict=True):
            target = params[slot.term]
            if slot.channel is None:
                target[slot.param] = float(value)
            else:
                rgb = list(target.get(slot.param) or (0.0, 0.0, 0.0))
                rgb[slot.channel] = float(value)
                target[slot.param] = tuple(rgb)
        return params

    def term_models(self, slots: tuple[Slot, ...], x: Any) -> list[BRDF]:
        """Each term's model for the vector ``x`` (`parse` checked the names, so the
        classes are called directly: `create` would inspect their signatures each time)."""
        params = self.params(slots, x)
        return [model_class(t.model)(**p) for t, p in zip(self.terms, params, strict=True)]

    def model(self, slots: tuple[Slot, ...], x: Any) -> BRDF:
        """The model for the vector ``x`` (a `Sum` when the family has several terms)."""
        built = self.term_models(slots, x)
        return built[0] if len(built) == 1 else Sum(built)

    def canonical(self, slots: tuple[Slot, ...], x: Any) -> list[int]:
        """A reordering of the slots that sorts repeated terms (same model and fixed
        parameters) by their first free parameter, ascending: ``ggx`` is the narrower
        lobe of ``lambert+ggx+ggx`` whichever start found it. ``x[order]`` is sorted."""
        order = list(range(len(self.terms)))
        for j, term in enumerate(self.terms):
            if not term.free:
                continue
            same = [
                k
                for k, t in enumerate(self.terms)
                if (t.model, t.fixed, t.free) == (term.model, term.fixed, term.free)
            ]
            key = {k: float(x[_first(slots, k)]) for k in same}
            ranked = sorted(same, key=lambda k: key[k])
            order[j] = ranked[same.index(j)]
        return [
            i for j in range(len(self.terms)) for i, s in enumerate(slots) if s.term == order[j]
        ]

    def typical(self, slots: tuple[Slot, ...]) -> list[float]:
        """A start inside the bounds (for checking a SPEC and seeding a fit)."""
        return [TYPICAL.get(s.param, TYPICAL_DEFAULT) for s in slots]


def _first(slots: tuple[Slot, ...], term: int) -> int:
    return next(i for i, s in enumerate(slots) if s.term == term)


def parse(spec: str) -> Family:
    """The family of ``spec``; `UnknownNameError` for an unknown name, `DomainError`
    (one line, naming the term) for a malformed term or a parameter the model lacks."""
    words = [w.strip() for w in spec.split("+")]
    if not spec.strip() or any(not w for w in words):
        raise DomainError(f"model {spec!r}: expected NAME or NAME+NAME… (e.g. lambert+ggx)")
    terms: list[Term] = []
    for word in words:
        name, _, rest = word.partition(":")
        label = _unique(name.strip(), [t.label for t in terms])
        terms.append(_term(word, name.strip(), label, rest))
    family = Family(spec, tuple(terms))
    slots = family.slots(rgb=False)
    try:
        for term, params in zip(terms, family.params(slots, family.typical(slots)), strict=True):
            create(term.model, **params)
    except GonioError as exc:
        raise DomainError(f"model {spec!r}: {exc}") from None
    return family


def _unique(name: str, taken: list[str]) -> str:
    if name not in taken:
        return name
    k = 2
    while f"{name}_{k}" in taken:
        k += 1
    return f"{name}_{k}"


def _term(word: str, name: str, label: str, rest: str) -> Term:
    if name not in FAMILIES:
        raise UnknownNameError(
            f"model {word!r}: unknown family {name!r}; expected one of {', '.join(FAMILIES)}"
        )
    model, preset = FAMILIES[name]
    fixed: dict[str, Any] = dict(preset)
    freed: set[str] = set()
    for item in filter(None, (s.strip() for s in rest.split(","))) if rest else ():
        key, eq, value = (s.strip() for s in item.partition("="))
        if not eq or not key or not value:
            raise DomainError(f"model {word!r}: expected KEY=VALUE, got {item!r}")
        if value == "free":
            if key not in BOUNDS:
                raise DomainError(
                    f"model {word!r}: {key} cannot be fitted; free parameters are "
                    f"{', '.join(BOUNDS)}"
                )
            fixed.pop(key, None)
            freed.add(key)
        else:
            fixed[key] = _value(word, key, value)
            freed.discard(key)
    shape = SHAPE.get(model, LOBE_SHAPE)
    optics = FRESNEL.get(str(fixed.get("fresnel")), ()) if "fresnel" in fixed else ()
    free = [p for p in (*shape, *optics) if p not in fixed]
    free += sorted(freed - set(free))
    return Term(label, model, fixed, tuple(free))


def _value(word: str, key: str, text: str) -> float | tuple[float, ...] | str:
    parts = text.split("/")
    if len(parts) == 3 and all(_NUMBER.match(p) for p in parts):
        return tuple(float(p) for p in parts)
    if _NUMBER.match(text):
        return float(text)
    if len(parts) > 1:
        raise DomainError(f"model {word!r}: {key}={text}: expected a number or r/g/b numbers")
    return text
