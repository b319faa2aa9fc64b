"""Issue 12, item 2: a copy of the last QR board cannot reset staleness while the odometer reading is missing,
and the route can be configured so that one forged sticker cannot lock every genuine board out."""

from __future__ import annotations

import math

import fearguard as fg
from fearguard.sensors.localisation import QrLocaliser

BOARD = "FG1;route=campus;sector=1;pos_m=10.0"
QR_CAR = fg.VehicleLimits(has_ultrasonic=False, has_qr_localisation=True)


def staleness(vehicle: fg.VehicleLimits, frames) -> list[float]:
    """The issue's reproducer: FearGuard.step on QR payloads and odometer readings (10 s gaps are stalls: faults, and
    the cues are still measured)."""
    guard = fg.FearGuard(lambda f: 0.0, vehicle=vehicle)
    return [guard.step(fg.Observation(t_s=t, speed_mps=1.0, qr_payload=p, odometer_m=odo)).cues.qr_staleness_s
            for t, p, odo in frames]


def test_a_stale_board_read_without_odometer_is_rejected() -> None:
    # the reproducer of the issue: 0 10 0 1 on the starting commit; with odometer 50 at t=20: 0 10 20 21
    for odo in (None, math.nan):
        assert staleness(QR_CAR, [(0.0, BOARD, 0.0), (10.0, None, 25.0), (20.0, BOARD, odo), (21.0, None, 51.0)]) == [
            0.0, 10.0, 20.0, 21.0]


def test_missing_odometer_is_dead_reckoned_with_the_speed() -> None:
    loc = QrLocaliser()
    loc.update(0.0, [BOARD], 0.0)
    assert loc.update(1.0, [BOARD], None, speed_mps=1.0).staleness_s == 0.0  # 1 m driven: still approaching the board
    assert loc.update(7.0, [BOARD], None, speed_mps=1.0).staleness_s == 6.0  # 7 m driven: a copy, rejected
    never = QrLocaliser()  # no odometer ever read: the time × speed bound still applies
    never.update(0.0, [BOARD], None)
    assert never.update(1.0, ["FG1;route=campus;sector=2;pos_m=15.0"], None).staleness_s == 0.0


def test_a_configured_route_ignores_a_forged_first_board() -> None:
    forged = "FG1;route=evil;sector=0;pos_m=0.0"
    locked = QrLocaliser()
    locked.update(0.0, [forged], 0.0)
    assert locked.update(1.0, [BOARD], 1.0).staleness_s == 1.0  # the first board read locked the route
    car = fg.VehicleLimits(has_qr_localisation=True, qr_route="campus")
    assert staleness(car, [(0.0, forged, 0.0), (1.0, BOARD, 1.0)]) == [math.inf, 0.0]
    assert fg.VehicleLimits.preset("qr_campus").localiser_max_speed_mps == 1.2 * 3.0
