"""The boundary tracks: a detection far from its track is a miss; only a persistent one moves the track."""

from __future__ import annotations

import numpy as np

from fearguard.vision.lane_tracker import REINIT_AFTER, BoundaryTrack

WIDTH_PX = 320


def steady_track() -> BoundaryTrack:
    track = BoundaryTrack(WIDTH_PX)
    for k in range(10):
        track.predict(0.05)
        assert track.update(0.05 * k, np.array([150.0, -40.0]))
    return track


def test_outliers_scattered_over_the_image_never_move_the_track() -> None:
    track = steady_track()
    for k, z in enumerate([(190.0, 360.0), (240.0, 300.0), (65.0, 378.0), (200.0, 420.0), (90.0, 250.0)]):
        track.predict(0.05)
        assert not track.update(0.5 + 0.05 * k, np.array(z))  # a shadow edge, a far dash, ...: noise
    assert abs(float(track.kf.x[0]) - 150.0) < 5.0


def test_an_outlier_that_persists_reinitialises_the_track_there() -> None:
    track = steady_track()
    accepted = []
    for k in range(REINIT_AFTER):
        track.predict(0.05)
        accepted.append(track.update(0.5 + 0.05 * k, np.array([60.0 + k, 300.0 - k])))  # the lane really moved
    assert accepted == [False] * (REINIT_AFTER - 1) + [True]
    assert abs(float(track.kf.x[0]) - (60.0 + REINIT_AFTER - 1)) < 1e-6
