"""The trend charts' geometry: runs spread along x, values along y (higher values higher up), a missing value
breaks its line, shares stay inside [0, 1], and series of the wrong length are refused."""

from __future__ import annotations

from dataclasses import dataclass

import pytest

from flows.dashboard.charts import line_chart, run_label


@dataclass(frozen=True)
class Line:
    label: str
    values: tuple[float | None, ...]


def test_points_follow_runs_and_values() -> None:
    chart = line_chart(["r1", "r2", "r3"], [Line("a", (0.2, 0.4, 0.3))])
    (line,) = chart.lines
    xs, ys = [p.x for p in line.points], [p.y for p in line.points]
    assert xs == sorted(xs) and xs[0] == chart.left and xs[-1] == chart.right
    assert ys[1] < ys[2] < ys[0]  # SVG y grows downwards
    assert all(chart.top <= y <= chart.bottom for y in ys)
    assert len(line.segments) == 1 and len(line.segments[0].split()) == 3


def test_a_missing_value_breaks_the_line() -> None:
    (line,) = line_chart(["a", "b", "c", "d", "e"], [Line("x", (1.0, 2.0, None, 3.0, 4.0))]).lines
    assert len(line.points) == 4 and len(line.segments) == 2


def test_shares_stay_inside_zero_and_one() -> None:
    chart = line_chart(["a", "b"], [Line("x", (0.98, 1.0))], unit="share")
    labels = [float(label) for _, label in chart.y_ticks]
    assert max(labels) <= 1.0 and min(labels) >= 0.0


def test_one_run_sits_in_the_middle() -> None:
    chart = line_chart(["only"], [Line("x", (5.0,))])
    assert chart.lines[0].points[0].x == pytest.approx((chart.left + chart.right) / 2)
    assert chart.lines[0].segments == ()


def test_series_of_the_wrong_length_are_refused() -> None:
    with pytest.raises(ValueError, match="'x' has 1 values for 2 runs"):
        line_chart(["a", "b"], [Line("x", (1.0,))])


def test_run_labels_are_short() -> None:
    assert run_label("main-20261127T165818912979Z") == "11-27 16:58"
    assert run_label("my-very-long-run-name") == "my-very-long-…"
