"""The timeline and trajectory plots as a person reads them: every panel labelled with its unit, fixed scales where
a quantity has one, the thresholds and strategies drawn, legends clear of the data and inside the picture, a lane
that fills its plot. Checked on the drawn figure (Agg renderer), not by eye alone."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from fearguard.cues import Cues
from fearguard.fear import FearLevel
from fearguard.fuzzy.loader import bundled_rules_path, load_rules
from fearguard.outputs.timeline import Trace, timeline_figure
from fearguard.policy import Mode, Strategy
from fearguard.sim.loop import run_scenario
from fearguard.sim.scenario import load_scenario
from fearguard.sim.suite import trajectory_figure
from fearguard.supervisor import Command

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"


def _trace(brightness: list[float], strategies: list[Strategy]) -> Trace:
    trace = Trace()
    for k, (b, strategy) in enumerate(zip(brightness, strategies, strict=True)):
        mode = Mode.EMERGENCY if strategy in (Strategy.STOP, Strategy.FOLLOW_LEAD) else Mode.NORMAL
        cues = Cues(0.8, b, 0.1, 3.0 if k % 2 else math.inf, 0.0)
        trace.add(k * 0.05, Command(0.0, 1.0, mode, strategy, 0.2, FearLevel.LOW, cues, ()), speed_mps=0.9)
    return trace


def _drawn(fig: Figure) -> Figure:
    FigureCanvasAgg(fig).draw()
    return fig


def _legends_clear_and_inside(fig: Figure) -> None:
    """Each legend to the right of its panel (clear of the data) and wholly inside the figure."""
    renderer = fig.canvas.get_renderer()
    width, height = fig.bbox.width, fig.bbox.height
    for ax in fig.axes:
        legend = ax.get_legend()
        if legend is None:
            continue
        box, panel = legend.get_window_extent(renderer), ax.get_window_extent(renderer)
        assert box.x0 >= panel.x1, f"legend of {ax.get_ylabel()!r} covers its panel"
        assert box.x1 <= width and box.y0 >= 0 and box.y1 <= height, f"legend of {ax.get_ylabel()!r} leaves the figure"


def test_the_timeline_labels_every_panel_and_keeps_fixed_scales():
    trace = _trace([100.0, 101.0, 102.0, 101.0] * 10, [Strategy.PASS_THROUGH] * 40)  # a 2-level flicker
    fig = _drawn(timeline_figure(trace, "flicker", with_speed=True, rules=load_rules(None)))
    panels = fig.axes
    assert all(ax.get_ylabel() for ax in panels)
    assert panels[5].get_xlabel() == "t (s)"
    brightness = next(ax for ax in panels if "grey level" in ax.get_ylabel())
    assert brightness.get_ylim() == (0.0, 255.0)  # noise of a grey level or two stays a flat line
    assert any("(m" in ax.get_ylabel() for ax in panels) and any("(m/s)" in ax.get_ylabel() for ax in panels)
    _legends_clear_and_inside(fig)
    title = fig.texts[0].get_window_extent(fig.canvas.get_renderer())
    assert title.x0 >= 0 and title.x1 <= fig.bbox.width  # the title is not clipped


def test_the_fear_panel_draws_the_rule_files_thresholds():
    rules = load_rules(bundled_rules_path("road_car.toml"))
    fig = _drawn(timeline_figure(_trace([120.0] * 5, [Strategy.PASS_THROUGH] * 5), rules=rules))
    fear = next(ax for ax in fig.axes if ax.get_ylabel().startswith("fear"))
    levels = sorted(line.get_ydata()[0] for line in fear.get_lines()[1:])
    assert levels == sorted([rules.policy.caution_fear, rules.policy.emergency_enter_fear])
    labels = fear.get_legend_handles_labels()[1]
    assert any(label.startswith("caution") for label in labels) and any(label.startswith("emergency") for label in labels)
    without = _drawn(timeline_figure(_trace([120.0] * 5, [Strategy.PASS_THROUGH] * 5)))  # no rule base: nothing invented
    assert len(next(ax for ax in without.axes if ax.get_ylabel().startswith("fear")).get_lines()) == 1


def test_strategies_are_shaded_and_named_only_when_they_happened():
    strategies = [Strategy.PASS_THROUGH] * 10 + [Strategy.FOLLOW_LEAD] * 10 + [Strategy.STOP] * 5 + [Strategy.PASS_THROUGH] * 5
    fig = _drawn(timeline_figure(_trace([120.0] * 30, strategies), rules=load_rules(None)))
    labels = fig.axes[5].get_legend_handles_labels()[1]
    assert labels == ["mode", "strategy FOLLOW_LEAD", "strategy STOP"]
    _legends_clear_and_inside(fig)


def test_a_timeline_with_qr_staleness_keeps_both_range_axes_labelled_and_legends_inside():
    trace = _trace([120.0] * 20, [Strategy.PASS_THROUGH] * 20)
    trace.cues["qr_staleness_s"] = [0.5 * k for k in range(20)]
    fig = _drawn(timeline_figure(trace, "with QR", rules=load_rules(None)))
    assert any("QR staleness" in ax.get_ylabel() for ax in fig.axes)
    _legends_clear_and_inside(fig)


@pytest.mark.parametrize("name", ["stationary_obstacle", "s_curves"])
def test_the_trajectory_shows_the_lane_at_a_readable_scale(name: str):
    scenario = load_scenario(SCENARIOS / f"{name}.toml")
    result = run_scenario(scenario, seed=0)
    fig = _drawn(trajectory_figure(scenario, result.rows, f"{name} (guarded, seed 0)"))
    along = fig.axes[0]
    low, high = along.get_ylim()
    assert scenario.road.lane_width_m / (high - low) >= 0.3  # the lane is not a hairline in an empty square
    assert along.get_xlim() == (0.0, pytest.approx(along.get_xlim()[1])) and along.get_xlim()[1] > 5.0
    assert along.get_xlabel() and along.get_ylabel()
    assert (len(fig.axes) == 2) == (name == "s_curves")  # the top-down map only where the road bends
    renderer = fig.canvas.get_renderer()
    title = fig.texts[0].get_window_extent(renderer)
    assert title.x0 >= 0 and title.x1 <= fig.bbox.width
    _legends_clear_and_inside(fig)
    labels = along.get_legend_handles_labels()[1]
    assert "NORMAL" in labels and ("obstacle" in labels) == bool(scenario.obstacles)


@pytest.mark.parametrize("frames", [0, 1])
def test_an_empty_or_one_frame_timeline_still_draws(frames: int):
    fig = _drawn(timeline_figure(_trace([120.0] * frames, [Strategy.STOP] * frames), "short", rules=load_rules(None)))
    low, high = fig.axes[5].get_xlim()
    assert high > low
    _legends_clear_and_inside(fig)
