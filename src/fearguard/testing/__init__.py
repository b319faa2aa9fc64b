"""fearguard.testing: prove the safety invariants of docs/architecture.md for *your* car with hypothesis.

Needs the ``testing`` extra (``pip install fearguard[testing]``: hypothesis); ``import fearguard`` does not.

In a test file, three lines::

    from fearguard.testing import supervisor_invariants
    test_my_car = supervisor_invariants(rules="rules/my_car.toml", vehicle=MY_CAR, steer=my_pilot)

From the shell: ``fearguard verify --rules rules/my_car.toml --vehicle vehicle.toml --steer my_pilot:steer``.

The parts, for your own properties:

- strategies (``fearguard.testing.strategies``): ``cues``, ``calm_cues``, ``hazard_cues``, ``cue_values``,
  ``unknown_values``, ``non_numbers``, ``speeds``, ``steering_outputs``, ``leads``, ``lead_boxes``,
  ``ultrasonic_readings``, ``echo_times``, ``qr_payloads``, ``frame_specs``, ``time_steps``, ``histories``,
  ``observations``, ``vehicles`` — each sized by a ``RuleBase`` and a ``VehicleLimits``;
- ``INVARIANTS``: one ``Invariant`` per numbered invariant, each with ``cases(subject)`` and
  ``check(subject, case)``; ``find_counterexample`` searches one, ``verify`` all of them;
- histories: ``Step``, ``Case``, ``FrameSpec``, ``save_case`` / ``load_case`` (JSON Lines with log.jsonl's
  names), ``run`` (a history through a fresh supervisor), ``replay_counterexample``.
"""

from fearguard.testing import strategies
from fearguard.testing.history import Case, FrameSpec, HistoryError, SteerRaises, Step, load_case, save_case
from fearguard.testing.invariants import INVARIANTS, Invariant, invariant
from fearguard.testing.strategies import (
    calm_cues,
    cue_values,
    cues,
    echo_times,
    frame_specs,
    hazard_cues,
    histories,
    lead_boxes,
    leads,
    non_numbers,
    observations,
    qr_payloads,
    speeds,
    steering_outputs,
    time_steps,
    ultrasonic_readings,
    unknown_values,
    vehicles,
)
from fearguard.testing.subject import Driver, Run, SetupError, Subject, run
from fearguard.testing.verify import (
    Counterexample,
    Outcome,
    find_counterexample,
    replay_counterexample,
    supervisor_invariants,
    table,
    verify,
)

__all__ = [
    "INVARIANTS",
    "Case",
    "Counterexample",
    "Driver",
    "FrameSpec",
    "HistoryError",
    "Invariant",
    "Outcome",
    "Run",
    "SetupError",
    "SteerRaises",
    "Step",
    "Subject",
    "calm_cues",
    "cue_values",
    "cues",
    "echo_times",
    "find_counterexample",
    "frame_specs",
    "hazard_cues",
    "histories",
    "invariant",
    "lead_boxes",
    "leads",
    "load_case",
    "non_numbers",
    "observations",
    "qr_payloads",
    "replay_counterexample",
    "run",
    "save_case",
    "speeds",
    "steering_outputs",
    "strategies",
    "supervisor_invariants",
    "table",
    "time_steps",
    "ultrasonic_readings",
    "unknown_values",
    "vehicles",
    "verify",
]
