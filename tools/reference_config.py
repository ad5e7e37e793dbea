"""The configuration reference: the shipped JSON Schemas (gonio/schemas/KIND.schema.json)
and the pages docs/reference/config/KIND.md, both generated from the models that load
the files (`gonio.cli.schema`), and the list of what only the loader checks.

    python -m tools.reference_config           # write every generated file
    python -m tools.reference_config --check   # exit 1 naming the files that differ

Run from the repository's root. tests/gonio/cli/test_schema.py checks that the committed
files are what this writes, and that the schema refuses what the loader refuses except
`LOADER_ONLY` (each entry shown refused by the loader and accepted by the schema).
"""

from __future__ import annotations

import argparse
import copy
import json
import re
import sys
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from gonio.cli.schema import KINDS, schema, schema_text
from gonio.config import MAX_INTEGER

ROOT = Path(__file__).resolve().parents[1]
#: The folder of each kind's shipped files (configs/FOLDER/*.yaml).
FOLDERS = {"plan": "plans", "rig": "rigs", "scene": "scenes", "sweep": "sweeps"}
#: Where the pages go.
PAGES = Path("docs/reference/config")
#: Removes a field in a `LoaderCheck`'s patch.
DELETE = "<delete>"


def editor_line(kind: str) -> str:
    """The first line of a shipped file of ``kind`` (configs/FOLDER/NAME.yaml)."""
    return f"# yaml-language-server: $schema=../../gonio/schemas/{kind}.schema.json"


@dataclass(frozen=True)
class LoaderCheck:
    """A check of a ``kind`` of file that its JSON Schema does not make: the loader's
    message names ``field`` (a pattern: ``*`` one key or index, ``**`` any keys, ``|``
    alternatives) and matches the regex ``message``. ``what`` is the reference page's
    sentence. ``example``: (a shipped file, its patches (dotted path, value or
    `DELETE`)) that the loader refuses so and the schema accepts; ``files``: refused
    only by the whole loader (it reads other files, or builds the rig model), not by the
    file's model alone."""

    kind: str
    field: str
    message: str
    what: str
    example: tuple[str, tuple[tuple[str, Any], ...]]
    files: bool = False

    def matches(self, field: str, message: str) -> bool:
        """Whether a refusal (its dotted field path, its message) is this check's."""
        return bool(re.fullmatch(_glob(self.field), field) and re.search(self.message, message))


def _glob(pattern: str) -> str:
    parts = [
        re.escape(p).replace(r"\*\*", ".*").replace(r"\*", "[^.]+") for p in pattern.split("|")
    ]
    return "|".join(f"(?:{p})" for p in parts)


_QUICKSTART, _ARCH, _SERIAL, _MATTE, _SWEEP = (
    "plans/quickstart.yaml",
    "rigs/arch.yaml",
    "rigs/arch_serial.yaml",
    "scenes/matte.yaml",
    "sweeps/quick.yaml",
)
_LAMBERT = {"name": "lambert", "albedo": 0.5}

#: What only the loader checks: relations between fields, values a schema cannot
#: compare, and the files a file names.
LOADER_ONLY: tuple[LoaderCheck, ...] = (
    # -- the plan ----------------------------------------------------------------------
    LoaderCheck(
        "plan", "sampling", "exactly one of counts",
        "`sampling`: exactly one of `counts` and `target`.",
        (_QUICKSTART, (("sampling.counts", {"theta_h": 2, "theta_d": 2, "phi_d": 2}),)),
    ),
    LoaderCheck(
        "plan", "sampling.counts", "counts apply to grid and stratified",
        "`sampling.counts`: only with the grid and stratified strategies.",
        (_QUICKSTART, (("sampling.target", DELETE),
                       ("sampling.counts", {"theta_h": 2, "theta_d": 2, "phi_d": 2}))),
    ),
    LoaderCheck(
        "plan", "sampling.counts", "expected a count for",
        "`sampling.counts`: a count for every coordinate.",
        (_QUICKSTART, (("sampling.strategy", "grid"), ("sampling.target", DELETE),
                       ("sampling.counts", {"theta_h": 2}))),
    ),
    LoaderCheck(
        "plan", "sampling.counts.*|sampling.warps.*", "not a coordinate",
        "`sampling.counts`, `sampling.warps`: their keys are coordinates of the "
        "parametrization (its isotropic ones when `isotropic`).",
        (_QUICKSTART, (("sampling.warps", {"hbar": {"power": 2}}),)),
    ),
    LoaderCheck(
        "plan", "sampling.adaptive", "options of the adaptive strategy",
        "`sampling.adaptive`: only with `strategy: adaptive`.",
        (_QUICKSTART, (("sampling.adaptive", {}),)),
    ),
    LoaderCheck(
        "plan", "sampling.warps", "places its own density",
        "`sampling.warps`: not with the adaptive strategy.",
        (_QUICKSTART, (("sampling.strategy", "adaptive"),
                       ("sampling.warps", {"theta_h": {"power": 2}}))),
    ),
    LoaderCheck(
        "plan", "sampling.target", "more targets than the survey",
        "`sampling.target`: with the adaptive strategy, more than `adaptive.survey`.",
        (_QUICKSTART, (("sampling.strategy", "adaptive"), ("sampling.target", 100))),
    ),
    LoaderCheck(
        "plan", "sampling.adaptive.model", "model",
        "`sampling.adaptive.model`: a model family as `gonio fit --model` reads it.",
        (_QUICKSTART, (("sampling.strategy", "adaptive"),
                       ("sampling.adaptive", {"model": "lambert+nosuch"}))),
    ),
    LoaderCheck(
        "plan", "sampling.fly", "options of the fly strategy",
        "`sampling.fly`: only with `strategy: fly`.",
        (_QUICKSTART, (("sampling.fly", {}),)),
    ),
    LoaderCheck(
        "plan", "sampling.warps", "lays out uniform sweeps",
        "`sampling.warps`: not with the fly strategy.",
        (_QUICKSTART, (("sampling.strategy", "fly"),
                       ("sampling.warps", {"theta_h": {"power": 2}}))),
    ),
    LoaderCheck(
        "plan", "sampling.fly.integration_s", "expected at most 1 / rate_hz",
        "`sampling.fly.integration_s`: at most 1 / `rate_hz`.",
        (_QUICKSTART, (("sampling.strategy", "fly"),
                       ("sampling.fly", {"rate_hz": 100, "integration_s": 0.5}))),
    ),
    LoaderCheck(
        "plan", "sampling.fly.blur_deg", "not both",
        "`sampling.fly.blur_deg`: not with `lobe_width_deg`.",
        (_QUICKSTART, (("sampling.strategy", "fly"),
                       ("sampling.fly", {"blur_deg": 1, "lobe_width_deg": 4}))),
    ),
    LoaderCheck(
        "plan", "exposure.adapt", "reads at a fixed rate",
        "`exposure.adapt`: not with the fly strategy.",
        (_QUICKSTART, (("sampling.strategy", "fly"),
                       ("exposure.adapt", {"material": _LAMBERT, "min_s": 0.01, "max_s": 1}))),
    ),
    LoaderCheck(
        "plan", "exposure.adapt.min_s", "at most max_s",
        "`exposure.adapt.min_s`: at most `max_s`.",
        (_QUICKSTART, (("exposure.adapt", {"material": _LAMBERT, "min_s": 2, "max_s": 1}),)),
    ),
    LoaderCheck(
        "plan", "exposure.adapt.material**", ".",
        "`exposure.adapt.material`: its parameters' values (ranges, names such as "
        "`fresnel: schlick`, energy conservation), checked by `gonio.brdf`.",
        (_QUICKSTART, (("exposure.adapt", {"material": {"name": "lambert", "albedo": 2},
                                           "min_s": 0.01, "max_s": 1}),)),
    ),
    LoaderCheck(
        "plan", "rig", "cannot read",
        "`rig`: the rig file, relative to the plan file, is read and checked as a rig file "
        "(unless `--rig` names another).",
        (_QUICKSTART, (("rig", "../rigs/nosuch.yaml"),)), files=True,
    ),
    # -- the rig ----------------------------------------------------------------------
    LoaderCheck(
        "rig", "axes.*.max_deg", "more than min_deg",
        "`axes.<axis>.max_deg`: above `min_deg`.",
        (_ARCH, (("axes.light_elevation.max_deg", -10),)),
    ),
    LoaderCheck(
        "rig", "axes", "rig has the axes",
        "`axes`: exactly the axes of the rig's `type`.",
        (_ARCH, (("type", "in_plane"),)),
    ),
    LoaderCheck(
        "rig", "axes.*.motor_id", "already used",
        "`axes.<axis>.motor_id`: each motor ID once.",
        (_ARCH, (("axes.detector_azimuth.motor_id", 1),)),
    ),
    LoaderCheck(
        "rig", "light.axes.*|detector.axes.*|sample.axes.*", "is not one of the axes",
        "`light.axes`, `detector.axes`, `sample.axes`: names of `axes`.",
        (_ARCH, (("light.axes", ["nosuch"]),)),
    ),
    LoaderCheck(
        "rig", "constraints.collisions.*.ranges_deg.*", "names unknown axis",
        "`constraints.collisions[].ranges_deg`: its keys are names of `axes`.",
        (_ARCH, (("constraints.collisions.0.ranges_deg", {"nosuch": [0, 1]}),)),
    ),
    LoaderCheck(
        "rig", "constraints.collisions.*.ranges_deg.*", r"expected \[low, high\]",
        "`constraints.collisions[].ranges_deg.<axis>`: low below high.",
        (_ARCH, (("constraints.collisions.0.ranges_deg.light_elevation", [85, 55]),)),
    ),
    LoaderCheck(
        "rig", "constraints.beam_diameter_mm", "collimated|point source",
        "`constraints.beam_diameter_mm`: required with `light.kind: collimated`, not given "
        "with `point`.",
        (_ARCH, (("constraints.beam_diameter_mm", DELETE),)),
    ),
    LoaderCheck(
        "rig", "light.distance_mm", "point|collimated",
        "`light.distance_mm`: required with `light.kind: point`, not given with `collimated`.",
        (_ARCH, (("light.distance_mm", 300),)),
    ),
    LoaderCheck(
        "rig", "detector.exposure_range_s", "min ≤ max",
        "`detector.exposure_range_s`: the shortest at most the longest.",
        (_ARCH, (("detector.exposure_range_s", [60, 1]),)),
    ),
    LoaderCheck(
        "rig", "health.min_voltage_v", "less than max_voltage_v",
        "`health.min_voltage_v`: below `max_voltage_v`.",
        (_ARCH, (("health", {"min_voltage_v": 15}),)),
    ),
    LoaderCheck(
        "rig", "light.switch.*_command", "one line of ASCII",
        "`light.switch`: each command one line of ASCII text.",
        (_SERIAL, (("light.switch.on_command", "LAMP\nON"),)),
    ),
    LoaderCheck(
        "rig", "light.switch.*", "not a valid regular expression",
        "`light.switch.ack`, `on_reply`, `off_reply`: valid (Python) regular expressions.",
        (_SERIAL, (("light.switch.ack", "("),)),
    ),
    LoaderCheck(
        "rig", "light.switch.*", "answer to query_command|command that on_reply answers",
        "`light.switch`: `query_command` with both `on_reply` and `off_reply`, and these "
        "only with it.",
        (_SERIAL, (("light.switch.off_reply", DELETE),)),
    ),
    LoaderCheck(
        "rig", "detector.interface**", ".",
        "`detector.interface` (serial): the templates' fields and the regular expressions' "
        "groups, by the driver's rules ([serial detector](../serial_detector.md)).",
        (_SERIAL, (("detector.interface.response", "VAL"),)),
    ),
    LoaderCheck(
        "rig", "", "rig needs",
        "Each chain (`light`, `detector`, `sample`) has the axes of the rig's `type`, about "
        "the rotation axes that type expects.",
        (_ARCH, (("light.axes", ["detector_elevation"]),)), files=True,
    ),
    LoaderCheck(
        "rig", "", r"points along \(0, 0, 1\)",
        "`light.pointing`, `detector.pointing`: [0, 0, 1] for both types.",
        (_ARCH, (("light.pointing", [1, 0, 0]),)), files=True,
    ),
    LoaderCheck(
        "rig", "", "ticks|motor",
        "Each axis's range within its motor's (0…4095 ticks in position mode, through "
        "`gear_ratio`, `direction` and `zero_offset_deg`).",
        (_ARCH, (("axes.light_elevation.zero_offset_deg", 0),)), files=True,
    ),
    LoaderCheck(
        "rig", "", "no direction pair measurable",
        "`constraints`: some direction pairs measurable (4 096 pairs over the hemisphere "
        "are probed).",
        (_ARCH, (("constraints.min_separation_deg", 179),)), files=True,
    ),
    # -- the scene --------------------------------------------------------------------
    LoaderCheck(
        "scene", "source", "expected one power",
        "`source`: exactly one of `irradiance_w_m2` and `intensity_w_sr`.",
        (_MATTE, (("source", {}),)),
    ),
    LoaderCheck(
        "scene", "material**", ".",
        "`material`: its parameters' values (ranges, names such as `fresnel: schlick`, "
        "parameters that go together such as `ior` and `k`, energy conservation), checked "
        "by `gonio.brdf`; a tabulated material's `path` is read.",
        (_MATTE, (("material.alpha", -1),)),
    ),
    LoaderCheck(
        "scene", "detector.full_well_e|detector.sensitivity_v", "Field required for kind",
        "`detector`: `full_well_e` for `kind: adc`, `sensitivity_v` for `kind: lockin`.",
        (_MATTE, (("detector.full_well_e", DELETE),)),
    ),
    LoaderCheck(
        "scene", "detector.full_well_e|detector.time_constant_s|detector.sensitivity_v",
        "only for kind",
        "`detector`: `time_constant_s` and `sensitivity_v` only for `kind: lockin`, "
        "`full_well_e` only for `kind: adc`.",
        (_MATTE, (("detector.time_constant_s", 0.01),)),
    ),
    LoaderCheck(
        "scene", "faults.*.at", "exactly one of at",
        "`faults[]`: exactly one of `at` and `rate`.",
        (_MATTE, (("faults", [{"kind": "comm_error"}]),)),
    ),
    LoaderCheck(
        "scene", "faults.*.axis", "names an axis",
        "`faults[].axis`: only for a `motor_fault` or an `overheat`.",
        (_MATTE, (("faults", [{"kind": "comm_error", "at": 1, "axis": "light_elevation"}]),)),
    ),
    LoaderCheck(
        "scene", "", r"light of .* is",
        "With its rig (`gonio simulate`, `gonio acquire`, `gonio tradeoff`): the source's "
        "power of the rig's `light.kind`.",
        (_MATTE, (("source", {"intensity_w_sr": 0.01}),)), files=True,
    ),
    LoaderCheck(
        "scene", "", "is not an axis of rig",
        "With its rig: `faults[].axis` one of the rig's axes.",
        (_MATTE, (("faults", [{"kind": "motor_fault", "at": 1, "axis": "elbow"}]),)),
        files=True,
    ),
    # -- the sweep --------------------------------------------------------------------
    LoaderCheck(
        "sweep", "warps.*.*", "not a coordinate",
        "`warps.<parametrization>`: its keys are coordinates of that parametrization (its "
        "isotropic ones when `isotropic`).",
        (_SWEEP, (("warps.rusinkiewicz", {"hbar": {"power": 2}}),)),
    ),
    LoaderCheck(
        "sweep", "axes.effects.*", "given twice",
        "`axes.effects`: `none` and `[]` are the same value, given once.",
        (_SWEEP, (("axes.effects", ["none", []]),)),
    ),
    LoaderCheck(
        "sweep", "adaptive.model", "model",
        "`adaptive.model`: a model family as `gonio fit --model` reads it.",
        (_SWEEP, (("adaptive", {"model": "lambert+nosuch"}),)),
    ),
    LoaderCheck(
        "sweep", "", "cannot read",
        "`rig`, `scenes`: the files, relative to the sweep file, are read and checked (each "
        "scene with the rig: its source of the rig's light, its name unlike the others').",
        (_SWEEP, (("scenes", ["../scenes/nosuch.yaml"]),)), files=True,
    ),
    LoaderCheck(
        "sweep", "", "outside the detector's exposure range",
        "`axes.exposure_s`: within the rig's `detector.exposure_range_s`.",
        (_SWEEP, (("axes.exposure_s", [100]),)), files=True,
    ),
    LoaderCheck(
        "sweep", "", "the detector takes at most",
        "`axes.averages`: at most the rig's `detector.max_averages`.",
        (_SWEEP, (("axes.averages", [100]),)), files=True,
    ),
    LoaderCheck(
        "sweep", "", "does not list the effect",
        "`axes.effects`: an effect with required parameters (`stray_light`) only where "
        "every scene gives them.",
        (_SWEEP, (("axes.effects", [["stray_light"]]),)), files=True,
    ),
    LoaderCheck(
        "sweep", "", "needs a warp",
        "`warps`: one for every parametrization swept with `warped` sampling that has no "
        "default (`spherical`), unless `exclude` leaves it out.",
        (_SWEEP, (("exclude", DELETE),)), files=True,
    ),
    LoaderCheck(
        "sweep", "", "every combination is excluded",
        "`exclude`: some combinations left to run.",
        (_SWEEP, (("exclude", [{"method": "naive"}]),)), files=True,
    ),
    LoaderCheck(
        "sweep", "", "combinations; expected at most",
        "At most 100 000 combinations in one sweep.",
        (_SWEEP, (("axes.samples", list(range(1, 3001))),)), files=True,
    ),
)  # fmt: skip

#: Where the schema is stricter than the loader: values the loader converts.
STRICTER = (
    'A number written as text (`"0.5"`) and a yes/no written as a number or a word other '
    "than true/false (`1`, `yes`, `on`: YAML 1.1, which the loader reads) are taken by the "
    "loader and refused by the schema; write plain numbers and `true`/`false`."
)


def patched(data: Any, patches: Sequence[tuple[str, Any]]) -> Any:
    """``data`` with each (dotted path, value) set, or removed for `DELETE` (a copy)."""
    out = copy.deepcopy(data)
    for path, value in patches:
        *parents, last = [int(p) if p.isdigit() else p for p in path.split(".")]
        node = out
        for key in parents:
            node = node[key]
        if value == DELETE:
            del node[last]
        else:
            node[last] = copy.deepcopy(value)
    return out


# -- the pages -------------------------------------------------------------------------

#: Each kind's page: title, what the files are, and where the rest is explained.
INTROS = {
    "plan": (
        "The plan file",
        "A plan file (`configs/plans/*.yaml`) says what to measure: the parametrization and "
        "how targets are placed in it, the exposure of each, how they are ordered for the "
        "motors and how `gonio acquire` runs them, on the rig its `rig` field names "
        "([rigs and the planner](../planner.md)).",
    ),
    "rig": (
        "The rig file",
        "A rig file (`configs/rigs/*.yaml`) describes the instrument, real or simulated: its "
        "axes and chains, what it cannot measure, the light, the detector, the reference "
        "standard, the motors' bus and their health limits ([rigs and the "
        "planner](../planner.md), [serial detector](../serial_detector.md)). Angles are "
        "degrees, lengths millimetres.",
    ),
    "scene": (
        "The scene file",
        "A scene file (`configs/scenes/*.yaml`) holds only what a simulation adds to the rig "
        "it runs on: the material, the source's power, the simulated sensor, the effects to "
        "model, injected faults and the seed ([the simulated "
        "instrument](../../explanations/simulator.md)); a fact of the instrument given here "
        "is refused with where it belongs in the rig file.",
    ),
    "sweep": (
        "The sweep file",
        "A sweep file (`configs/sweeps/*.yaml`) is a trade-off study for `gonio tradeoff`: "
        "every combination of its axes' values, for every scene, is planned, acquired on "
        "the simulated rig, reconstructed and scored ([the speed/accuracy "
        "trade](../../explanations/tradeoff.md)).",
    ),
}
#: Names of a mapping's keys in a field's path, by the path of the mapping.
PLACEHOLDERS = {
    "axes": "<axis>",
    "sampling.counts": "<coordinate>",
    "sampling.warps": "<coordinate>",
    "constraints.collisions[].ranges_deg": "<axis>",
    "warps": "<parametrization>",
    "warps.<parametrization>": "<coordinate>",
}
#: Units by the end of a field's name (the longest that fits wins).
UNITS = {
    "_deg": "°", "_deg_s": "°/s", "_deg_s2": "°/s²", "_mm": "mm", "_s": "s", "seconds": "s",
    "_sr": "sr", "_w_m2": "W/m²", "_w_sr": "W/sr", "_w": "W", "_a_w": "A/W", "_e_s": "e⁻/s",
    "_e": "e⁻", "_c": "°C", "_v": "V", "_minutes": "min", "_per_hour": "1/h", "_bits": "bit",
    "_bytes": "byte",
}  # fmt: skip


@dataclass(frozen=True)
class Row:
    path: str
    type: str
    unit: str
    default: str
    allowed: str
    description: str


class _Page:
    """The rows of one schema's fields, and the material models it mentions."""

    def __init__(self, root: dict[str, Any]) -> None:
        self.defs: dict[str, Any] = root.get("$defs", {})
        self.rows: list[Row] = []
        self.materials: dict[str, Any] | None = None
        self._object(root, "")

    def resolve(self, node: Any) -> dict[str, Any]:
        """A schema with its ``$ref`` replaced by the definition (the field's own keys win)."""
        if not isinstance(node, dict):
            return {}
        if "$ref" in node:
            target = self.defs[node["$ref"].rsplit("/", 1)[1]]
            return {**self.resolve(target), **{k: v for k, v in node.items() if k != "$ref"}}
        return node

    def variants(self, node: dict[str, Any]) -> list[dict[str, Any]]:
        """The alternatives of a union (itself when it is none), resolved, nulls included."""
        out = []
        for key in ("anyOf", "oneOf"):
            for part in node.get(key, []):
                out += self.variants(self.resolve(part))
        return out or [node]

    def _object(self, node: dict[str, Any], prefix: str, qualifier: str = "") -> None:
        required = set(node.get("required", ()))
        for name, field in node.get("properties", {}).items():
            path = f"{prefix}.{name}" if prefix else name
            self._field(self.resolve(field), path, name, name in required, qualifier)

    def _field(
        self, node: dict[str, Any], path: str, name: str, required: bool, qualifier: str
    ) -> None:
        shown = f"`{path}`" + (f" ({qualifier})" if qualifier else "")
        nullable = any(v.get("type") == "null" for v in self.variants(node))
        cells = (
            shown,
            self.type_of(node),
            _unit(name),
            "required" if required else _default(node, nullable),
            self.allowed(node),
            node.get("description", ""),
        )
        self.rows.append(Row(*(_cell(c) for c in cells)))
        if "allOf" in node or "if" in node:  # a material: its models in their own table
            self.materials = node
            return
        kinds = [v for v in self.variants(node) if "properties" in v or "items" in v]
        tagged = len([v for v in kinds if "kind" in v.get("properties", {})]) > 1
        for variant in kinds:
            kind = variant.get("properties", {}).get("kind", {}).get("const")
            inner = f"kind: {kind}" if tagged and kind else qualifier
            if variant.get("type") == "object":
                self._object(variant, path, inner)
            items = self.resolve(variant.get("items"))
            if "properties" in items:
                self._object(items, f"{path}[]", inner)
        for variant in self.variants(node):
            values = self.resolve(variant.get("additionalProperties"))
            if values:
                key = PLACEHOLDERS.get(path.replace("`", ""), "<key>")
                for inner_variant in self.variants(values):
                    if "properties" in inner_variant:
                        self._object(inner_variant, f"{path}.{key}", qualifier)
                    elif "additionalProperties" in inner_variant:
                        self._field(inner_variant, f"{path}.{key}", key, False, qualifier)

    def type_of(self, node: dict[str, Any]) -> str:
        names: list[str] = []
        for variant in self.variants(node):
            name = self._type_name(variant)
            if name not in names:
                names.append(name)
        return " or ".join(names)

    def _type_name(self, node: dict[str, Any]) -> str:
        kind = node.get("type")
        if "allOf" in node or "if" in node:
            return "mapping"
        if kind == "array":
            if "prefixItems" in node:
                items = [self.type_of(self.resolve(p)) for p in node["prefixItems"]]
                return "[" + ", ".join(items) + "]"
            return f"list of {_grouped(self.type_of(self.resolve(node.get('items', {}))))}"
        if kind == "object":
            values = node.get("additionalProperties")
            if isinstance(values, dict) and values:
                return f"mapping of {_grouped(self.type_of(self.resolve(values)))}"
            return "mapping"
        return {
            "number": "number",
            "integer": "integer",
            "string": "string",
            "boolean": "boolean",
            "null": "null",
        }.get(str(kind), "any")

    def _each(self, items: dict[str, Any]) -> list[str]:
        """What a list's items may be, in words."""
        out = []
        for variant in [items, *self.variants(items)]:
            out += [f"each {b}" for b in _bounds(variant)]
            if variant.get("type") == "array":
                inner = self.resolve(variant.get("items"))
                words = list(
                    dict.fromkeys(b for v in [inner, *self.variants(inner)] for b in _bounds(v))
                )
                if words:
                    out.append(f"or a list of {'; '.join(words)}")
        return list(dict.fromkeys(out))

    def allowed(self, node: dict[str, Any]) -> str:
        if "allOf" in node or "if" in node:
            return "a model of [the table below](#material-models)"
        parts: list[str] = []
        for variant in [node, *self.variants(node)]:
            said = _bounds(variant)
            if variant.get("type") == "array":
                if "prefixItems" in variant:
                    items = [_bounds(self.resolve(p)) for p in variant["prefixItems"]]
                    said += [f"item {i + 1}: {', '.join(b)}" for i, b in enumerate(items) if b]
                else:
                    said += self._each(self.resolve(variant.get("items")))
            values = variant.get("additionalProperties")
            if variant.get("type") == "object" and isinstance(values, dict):
                said += [f"each {b}" for b in _bounds(self.resolve(values))]
            for text in said:
                if text not in parts:
                    parts.append(text)
        return "; ".join(parts)


def _grouped(text: str) -> str:
    return f"({text})" if " or " in text else text


def _bounds(node: dict[str, Any]) -> list[str]:
    """What a schema allows, in words (not its type, not the 64-bit limit of integers)."""
    out = []
    if "const" in node:
        out.append(_value(node["const"]))
    if "enum" in node:
        out.append(", ".join(_value(v) for v in node["enum"]))
    for key, sign in (("minimum", "≥"), ("exclusiveMinimum", ">")):
        if key in node and node[key] != -MAX_INTEGER:
            out.append(f"{sign} {_number(node[key])}")
    for key, sign in (("maximum", "≤"), ("exclusiveMaximum", "<")):
        if key in node and node[key] != MAX_INTEGER:
            out.append(f"{sign} {_number(node[key])}")
    if node.get("minLength") == 1:
        out.append("not empty")
    if node.get("pattern") == r"\S":
        out.append("not blank")
    if node.get("type") == "array" and "prefixItems" not in node and node.get("minItems"):
        out.append(f"at least {node['minItems']} item{'s' if node['minItems'] > 1 else ''}")
    if node.get("uniqueItems"):
        out.append("each value once")
    if node.get("minProperties") == 1:
        out.append("not empty")
    if "propertyNames" in node:
        out.append("keys: " + ", ".join(_value(v) for v in node["propertyNames"]["enum"]))
    if "not" in node and "const" in node["not"]:
        out.append(f"not {json.dumps(node['not']['const'])}")
    return out


def _value(value: Any) -> str:
    text = json.dumps(value, ensure_ascii=False) if not isinstance(value, str) else value
    text = json.dumps(value)[1:-1] if isinstance(value, str) and not value.isprintable() else text
    return f"`{text}`" if text else '`""`'


def _number(value: float) -> str:
    return str(int(value)) if float(value).is_integer() and abs(value) < 1e6 else f"{value:g}"


def _default(node: dict[str, Any], nullable: bool) -> str:
    if "default" not in node or (node["default"] is None and not nullable):
        return ""
    value = node["default"]
    if value == [] or value == {}:
        return "`[]`" if value == [] else "`{}`"
    if isinstance(value, dict):
        return _value(value["kind"]) if set(value) == {"kind"} else "its fields' defaults"
    return _value(value)


def _unit(name: str) -> str:
    fits = [suffix for suffix in UNITS if name.endswith(suffix)]
    return UNITS[max(fits, key=len)] if fits else ""


def _cell(text: str) -> str:
    return text.replace("|", "\\|")


def _materials(node: dict[str, Any]) -> list[str]:
    """The material models' table (the flat form's branches)."""
    flat = node.get("else", node)
    lines = ["| `name` | parameters (required ones in bold) |", "| --- | --- |"]
    for branch in flat["allOf"]:
        model = branch["if"]["properties"]["name"]["const"]
        then = branch["then"]
        required = then.get("required", [])
        params = [p for p in then["properties"] if p != "name"]
        shown = [f"**`{p}`**" if p in required else f"`{p}`" for p in params]
        lines.append(f"| `{model}` | {', '.join(shown) or 'none'} |")
    return lines


def page(kind: str) -> str:
    """The reference page of ``kind``'s files (Markdown)."""
    title, intro = INTROS[kind]
    built = _Page(schema(kind))
    folder = FOLDERS[kind]
    lines = [
        "<!-- Generated by `python -m tools.reference_config` from the models; do not edit. -->",
        f"# {title}",
        "",
        f"{intro} Its JSON Schema ships as `gonio/schemas/{kind}.schema.json` "
        f"(`gonio schema {kind}` prints it). An editor with the YAML language server (VS "
        "Code's YAML extension, PyCharm) completes and checks a file whose first line names "
        "the schema, relative to the file, as every shipped file's does: "
        f"`{editor_line(kind)}` in `configs/{folder}/`.",
        "",
        "## Fields",
        "",
        "Every field, by its dotted path (`<key>`: a key of your choosing, `[]`: each item "
        "of a list); blank: no unit, no default, no bound.",
        "",
        "| field | type | unit | default | allowed | description |",
        "| --- | --- | --- | --- | --- | --- |",
        *(
            f"| {r.path} | {r.type} | {r.unit} | {r.default} | {r.allowed} | {r.description} |"
            for r in built.rows
        ),
    ]
    if built.materials is not None:
        lines += [
            "",
            "### Material models",
            "",
            "A material is `name` and that model's parameters beside it, e.g. "
            "`{name: cook_torrance, alpha: 0.2, kd: 0.3}` ([the models and their "
            "parameters](../../explanations/brdf.md)).",
            "",
            *_materials(built.materials),
        ]
    checks = [c for c in LOADER_ONLY if c.kind == kind]
    lines += [
        "",
        "## Checked when the file is read",
        "",
        "The schema says what one field may hold; the loader also checks these, which a "
        "schema cannot say or which need the files a file names. A mistake is one line "
        "`FILE:LINE: field: …`.",
        "",
        *(f"- {c.what}" for c in checks),
        "",
        f"The schema is stricter than the loader in one way. {STRICTER}",
    ]
    return "\n".join(lines) + "\n"


def outputs() -> dict[Path, str]:
    """Every generated file (relative to the repository's root) and its text."""
    out = {}
    for kind in KINDS:
        out[Path("gonio/schemas") / f"{kind}.schema.json"] = schema_text(kind)
        out[PAGES / f"{kind}.md"] = page(kind)
    return out


def stale(root: Path = ROOT) -> Iterator[Path]:
    """The generated files whose committed text differs from what is generated now, and
    files in their folders that nothing generates any more (a kind renamed or removed)."""
    expected = outputs()
    for path, text in expected.items():
        target = root / path
        if not target.is_file() or target.read_text(encoding="utf-8") != text:
            yield path
    for pattern in ("gonio/schemas/*.schema.json", f"{PAGES.as_posix()}/*.md"):
        for found in sorted(root.glob(pattern)):
            if found.relative_to(root) not in expected:
                yield found.relative_to(root)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m tools.reference_config", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument("--check", action="store_true", help="only say which files differ")
    args = parser.parse_args(argv)
    if args.check:
        differ = list(stale())
        for path in differ:
            print(f"{path}: stale; regenerate with python -m tools.reference_config")
        return 1 if differ else 0
    for path, text in outputs().items():
        target = ROOT / path
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(text, encoding="utf-8")
        print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
