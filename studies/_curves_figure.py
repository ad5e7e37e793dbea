"""The figure of a noise-free curves page (docs/results/study-curves*.md): log-RMSE against
the sample count, one panel per scene, one line per plan (colour: parametrization; line:
method; marker: uniform or adaptive sampling), the error targets dotted.

`study.py curves` (and `report`) draws it from curves.csv's rows before its tables. Where
those rows are not at hand, the page's own tables hold them (to the four decimals
printed): ``python studies/_curves_figure.py docs/results/study-curves.md`` draws the
figure from them and puts its link where `study.py` prints it, the rest of the page as
it was.
"""

from __future__ import annotations

import io
import os
import re
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from gonio.output import reserve_output
from gonio.plots import require_matplotlib

ROOT = Path(__file__).resolve().parents[1]
IMG = ROOT / "docs" / "img"
#: One colour per parametrization, one line style per method, one marker per sampling.
COLOURS = {"spherical": "0.45", "rusinkiewicz": "C0", "orthographic": "C2", "hybrid": "C3"}
STYLES = {"linear": "-", "rbf": "--"}
MARKERS = {"sobol": "o", "adaptive": "^"}
#: The page's heading of a scene's table.
HEADING = re.compile(r"^### (\S+) \(noise-free, log-RMSE\)$")


def alt_text(rows: list[dict[str, str]]) -> str:
    """The image's alternative text."""
    kinds = sorted({r["sampling"] for r in rows})
    return "log-RMSE against samples, " + " and ".join(
        "adaptive" if k == "adaptive" else "uniform" for k in kinds
    )


def draw(rows: list[dict[str, str]], path: Path, targets: tuple[float, ...]) -> None:
    """Write the figure of ``rows`` (curves.csv's columns scene, sampling, parametrization,
    method, samples, log_rmse) to ``path`` (PNG)."""
    plt = require_matplotlib()
    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    cols = min(len(scenes), 2)
    lines = -(-len(scenes) // cols)
    fig, axes = plt.subplots(
        lines, cols, figsize=(5.2 * cols, 3.6 * lines), squeeze=False, sharex=True
    )
    for ax, scene in zip(axes.flat, scenes, strict=False):
        mine = [r for r in rows if r["scene"] == scene]
        plans = dict.fromkeys((r["sampling"], r["parametrization"], r["method"]) for r in mine)
        for kind, name, method in plans:
            pts = sorted(
                (int(r["samples"]), float(r["log_rmse"]))
                for r in mine
                if (r["sampling"], r["parametrization"], r["method"]) == (kind, name, method)
            )
            n = np.array([p[0] for p in pts], dtype=np.float64)
            e = np.array([p[1] for p in pts], dtype=np.float64)
            e[e <= 0.0] = np.nan  # below the table's last decimal: no point on a log axis
            label = f"{name}, {method}" + (", adaptive" if kind == "adaptive" else "")
            ax.plot(
                n,
                e,
                STYLES.get(method, ":"),
                marker=MARKERS.get(kind, "s"),
                ms=3,
                color=COLOURS.get(name, "k"),
                lw=1.1,
                label=label,
            )
        drawn = [float(r["log_rmse"]) for r in mine if float(r["log_rmse"]) > 0.0]
        for target in targets:  # the targets the curves reach or come near
            if min(drawn) / 2.0 <= target <= max(drawn) * 2.0:
                ax.axhline(target, color="0.6", lw=0.6, ls=":")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_title(f"{scene} (noise-free)", fontsize=9)
        ax.set_ylabel("log-RMSE")
        ax.grid(True, which="major", lw=0.3)
        ax.tick_params(labelsize=7)
    for ax in axes[-1]:
        ax.set_xlabel("samples")
    for ax in list(axes.flat)[len(scenes) :]:
        ax.axis("off")
    handles, labels = axes.flat[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=4, fontsize=7, frameon=False)
    fig.tight_layout(rect=(0.0, 0.015 + 0.022 * -(-len(labels) // 4), 1.0, 1.0))
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=80)
    plt.close(fig)
    with reserve_output(path, "image") as out:
        out.write_bytes(buffer.getvalue())


def rows_of_page(text: str) -> list[dict[str, str]]:
    """The rows (scene, sampling, parametrization, method, samples, log_rmse) of a curves
    page's tables."""
    rows: list[dict[str, str]] = []
    scene = ""
    counts: list[str] = []
    for line in text.splitlines():
        if match := HEADING.match(line):
            scene, counts = match.group(1), []
            continue
        if not scene or not line.startswith("|") or line.startswith("|---"):
            continue
        cells = [c.strip() for c in line.strip("|").split("|")]
        if cells[0] == "sampling":
            counts = [c.replace(",", "") for c in cells[3:] if not c.startswith("n for")]
            continue
        for n, value in zip(counts, cells[3 : 3 + len(counts)], strict=True):
            if value != "—":
                rows.append(
                    {
                        "scene": scene,
                        "sampling": cells[0],
                        "parametrization": cells[1],
                        "method": cells[2],
                        "samples": n,
                        "log_rmse": value,
                    }
                )
    return rows


def targets_of_page(text: str) -> tuple[float, ...]:
    """The error targets of a page's "n for …" columns."""
    return tuple(dict.fromkeys(float(t) for t in re.findall(r"\| n for ([0-9.]+)", text)))


def add_to_page(page: Path) -> Path:
    """Draw the figure of ``page`` from its tables beside the other figures and link it
    before the first table, where `study.py` prints it; the figure's path."""
    text = page.read_text(encoding="utf-8")
    rows = rows_of_page(text)
    if not rows:
        raise SystemExit(f"{page}: no table of noise-free curves")
    path = IMG / f"{page.stem}.png"
    draw(rows, path, targets_of_page(text))
    link = f"![{alt_text(rows)}]({os.path.relpath(path, page.parent)})"
    kept = [line for line in text.splitlines() if not line.startswith(f"![{alt_text(rows)}](")]
    first = next(i for i, line in enumerate(kept) if HEADING.match(line))
    while first > 0 and not kept[first - 1].strip() and not kept[first - 2].strip():
        del kept[first - 1]  # one blank line before the link
        first -= 1
    kept[first:first] = [link, ""]
    page.write_text("\n".join(kept) + "\n", encoding="utf-8")
    return path


if __name__ == "__main__":
    for arg in sys.argv[1:]:
        print(f"wrote {add_to_page(Path(arg)).relative_to(ROOT)}")
