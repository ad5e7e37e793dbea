"""The verdict of a stream check as a file, and what hardware fly support reads of it.

The file sits beside the rig file: ``RIG.stream-check.yaml`` for ``RIG.yaml``
(`verdict_path`). It names the instrument (its port, its answer to an identification
command when one was asked, and its detector configuration with that configuration's
SHA-256), the date, the stream checked (rate, integration, duration, starts), the
limits, and each requirement's figures and pass/fail. `fly_refusal` says why a fly plan
may not run on the rig's hardware, or None once a passing verdict for the same
configuration exists.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from gonio.rig import Rig, SerialInterfaceSpec
from gonio.workflows.stream_check.figures import REQUIREMENTS, Limits, Requirement

#: The verdict of ``RIG.yaml`` is ``RIG`` + this, in the same folder.
SUFFIX = ".stream-check.yaml"
#: The command that writes it (for the messages that ask for it).
COMMAND = "gonio detector check-stream"


def verdict_path(rig_path: Path) -> Path:
    """Where the verdict of the rig file ``rig_path`` is written and read."""
    return rig_path.with_name(rig_path.stem + SUFFIX)


def interface_config(interface: SerialInterfaceSpec) -> dict[str, Any]:
    """The detector's interface as plain data (what a verdict is for)."""
    return interface.model_dump(mode="json")


def config_sha256(config: dict[str, Any]) -> str:
    """The SHA-256 of a detector configuration (`interface_config`), keys sorted."""
    text = json.dumps(config, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


@dataclass(frozen=True)
class Verdict:
    """A stream check's outcome: the instrument, when and how it was checked, and each
    requirement's verdict (in the order of `REQUIREMENTS`)."""

    rig: str
    checked_utc: str
    port: str
    identity: str | None
    config: dict[str, Any]
    rate_hz: float
    integration_s: float
    duration_s: float
    starts: int
    limits: Limits
    requirements: list[Requirement]

    @property
    def passed(self) -> bool:
        return all(r.passed for r in self.requirements)

    @property
    def failed(self) -> list[Requirement]:
        return [r for r in self.requirements if not r.passed]

    def to_yaml(self) -> str:
        """The verdict file's text."""
        data = {
            "passed": self.passed,
            "checked_utc": self.checked_utc,
            "rig": self.rig,
            "instrument": {
                "port": self.port,
                "identity": self.identity,
                "config_sha256": config_sha256(self.config),
                "config": self.config,
            },
            "stream": {
                "rate_hz": self.rate_hz,
                "integration_s": self.integration_s,
                "duration_s": self.duration_s,
                "starts": self.starts,
            },
            "limits": asdict(self.limits),
            "requirements": {
                r.name: {
                    "passed": r.passed,
                    "requirement": REQUIREMENTS[r.name],
                    "summary": r.summary,
                    "figures": {k: _plain(v) for k, v in r.figures.items()},
                }
                for r in self.requirements
            },
        }
        head = f"# {COMMAND}: the stream check of a photometer (gonio reads it for fly plans)\n"
        return head + yaml.safe_dump(data, sort_keys=False, allow_unicode=True)


def _plain(value: object) -> object:
    """A figure as YAML writes it: numpy scalars as Python ones, NaN as None."""
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


@dataclass(frozen=True)
class StoredVerdict:
    """What fly support reads of a verdict file."""

    passed: bool
    config: dict[str, Any]
    rate_hz: float
    failed: list[tuple[str, str]]  # (requirement, summary) of each failed one


def read_verdict(path: Path) -> StoredVerdict:
    """The verdict in ``path``; `ValueError` (its reason) if it is not one."""
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as exc:
        raise ValueError(f"cannot read it ({type(exc).__name__})") from None
    try:
        passed, config = data["passed"], data["instrument"]["config"]
        rate, requirements = float(data["stream"]["rate_hz"]), data["requirements"]
        failed = [
            (str(name), str(r["summary"])) for name, r in requirements.items() if not r["passed"]
        ]
    except (TypeError, KeyError, ValueError, AttributeError):
        raise ValueError("not a stream check's verdict (a field is missing)") from None
    if not isinstance(passed, bool) or not isinstance(config, dict) or passed == bool(failed):
        raise ValueError("not a stream check's verdict (its passed does not add up)")
    return StoredVerdict(passed, config, rate, failed)


def fly_refusal(rig: Rig, rate_hz: float | None) -> str | None:
    """Why a fly plan streaming at ``rate_hz`` (Hz; None: not known) may not run on the
    hardware of ``rig``, in one line ending with how to re-check; None when the verdict
    beside the rig file passed for the rig's detector configuration at that rate or above."""
    interface = rig.spec.detector.interface
    where = rig.source or "rig"
    if not isinstance(interface, SerialInterfaceSpec) or interface.stream is None:
        return f"{where}: detector.interface: no serial detector with a stream section to check"
    if rig.source is None:
        return "a rig made in code has no stream check; give the rig file"
    path = verdict_path(rig.source)
    again = f"`{COMMAND} --rig {rig.source}`"
    if not path.exists():
        return f"{where}: its photometer has no stream check ({path} is missing): run {again}"
    try:
        verdict = read_verdict(path)
    except ValueError as exc:
        return f"{path}: {exc}: run {again} again"
    changed = _changed(verdict.config, interface_config(interface))
    if changed:
        shown = ", ".join(f"detector.interface.{name}" for name in changed[:3])
        more = f" and {len(changed) - 3} more" if len(changed) > 3 else ""
        return f"{path}: checked with another configuration ({shown}{more} changed): run {again}"
    if not verdict.passed:
        name, summary = verdict.failed[0]
        others = f" (and {len(verdict.failed) - 1} more)" if len(verdict.failed) > 1 else ""
        return f"{path}: the photometer failed {name}{others}: {summary}; fix it, then run {again}"
    if rate_hz is not None and rate_hz > verdict.rate_hz * (1 + 1e-9):
        return (
            f"{path}: checked at {verdict.rate_hz:g} Hz and the plan streams at {rate_hz:g} "
            f"Hz: run {again} --rate {rate_hz:g}"
        )
    return None


def _changed(old: Any, new: Any, prefix: str = "") -> list[str]:
    """The dotted names of the fields that differ between two configurations."""
    if isinstance(old, dict) and isinstance(new, dict):
        names = sorted(set(old) | set(new))
        return [c for n in names for c in _changed(old.get(n), new.get(n), f"{prefix}{n}.")]
    return [] if old == new else [prefix.rstrip(".") or "(all)"]
