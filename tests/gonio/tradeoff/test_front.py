"""The Pareto front of error against instrument time on known numbers, its defining
property on random rows, and the fastest row meeting a target."""

from __future__ import annotations

from typing import Any

from hypothesis import given
from hypothesis import strategies as st

from gonio.tradeoff.front import best, fastest_meeting, pareto_front


def rows(*pairs: tuple[float | None, float | None]) -> list[dict[str, Any]]:
    return [{"instrument_s": t, "log_rmse": e, "n": i} for i, (t, e) in enumerate(pairs)]


KNOWN = rows(
    (100.0, 0.05),  # 0 front: fastest
    (150.0, 0.06),  # 1 slower and worse than 0
    (200.0, 0.03),  # 2 front
    (200.0, 0.03),  # 3 the same as 2: 2 stands for both
    (210.0, 0.03),  # 4 slower, no better
    (300.0, 0.01),  # 5 front
    (400.0, None),  # 6 failed: no error
    (None, 0.001),  # 7 no time
    (500.0, 0.02),  # 8 dominated by 5
)


def test_the_front_on_known_numbers() -> None:
    assert pareto_front(KNOWN, "log_rmse") == [0, 2, 5]
    assert pareto_front([], "log_rmse") == []


def test_the_fastest_meeting_a_target() -> None:
    assert fastest_meeting(KNOWN, "log_rmse", 0.03)["n"] == 2  # type: ignore[index]
    assert fastest_meeting(KNOWN, "log_rmse", 0.05)["n"] == 0  # type: ignore[index]
    assert fastest_meeting(KNOWN, "log_rmse", 0.0099) is None
    assert best(KNOWN, "log_rmse")["n"] == 5  # type: ignore[index]
    assert best(rows((None, None)), "log_rmse") is None


POINT = st.tuples(st.integers(1, 8).map(float), st.integers(1, 8).map(lambda e: e / 100))


@given(st.lists(POINT, max_size=30))
def test_no_front_row_is_dominated_and_every_other_row_is(
    points: list[tuple[float, float]],
) -> None:
    table = rows(*points)
    front = pareto_front(table, "log_rmse")

    def dominates(a: tuple[float, float], b: tuple[float, float]) -> bool:
        return a[0] <= b[0] and a[1] <= b[1] and a != b

    for i in front:
        assert not any(dominates(p, points[i]) for p in points)
    for i in set(range(len(points))) - set(front):
        assert any(dominates(points[j], points[i]) or points[j] == points[i] for j in front)
    assert [points[i][0] for i in front] == sorted(points[i][0] for i in front)
    assert len({points[i] for i in front}) == len(front)
