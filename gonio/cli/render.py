"""Plan summaries as text: the table `gonio plan` (and `gonio acquire`) prints."""

from __future__ import annotations

from typing import TYPE_CHECKING

from gonio.planner import Plan, Summary
from gonio.progress import hms
from gonio.rig import PyMeasureInterfaceSpec

if TYPE_CHECKING:  # the choice's module is imported only by the command that chooses
    from gonio.tradeoff import Choice, Prediction


def render_summary(plan: Plan) -> str:
    """The summary table `gonio plan` prints."""
    s = plan.summary
    spec = plan.spec
    kind = "isotropic" if spec.isotropic else "anisotropic"
    lines = [
        f"plan {spec.name!r}: {kind} {spec.parametrization}, {spec.sampling.strategy}"
        + (f" {'×'.join(map(str, s.grid_shape))}" if s.grid_shape else "")
        + f", rig {plan.rig.spec.name!r}",
        f"  {'requested':<26}{s.requested:>9}",
        f"  {'outside the domain':<26}{s.invalid:>9}",
    ]
    for label, count in s.refused.items():
        lines.append(f"  {'refused: ' + label.replace('_', ' '):<26}{count:>9}")
    lines += [
        f"  {'kept':<26}{s.kept:>9}"
        + (
            f"   (target {s.target}: a grid keeps the cells that fall in the domain)"
            if s.target is not None and s.grid_shape is not None and s.kept != s.target
            else ""
        ),
    ]
    if spec.sampling.strategy == "adaptive" and s.target is not None and s.kept < s.target:
        lines.append(
            f"  {'':<26}{'':>9}   (the survey: the other {s.target - s.kept} targets are "
            "planned from its measurements during the run, docs/explanations/adaptive.md)"
        )
    if s.second_pass is not None:
        lines.append(f"  {'second pass':<26}{'':>9}   {s.second_pass}")
    if s.fly is not None:
        fly = spec.sampling.fly_options()
        paths = fly.segment == "theta_h_line"
        return "\n".join(
            [*lines, "", *fly_lines(s, paths, fly.fill), f"  {'ordering':<26}{ordering_line(s)}"]
        )
    bus = f", bus {hms(s.bus_s)}" if s.timing == "dynamixel" else ""
    lines += [
        "",
        f"  {'predicted duration':<26}{hms(s.total_s):>9}   (moves {hms(s.travel_s)}, "
        f"settle + exposure {hms(s.dwell_s)}{bus})",
        f"  {'timed with':<26}{timing_line(plan)}",
    ]
    if s.naive_total_s is not None:
        lines.append(
            f"  {'in generation order':<26}{hms(s.naive_total_s):>9}   "
            f"({s.naive_total_s / s.total_s:.2f}× the ordered plan)"
        )
    if s.lower_bound_s is not None and s.lower_bound_travel_s is not None:
        weak = "" if s.lower_bound_exact else "; memory forced a weaker bound"
        lines.append(
            f"  {'lower bound (Held–Karp)':<26}{hms(s.lower_bound_s):>9}   "
            f"(ordered / bound = {s.travel_s / max(s.lower_bound_travel_s, 1e-12):.3f}"
            f" in moves, any order and solutions{weak})"
        )
    if s.mst_travel_s is not None:
        lines.append(
            f"  {'lower bound (MST)':<26}{hms(s.mst_travel_s + s.dwell_s + s.bus_s):>9}   "
            f"(ordered / bound = {s.travel_s / max(s.mst_travel_s, 1e-12):.3f} in moves)"
        )
    if _dark_subtracted(plan) and spec.acquisition.calibration.dark:
        lines.append(
            f"  {'dark readings':<26}{'none':>9}   (the detector subtracts the dark and "
            "ambient signal: a lock-in behind a chopper)"
        )
    lines.append(f"  {'ordering':<26}{ordering_line(s)}")
    if plan.ordering_s is not None:  # a plan built here, not read back
        lines.append(f"  {'ordering took':<26}{plan.ordering_s:>8.1f}s")
    return "\n".join(lines)


def timing_line(plan: Plan) -> str:
    """What a stop-and-go plan's times were predicted with (`Summary.timing`): the rig
    file's rates, or the rates the Dynamixel motors' profile registers hold and the
    bus's wire time a target (goals, settle polls, read back)."""
    s = plan.summary
    if s.timing == "rig":
        return "the rig file's velocities and accelerations (simulated motors, no bus)"
    baud = f"{plan.rig.spec.bus.baud:,}".replace(",", " ")
    per_target = 1e3 * s.bus_s / max(s.kept, 1)
    return (
        f"the motors' register-rounded profiles and the bus at {baud} baud "
        f"({per_target:.1f} ms a target)"
    )


def fly_lines(s: Summary, paths: bool = False, fill: int = 0) -> list[str]:
    """A fly plan's lines of the summary: its sweeps, their velocities, the predicted
    readings and duration against stop-and-go, and the coverage figure; ``paths``: its
    sweeps are path lines along θh (every axis moving), ``fill`` stop-and-go targets
    after them (a mixed plan)."""
    f = s.fly
    assert f is not None
    per_hour = 3600.0 * s.kept / max(s.total_s, 1e-12)
    sg_per_hour = 3600.0 * s.kept / max(f.stop_and_go_s, 1e-12)
    speeds = (
        f"{f.velocity_min_deg_s:.3g}°/s"
        if abs(f.velocity_max_deg_s - f.velocity_min_deg_s) < 1e-9
        else f"{f.velocity_min_deg_s:.3g}–{f.velocity_max_deg_s:.3g}°/s"
    )
    if paths:
        head = [
            f"  {'sweeps':<26}{f.segments:>9}   (on {f.lines} lines along θh at fixed θd, φd; "
            "every axis follows a trajectory)",
            f"  {'fastest axis':<26}{speeds:>9}   (smear ≤ {f.smear_max_deg:.3g}° per reading, "
            f"budget {f.blur_deg:g}°)",
            f"  {'readings':<26}{s.kept:>9}   ({1 / f.period_s:g} Hz, {1e3 * f.integration_s:g} "
            f"ms each; {f.streamed} streamed, those at least half the budget apart along θh "
            "kept)",
            f"  {'predicted duration':<26}{hms(s.total_s):>9}   (on the lines "
            f"{hms(f.cruise_s)}, moves + settle {hms(f.moves_s)}"
            + (f"; then {fill} stop-and-go targets where the lines leave gaps)" if fill else ")"),
        ]
    else:
        head = [
            f"  {'sweeps':<26}{f.segments:>9}   (on {f.lines} lines)",
            f"  {'sweep velocity':<26}{speeds:>9}   (smear ≤ {f.smear_max_deg:.3g}° per "
            f"reading, budget {f.blur_deg:g}°)",
            f"  {'readings':<26}{s.kept:>9}   ({1 / f.period_s:g} Hz, {1e3 * f.integration_s:g} "
            f"ms each; {f.streamed} streamed, thinned to cover the coordinates uniformly)",
            f"  {'predicted duration':<26}{hms(s.total_s):>9}   (constant velocity "
            f"{hms(f.cruise_s)}, ramps {hms(f.ramps_s)}, moves + settle {hms(f.moves_s)})",
        ]
    return [
        *head,
        f"  {'readings per hour':<26}{per_hour:>9,.0f}   (stop-and-go: {sg_per_hour:,.0f}, "
        f"{hms(f.stop_and_go_s)} for as many; {f.stop_and_go_s / max(s.total_s, 1e-12):.1f}× "
        "faster)",
        f"  {'coverage (TV distance)':<26}{f.coverage_tv:>9.3f}   (to uniform over the reach, "
        f"{f.coverage_bins} bins a coordinate; a uniform stop-and-go plan of as many: "
        f"{f.coverage_tv_uniform:.3f})",
        f"  {'largest empty ball':<26}{f.coverage_gap:>9.3f}   (radius in the unit box about a "
        f"reachable point; the uniform plan's: {f.coverage_gap_uniform:.3f})",
    ]


def _dark_subtracted(plan: Plan) -> bool:
    """Whether the rig's detector reads dark-subtracted values (a PyMeasure lock-in)."""
    interface = plan.rig.spec.detector.interface
    return isinstance(interface, PyMeasureInterfaceSpec) and interface.config().dark_subtracted


def ordering_line(s: Summary) -> str:
    """How the ordering ended, for the summary table."""
    kicks = f"{s.kicks:,} kicks ({s.kicks_kept:,} kept)"
    if s.stopped == "converged":
        return (
            f"converged after {s.moves:,} moves, then {kicks}; budgets {s.max_moves:,} "
            f"and {s.max_kicks:,}"
        )
    if s.stopped == "move budget":
        return f"stopped at the move budget ({s.max_moves:,} moves): not converged"
    return (
        f"stopped at the time cap ({s.time_cap_s:g} s, after {s.moves:,} of {s.max_moves:,} "
        f"moves, {s.kicks:,} of {s.max_kicks:,} kicks): not converged, and this order "
        "depends on the machine's speed"
    )


def render_choice(choice: Choice) -> str:
    """The candidates of a choice of plan, their predictions and the choice, with why."""
    minutes = f"{choice.budget_s / 60.0:g} min"
    lines = [
        f"choice of plan for {minutes} of instrument time, the material guess {choice.material}",
        f"  predicted on {choice.test_pairs} test pairs (seed {choice.test_seed}): the guess "
        "sampled without noise or blur at each plan's pairs,",
        "  reconstructed linearly across every gap and by rbf (the lower counts; outside "
        "the support, the nearest sample's value), log-RMSE over every pair",
        f"  {'candidate':<34}{'motion':<7}{'time':>9}{'samples':>9}{'log-RMSE':>10}"
        f"{'method':>8}{'coverage':>10}{'gap':>7}",
    ]
    for p in choice.predictions:
        head = f"  {p.name:<34}{'fly' if p.is_fly else 'stop':<7}"
        if p.plan is None or p.log_rmse is None:
            lines.append(f"{head}{'—':>9}   ({p.error or 'no prediction'})")
            continue
        mark = "   ← chosen" if p is choice.chosen else ""
        lines.append(
            f"{head}{hms(p.seconds or 0.0):>9}{p.samples:>9}{p.log_rmse:>10.3g}"
            f"{p.method:>8}{_percent(p.coverage):>10}{_number(p.gap):>7}{mark}"
        )
    lines += [
        "  (coverage: the share of test pairs inside the method's support; gap: the largest "
        "distance from a test pair",
        "  to its nearest sample, in the unit box of the plan's coordinates)",
        f"chose {choice.chosen.name} for {minutes}: {choice_reason(choice)} (chosen in "
        f"{choice.wall_s:.1f} s)",
    ]
    return "\n".join(lines)


def choice_reason(choice: Choice) -> str:
    """Why the chosen candidate: its predicted error against the best of the other
    motion's."""
    chosen, stop = choice.chosen, choice.best_stop
    assert chosen.log_rmse is not None
    if chosen.is_fly:
        if stop is None or stop.log_rmse is None:
            return f"predicted log-RMSE {chosen.log_rmse:.3g}; no stop-and-go plan fits"
        return (
            f"predicted log-RMSE {chosen.log_rmse:.3g} against {stop.log_rmse:.3g} for the "
            f"best stop-and-go ({stop.name}), {stop.log_rmse / chosen.log_rmse:.1f}× lower"
        )
    fly = _best_of(choice.predictions)
    if fly is None or fly.log_rmse is None:
        return f"predicted log-RMSE {chosen.log_rmse:.3g}; no fly plan fits"
    lowest = "" if fly.log_rmse < chosen.log_rmse else "the lowest "
    return (
        f"{lowest}predicted log-RMSE {chosen.log_rmse:.3g}; the best fly plan "
        f"({fly.name}) is predicted {fly.log_rmse:.3g}, and a fly plan is chosen only "
        f"when predicted at least {choice.margin:g}× lower than every stop-and-go one (the "
        "prediction knows no noise, blur or jitter)"
    )


def _best_of(predictions: tuple[Prediction, ...]) -> Prediction | None:
    """The fly candidate of lowest predicted error (None if none has one)."""
    scored = [p for p in predictions if p.is_fly and p.log_rmse is not None]
    return min(scored, key=lambda p: p.log_rmse or 0.0) if scored else None


def _percent(share: float | None) -> str:
    return "—" if share is None else f"{100.0 * share:.0f} %"


def _number(value: float | None) -> str:
    return "—" if value is None else f"{value:.3f}"
