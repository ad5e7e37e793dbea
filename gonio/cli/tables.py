"""`gonio tables`: the four parametrizations on named direction pairs (coordinates and
round-trip error) and the lobe comparison of Romanyuk et al.'s modified
cosine-quadratic model. The demo of the instrument is `make demo` (`gonio acquire` of
the quickstart plan on the simulated rig, then `gonio info` and `gonio evaluate`)."""

from __future__ import annotations

import argparse

import numpy as np

from gonio import params
from gonio.params import NAMED_PAIRS, roundtrip_error

#: Coordinates printed in degrees (the rest are unitless norms).
_ANGLE = {"theta_i", "phi_i", "theta_o", "phi_o", "theta_h", "phi_h", "theta_d", "phi_d", "phi_k"}


def parametrization_table() -> str:
    lines = [
        "Parametrizations on named direction pairs "
        "(angles in degrees, norms unitless; err = ‖ω' − ω‖ after forward and inverse)"
    ]
    for name in params.names():
        p = params.get(name)
        header = "".join(f"{c + ('°' if c in _ANGLE else ''):>12}" for c in p.names)
        lines += ["", f"{name:<20}{header}{'err':>10}"]
        for label, (wi, wo) in NAMED_PAIRS.items():
            c = p.forward(wi, wo)
            a, b = p.inverse(c)
            err = float(roundtrip_error(wi, wo, a, b))
            shown = [np.degrees(v) if n in _ANGLE else v for n, v in zip(p.names, c, strict=True)]
            cells = "".join(f"{v:12.6f}" for v in shown)
            lines.append(f"  {label:<18}{cells}{err:10.1e}")
    return "\n".join(lines)


def render() -> str:
    from gonio.brdf import lobe_errors

    return "\n\n".join([parametrization_table(), lobe_errors.render_summary()])


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser], help_: str) -> None:
    tables = sub.add_parser(
        "tables",
        help=help_,
        description="The four parametrizations' coordinates and round-trip errors for named "
        "direction pairs, and the lobe comparison of Romanyuk et al. (The instrument's "
        "demo is make demo: gonio acquire on the simulated rig, then gonio info and gonio "
        "evaluate.)",
    )
    tables.set_defaults(func=_cmd_tables)


def _cmd_tables(args: argparse.Namespace) -> int:
    print(render())
    return 0
