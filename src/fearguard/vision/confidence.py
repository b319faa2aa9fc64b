"""lane_confidence from evidence: both boundaries, their support, plausible geometry, agreement over time.

    confidence = mean(support_left, support_right) × geometry × agreement × visibility

A side not found contributes 0 support, so one boundary alone gives at most 0.5. ``geometry`` is 1 when the
lane width at the region's middle row and the vanishing point are plausible for a forward camera, falling linearly
to 0 outside; ``agreement`` (1 without history) compares the detection with the tracked estimate.
``visibility`` = (1 − occlusion / OCCLUDED_BLIND) × (1 − clipped share / CLIPPED_BLIND): a boundary found on the visible
part of the road says nothing about the hidden part, and clipped (saturated or black) pixels carry no
information at all — so washed-out, dark and hidden markings all lower the confidence.
"""

from __future__ import annotations

from dataclasses import dataclass

from fearguard.vision.lanes import LaneLine, RoadRegion, geometry_plausibility, vanishing_point  # noqa: F401

CLIPPED_BLIND = 0.5  # [-] share of clipped road pixels at which the picture counts as blind
OCCLUDED_BLIND = 0.8  # [-] occlusion at which the visible rest of the markings no longer vouches for the lane
AGREEMENT_SCALE = 0.35  # [-] of the lane width: mean disagreement with the track at which agreement reaches 0


@dataclass(frozen=True)
class LaneEvidence:
    """The factors of lane_confidence, kept for the reasons."""

    confidence: float
    support_left: float
    support_right: float
    geometry: float
    agreement: float
    visibility: float


def agreement(measured: LaneLine | None, tracked: LaneLine | None, region: RoadRegion, lane_width_px: float) -> float:
    """1 when the detected boundary lies on the tracked one (mid and bottom rows), 0 at AGREEMENT_SCALE of a lane width apart."""
    if measured is None or tracked is None or lane_width_px <= 0:
        return 1.0
    rows = (0.5 * (region.top_v_px + region.bottom_v_px), region.bottom_v_px)  # the far end swings most in curves
    err = sum(abs(measured.u_at(v) - tracked.u_at(v)) for v in rows) / len(rows)
    return max(0.0, 1.0 - err / (AGREEMENT_SCALE * lane_width_px))


def lane_confidence(
    left: LaneLine | None, right: LaneLine | None, region: RoadRegion, agreement_left: float = 1.0, agreement_right: float = 1.0,
    occlusion: float = 0.0, clipped_share: float = 0.0,
) -> LaneEvidence:
    """Confidence 0..1 in the ego lane's boundaries, with its factors."""
    s_l = left.support if left is not None else 0.0
    s_r = right.support if right is not None else 0.0
    geometry = geometry_plausibility(left, right, region) if left is not None and right is not None else 1.0
    agree = min(agreement_left if left is not None else 1.0, agreement_right if right is not None else 1.0)
    visibility = _unit(1.0 - occlusion / OCCLUDED_BLIND) * _unit(1.0 - clipped_share / CLIPPED_BLIND)
    conf = 0.5 * (s_l + s_r) * geometry * agree * visibility
    return LaneEvidence(_unit(conf), s_l, s_r, geometry, agree, visibility)


def _unit(x: float) -> float:
    """x clamped to [0, 1]; NaN (unknown) counts as 0."""
    return float(min(1.0, max(0.0, x))) if x == x else 0.0
