"""The fuzz campaign of ``benchmarks/fuzz_campaign.py`` at a small count, as a regular test.

The benchmark runs ≥ 100 000 observations and ≥ 5 000 file mutants; CI replays the same seeded
generators (every garbage type, every file format) at a count that takes seconds. Any traceback,
unsafe command or internal error fails the test with examples.
"""

from __future__ import annotations

import dataclasses
import importlib.util
import sys
import warnings
from pathlib import Path

import pytest

from fearguard.errors import SensorLogWarning

CAMPAIGN = Path(__file__).resolve().parents[2] / "benchmarks" / "fuzz_campaign.py"


@pytest.fixture(scope="module")
def campaign():
    spec = importlib.util.spec_from_file_location("fuzz_campaign", CAMPAIGN)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up by name
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("seed", [1, 2])
def test_fuzzed_observations_and_file_mutants_give_no_traceback_unsafe_command_or_internal_error(campaign, seed: int) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SensorLogWarning)
        tally = campaign.campaign(observations=1_200, files=72, seed=seed)
    summary = tally.summary()
    assert summary["observations"] == 1_200 and summary["file_mutants"] == 72
    assert summary["frame_observations"] > 0 and summary["expected_faults"] > 0
    assert (summary["tracebacks"], summary["unsafe_commands"], summary["internal_errors"]) == (0, 0, 0), summary["examples"]
    kinds = {k.split(":")[0] for k in summary["file_outcomes"]}
    assert kinds == {"rules", "vehicle", "camera", "counterexample", "scenario", "sensor_csv", "sensor_jsonl", "tub_manifest",
                     "tub_catalog"}


def test_the_oracle_catches_an_unsafe_command_and_an_unreported_fault(campaign) -> None:
    import math

    import fearguard as fg

    vehicle = fg.VehicleLimits()
    tally = campaign.Tally()
    bad = fg.Command(0.0, vehicle.max_speed_mps * 2, fg.Mode.NORMAL, fg.Strategy.PASS_THROUGH, 0.1, fg.FearLevel.VERY_LOW,
                     fg.Cues(0.9, 120.0, 0.0, math.inf, 0.0), ("fear 0.10",))
    campaign.judge(bad, vehicle, campaign.Injected(fault="steering raised", non_number_cues=(0,)), tally)
    assert set(tally.unsafe) == {"speed limit outside [0, max]", "injected fault not reported (steering raised)",
                                 "non-number read as a number (lane_confidence)"}
    internal = fg.Command(0.0, 0.0, fg.Mode.EMERGENCY, fg.Strategy.STOP, 1.0, fg.FearLevel.VERY_HIGH,
                          fg.Cues(*[math.nan] * 5), ("fault: internal error ValueError: x",))
    campaign.judge(internal, vehicle, campaign.Injected(), tally)
    assert sum(tally.internal_errors.values()) == 1 and not tally.clean


# -- the same oracle over the testing kit's public strategies (fearguard.testing) ----------------
try:
    from hypothesis import given, settings
    from hypothesis import strategies as st

    from fearguard.testing import strategies as kit
except ImportError:  # pragma: no cover - hypothesis is a test dependency
    kit = None


if kit is not None:
    import fearguard as fg

    CAR = fg.VehicleLimits(has_ultrasonic=True, has_qr_localisation=True)

    @settings(max_examples=150, derandomize=True, deadline=None)
    @given(history=st.lists(st.one_of(kit.observations(vehicle=CAR), kit.observations(vehicle=CAR, level="frame")),
                            min_size=1, max_size=6),
           bad=kit.non_numbers(), field=st.integers(0, 4), steer=kit.steering_outputs(CAR))
    def test_kit_observations_with_a_non_number_cue_keep_every_invariant(campaign, history, bad, field, steer) -> None:
        guard = fg.FearGuard(lambda frame: steer, vehicle=CAR)
        tally = campaign.Tally()
        for obs in history:
            injected = campaign.Injected()
            if obs.cues is not None:
                values = list(obs.cues.values())
                values[field] = bad
                obs = dataclasses.replace(obs, cues=fg.Cues(*values))
                injected = campaign.Injected(non_number_cues=(field,))
            campaign.judge(guard.step(obs), CAR, injected, tally)
        assert tally.clean, tally.examples
