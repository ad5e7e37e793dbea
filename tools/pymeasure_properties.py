"""Write drivers/pymeasure/properties.py: the public properties each preset instrument
class declares (`drivers.pymeasure.boundary.properties`, read from the class), so the
rig file's property names are checked at load without importing PyMeasure (the rig
loads no serial stack). Run after upgrading PyMeasure: ``python -m tools.pymeasure_properties``
(tests/drivers/test_pymeasure.py fails while the file is stale)."""

from __future__ import annotations

import textwrap
from pathlib import Path

from drivers.pymeasure import PRESETS
from drivers.pymeasure.boundary import load_class, properties

PATH = Path(__file__).resolve().parents[1] / "drivers" / "pymeasure" / "properties.py"
HEADER = '''"""The public properties each preset instrument class declares (PyMeasure's
``Instrument.control``, ``measurement`` and ``setting``, and plain properties), read from
the classes by tools/pymeasure_properties.py (generated: do not edit): the rig file's
property names are checked against them at load without importing PyMeasure."""

from collections.abc import Mapping


def _names(text: str) -> frozenset[str]:
    return frozenset(text.split())


PROPERTIES: Mapping[str, frozenset[str]] = {
'''


def text() -> str:
    """The module's text, from the installed PyMeasure."""
    lines = [HEADER]
    for dotted in sorted(PRESETS):
        names = " ".join(sorted(properties(load_class(dotted))))
        wrapped = textwrap.wrap(names, 80, break_on_hyphens=False, break_long_words=False)
        lines.append(f'    "{dotted}": _names(\n        """\n')
        lines += [f"        {line}\n" for line in wrapped]
        lines.append('        """\n    ),\n')
    lines.append("}\n")
    return "".join(lines)


def main() -> None:
    PATH.write_text(text())
    print(PATH.relative_to(PATH.parents[2]))


if __name__ == "__main__":
    main()
