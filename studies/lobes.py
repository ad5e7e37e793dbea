"""Romanyuk et al.'s modified cosine-quadratic lobes: accuracy next to speed.

Accuracy against F_B = cos^n ψ, next to numpy evaluation speed. Run:
``.venv/bin/python studies/lobes.py`` (about 10 s). Prints the machine, the
recomputed equation 12, the epicentre relative errors over n, the candidate readings
of the "4.5-fold" claim, the absolute errors over the hemisphere, the zero-crossing
and inflexion checks, and ns per value for each lobe (10^6 values, best of repeats).
"""

from __future__ import annotations

import datetime
import math
import os
import platform
import sys
import timeit
from collections.abc import Callable
from pathlib import Path

import numpy as np
import scipy
from scipy import integrate, optimize

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # _report
sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # studies
import _report

from gonio.brdf import lobe_errors as st
from gonio.brdf import lobes
from studies.brdf import lobe_grid

N_TABLE = (16.0, 23.4, 32.0, 64.0, 128.0, 256.0, 512.0, 1000.0)
N_VALUES = 1_000_000
REPEATS = 15
NUMBER = 5


def pct(x: float) -> str:
    return f"{100.0 * x:7.3f}%"


def cpu_name() -> str:
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as fh:
            for line in fh:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def machine() -> None:
    print("== machine")
    print(f"date      {datetime.datetime.now(datetime.UTC):%Y-%m-%d %H:%M} UTC")
    print(f"platform  {platform.platform()}")
    print(f"cpu       {cpu_name()} ({os.cpu_count()} logical CPUs)")
    print(f"python    {platform.python_version()}", end="")
    print(f"  numpy {np.__version__}  scipy {scipy.__version__}")
    try:  # numpy ≥ 2.0: which SIMD kernel each float64 ufunc dispatches to
        from numpy.lib.introspect import opt_func_info

        info = opt_func_info(func_name="power|multiply|divide|maximum", signature="float64")
        kernels = ", ".join(f"{f} {next(iter(v.values()))['current']}" for f, v in info.items())
        print(f"simd      {kernels}")
    except ImportError:
        pass


def dblquad_eq12(k: float) -> list[float]:
    """Eq 11's four integrals straight from the ψ-integrands (independent of the closed form)."""

    def lim(n: float) -> float:
        return math.acos(math.exp(-k / n))

    fs: list[Callable[[float, float], float]] = [
        lambda p, n: math.cos(p) ** n * math.cos(p) * math.sin(p),
        lambda p, n: n * n * (math.cos(p) - 1.0) ** 2 * math.cos(p) * math.sin(p),
        lambda p, n: 2.0 * n * (math.cos(p) - 1.0) * math.cos(p) * math.sin(p),
        lambda p, n: math.cos(p) * math.sin(p),
    ]
    return [
        float(integrate.dblquad(f, *st.EQ11_N, 0.0, lim, epsabs=1e-14, epsrel=1e-12)[0]) for f in fs
    ]


def equation_12() -> None:
    print("\n== equation 12: left = ξ² A + ξ B + C, n ∈ [16, 256], ψ ≤ acos(exp(−K/n))")
    print(f"{'source':<24}{'left':>11}{'A (ξ²)':>11}{'B (ξ)':>11}{'C (1)':>11}{'root ξ':>10}")
    rows = [
        ("paper printed", st.SEED_EQ12),
        ("closed form K=0.511", st.equation_12()),
        ("closed form K=ln(5/3)", st.equation_12(st.K_LN_5_3)),
        ("dblquad K=0.511", st.Eq12(*dblquad_eq12(st.K_PRINTED))),
    ]
    for name, e in rows:
        print(
            f"{name:<24}{e.left:>11.6f}{e.quadratic:>11.6f}{e.linear:>11.6f}"
            f"{e.constant:>11.6f}{e.xi():>10.6f}"
        )
    ours = rows[1][1]
    print(f"quad error estimate ≤ {ours.abserr:.1e}; ln(5/3) = {st.K_LN_5_3:.6f}")
    seed_with_our_left = st.Eq12(
        ours.left, *[getattr(st.SEED_EQ12, a) for a in ("quadratic", "linear", "constant")]
    )
    print(
        f"the paper's A,B,C with unrounded left {ours.left:.6f}: ξ = {seed_with_our_left.xi():.6f}"
    )
    xi_mm, d_mm = st.minimax_xi()
    print(
        f"29/64 = {29 / 64:.6f} ({100 * (29 / 64 / ours.xi() - 1):+.2f}% off the root); "
        f"nearest /64: {round(64 * ours.xi())}/64, /128: {round(128 * ours.xi())}/128; "
        f"minimax-δ ξ on [16,1000]: {xi_mm:.5f} (max δ {100 * d_mm:.3f}%)"
    )


def pointwise_ratio(other: st.Lobe, vol: st.Lobe, n: np.ndarray | float) -> np.ndarray:
    """δ_other(n) / δ_vol(n), both maximized over the epicentre zone at each n."""
    return st.epicentre_max_relative_error(other, n)[0] / st.epicentre_max_relative_error(vol, n)[0]


def epicentre() -> None:
    ls = st.study_lobes()
    print("\n== max relative error δ = |F − F_B|/F_B, epicentre zone ψ ≤ acos(e^(−0.511/n))")
    print(f"{'n':>7}" + "".join(f"{lb.name:>14}" for lb in ls))
    for n in N_TABLE:
        print(
            f"{n:>7g}"
            + "".join(f"{pct(float(st.epicentre_max_relative_error(lb, n)[0])):>14}" for lb in ls)
        )
    print(f"{'n→∞':>7}" + "".join(f"{pct(st.epicentre_limit_n_inf(lb)):>14}" for lb in ls))
    peaks = [st.epicentre_peak(lb) for lb in ls]
    print(f"{'max':>7}" + "".join(f"{pct(p[0]):>14}" for p in peaks))
    print(f"{'argmax':>7}" + "".join(f"{p[1]:>14.1f}" for p in peaks))
    n = np.geomspace(*st.FIG3_N, 257)
    where = []
    for lb in ls:
        c = st.epicentre_max_relative_error(lb, n)[1]
        at_edge = np.isclose(c, lobes.epicentre_limit_cos(n), rtol=0.0, atol=1e-15)
        where.append(f"edge {int(at_edge.sum())}/{n.size}")
    print(f"{'where':>7}" + "".join(f"{w:>14}" for w in where))

    print("\n== readings of the '4.5-fold' claim (δ as above; n ∈ [16, 1000])")
    for vol in ls[:3]:
        for name, r in st.improvement_ratios(vol, ls[3:]):
            print(f"  {name:<46}{r:6.2f}")
        for other in ls[3:]:
            r = pointwise_ratio(other, vol, n)
            hit = ""
            if r.min() < st.SEED_IMPROVEMENT < r.max():
                n45 = optimize.brentq(
                    lambda m, o=other, v=vol: float(pointwise_ratio(o, v, m)) - 4.5, *st.FIG3_N
                )
                hit = f"; = 4.5 at n = {n45:.1f}"
            print(f"  pointwise δ {other.name}/δ {vol.name}: {r.min():.2f} … {r.max():.2f}{hit}")


def absolute() -> None:
    ls = st.study_lobes()
    n = np.geomspace(*st.FIG3_N, 257)
    lim = np.arccos(lobes.epicentre_limit_cos(n))
    print("\n== max absolute error Δ = |F − F_B| over ψ ∈ [0, π/2] (F_B peak = 1)")
    print(f"{'lobe':<14}{'Δ n=16':>9}{'max Δ':>9}{'at n':>7}{'ψ*/lim(n)':>16}{'F_B(ψ*)':>14}  zone")
    for lb in ls:
        d, psi = lobe_grid.max_abs_error(lb, n)
        fb = lobes.power_cosine(np.cos(psi), n)
        ratio = psi / lim
        zone = "attenuation" if np.all(ratio > 1.0) else "epicentre/both"
        print(
            f"{lb.name:<14}{d[0]:>9.4f}{d.max():>9.4f}{n[np.argmax(d)]:>7.0f}"
            f"{ratio.min():>8.3f}…{ratio.max():<7.3f}{fb.min():>6.3f}…{fb.max():<7.3f}  {zone}"
        )


def zero_crossing() -> None:
    print("\n== zero crossing: eq 14 acos((29n − 64)/(29n)) vs the true zero acos(1 − 1/(ξn)), deg")
    ns = np.array([16.0, 64.0, 256.0, 1000.0])
    print(
        f"{'n':>7}{'eq 14':>10}"
        + "".join(f"{f'ξ={x:.5g}':>13}" for x in (29 / 64, st.SEED_XI, 0.5))
    )
    for n in ns:
        print(
            f"{n:>7g}{math.degrees(float(st.eq14_psi(n))):>10.4f}"
            + "".join(
                f"{math.degrees(float(lobe_grid.zero_crossing_psi(n, x))):>13.4f}"
                for x in (29 / 64, st.SEED_XI, 0.5)
            )
        )
    nn = np.geomspace(16.0, 1e4, 1000)
    raw = lobes.cosine_quadratic(np.cos(st.eq14_psi(nn)), nn, lobes.XI_29_64, cut=False)
    print(f"raw F_VOL(29/64) at eq 14, n ∈ [16, 1e4]: max {raw.max():.1e}")
    for x in (st.SEED_XI, st.equation_12().xi(), 0.5):
        print(f"raw (ξ n (c − 1) + 1)² at eq 14 with ξ = {x:.5f}: {(1 - x * 64 / 29) ** 2:.2e}")


def inflexion() -> None:
    print("\n== epicentre limit acos(e^(−0.511/n)) vs the exact inflexion atan(1/√(n−1))")
    print(f"{'n':>7}{'lim deg':>10}{'infl deg':>10}{'lim/infl−1':>12}", end="")
    print(f"{'F_B(infl)':>11}{'K exact':>9}")
    for n in N_TABLE:
        a = math.degrees(math.acos(math.exp(-st.K_PRINTED / n)))
        b = math.degrees(float(st.inflexion_psi(n)))
        print(
            f"{n:>7g}{a:>10.4f}{b:>10.4f}{100 * (a / b - 1):>11.3f}%"
            f"{(1 - 1 / n) ** (n / 2):>11.5f}{float(st.k_at_inflexion(n)):>9.5f}"
        )
    print(
        f"F_B at the limit: e^−0.511 = {math.exp(-0.511):.5f}; limit = inflexion at "
        f"n = {st.n_where_limit_is_inflexion():.2f}; n → ∞: K → 0.5, F_B(infl) → e^−½ = "
        f"{math.exp(-0.5):.5f}"
    )


def best_ns(stmt: Callable[[], object]) -> float:
    stmt()
    t = min(timeit.repeat(stmt, number=NUMBER, repeat=REPEATS)) / NUMBER
    return 1e9 * t / N_VALUES


def speed() -> None:
    rng = np.random.default_rng(3)
    hemi = np.cos(rng.uniform(0.0, math.pi / 2, N_VALUES))
    epi = np.cos(rng.uniform(0.0, math.acos(math.exp(-st.K_PRINTED / 100.0)), N_VALUES))
    n = 100.0
    ls = st.study_lobes()
    d = {lb.name: st.epicentre_peak(lb)[0] for lb in ls}
    ng = np.geomspace(*st.FIG3_N, 129)
    a = {lb.name: float(lobe_grid.max_abs_error(lb, ng)[0].max()) for lb in ls}
    cases: list[tuple[str, str, Callable[[np.ndarray], object]]] = [
        ("F_B n=100", "F_B", lambda c: lobes.power_cosine(c, n)),
        ("F_B n=37.5", "F_B", lambda c: lobes.power_cosine(c, 37.5)),
        ("F_B bare c**100.0", "F_B", lambda c: c**n),
        ("F_B bare c**37.5", "F_B", lambda c: c**37.5),
    ]
    for lb in ls:
        cases.append((lb.name, lb.name, lambda c, b=lb: b(c, n)))
    cases.append(("F_2 bare (xn(c−1)+1)²", "F_2", lambda c: np.square(50.0 * (c - 1.0) + 1.0)))
    cases.append(
        (
            "F_VOL bare max(…, 0)²",
            "F_VOL(29/64)",
            lambda c: np.square(np.maximum((lobes.XI_29_64 * n) * (c - 1.0) + 1.0, 0.0)),
        )
    )
    cases.append(("F_S bare c/(n−nc+c)", "F_S", lambda c: c / (n - n * c + c)))
    print(
        f"\n== speed, ns per value (numpy, {N_VALUES:.0e} values, best of {REPEATS}×{NUMBER}),"
        " n = 100; accuracy over n ∈ [16, 1000]"
    )
    print(f"{'evaluation':<26}{'hemisphere':>11}{'epicentre':>11}{'max δ epi':>11}{'max Δ':>8}")
    for label, key, fn in cases:
        dd, aa = ("0", "0") if key == "F_B" else (pct(d[key]), f"{a[key]:.3f}")
        print(
            f"{label:<26}{best_ns(lambda f=fn: f(hemi)):>11.2f}"
            f"{best_ns(lambda f=fn: f(epi)):>11.2f}{dd:>11}{aa:>8}"
        )


def main() -> None:
    machine()
    equation_12()
    epicentre()
    absolute()
    zero_crossing()
    inflexion()
    speed()


if __name__ == "__main__":
    _report.run(main, __file__, __doc__, title="Romanyuk et al.'s lobes: accuracy next to speed")
