"""The figures of an ordering (`Ordering`) and why its search stopped (`Stop`): what a
`Plan` keeps of how its targets were ordered, apart from the search that ordered them
(`gonio.planner.ordering`, whose compiled loops load numba), so a stored plan is read
without it."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

#: Why a search stopped (only the last depends on the machine).
Stop = Literal["converged", "move budget", "time cap"]


@dataclass(frozen=True)
class Ordering:
    """``order`` indexes the targets in visiting order; times in seconds (moves only)."""

    order: np.ndarray
    travel_s: float  # the ordered path from the start
    constructed_s: float  # the constructive order before improvement
    given_s: float  # the targets in the order given
    lower_bound_s: float  # the minimum spanning tree over the start and the targets
    lower_bound_exact: bool  # False if memory forced a weaker bound
    moves: int  # improving moves of the descent
    converged: bool  # the descent ended with no improving move left
    stopped: Stop = "converged"  # why the improvement ended
    max_moves: int = 0  # the budget of improving moves it had
    order_wall_s: float = 0.0  # wall time spent constructing and improving
    bound_wall_s: float = 0.0  # wall time spent on the lower bound
    kicks: int = 0  # kicks of the iterated local search tried
    kicks_kept: int = 0  # … that shortened the path
    max_kicks: int = 0  # the budget of kicks
