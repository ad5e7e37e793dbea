"""`gonio info RUN.sqlite`: what a run file holds — plan, backend, progress, instrument
time, faults, skips, pauses, motor recoveries, calibration drift (``--json`` for
scripts)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser], help_: str) -> None:
    p = sub.add_parser(
        "info",
        help=help_,
        description="Print what a run file holds: plan, backend, progress, instrument time, "
        "faults, skips, pauses, motor recoveries (a line each) and calibration drift. The "
        "file may still be being written.",
    )
    p.add_argument("run", type=Path, help="the run file (SQLite, from gonio acquire)")
    p.add_argument("--json", action="store_true", help="print the figures as JSON")
    p.set_defaults(func=cmd_info)


def cmd_info(args: argparse.Namespace) -> int:
    from gonio.acquire import recovery
    from gonio.analysis import summary
    from gonio.cli import run_table
    from gonio.store import open_run

    run = open_run(args.run)
    if args.json:
        figures = {
            **summary.figures(run),
            "recoveries": recovery.summaries(run),
            "alignment_path": run.meta.get("alignment_path"),
            "alignment_sha256": run.meta.get("alignment_sha256"),
        }
        print(json.dumps(figures, indent=2, ensure_ascii=False))
    else:
        print(run_table.render(run))
        print(run_table.alignment_line(run))
        print(run_table.render_details(run))
    return 0
