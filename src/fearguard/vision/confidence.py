"""lane_confidence from evidence: both boundaries, their support, plausible geometry, agreement over time.

    confidence = mean(support_left, support_right) × geometry × agreement × visibility

(a track whose guidance is one line — a centre line, one edge: ``lane.GUIDANCE`` — counts its best line's support
instead of the mean, and no pair geometry). A side not found contributes 0 support, so one boundary alone gives at
most 0.5; a side found counts the support its track
holds (``held``: the best of its last SUPPORT_HOLD_S, so a dashed line does not flicker as its dashes pass) in a clean
picture, where a weaker line is sparser paint, not paint the noise hid. ``geometry`` is 1 when the
lane width at the region's middle row and the vanishing point are plausible for a forward camera, falling linearly
to 0 outside; ``agreement`` (1 without history) compares the detection with the tracked estimate.
``visibility`` = (1 − hidden / OCCLUDED_BLIND) × (1 − clipped share / CLIPPED_BLIND)
× (1 − NOISE_WEIGHT · (1 − min(1, S/N / SNR_ACCEPTABLE))), hidden being the share of both boundaries' expected
samples hidden (``occlusion.HiddenMarkings.share``, or the lane hidden beyond an object): a boundary found on the
visible part of the road says nothing about the hidden part, clipped (saturated or black) pixels carry no information
at all, and a picture whose noise is a large share of its signal (night: dark and noisy) supports what it shows less —
so washed-out, dark, noisy and hidden markings all lower the confidence, while dim light with a clean picture (deep
shade by day) does not.
"""

from __future__ import annotations

from dataclasses import dataclass

from fearguard.vision.lanes import LaneLine, RoadRegion, geometry_plausibility, vanishing_point  # noqa: F401

CLIPPED_BLIND = 0.5  # [-] share of clipped road pixels at which the picture counts as blind
OCCLUDED_BLIND = 0.8  # [-] occlusion at which the visible rest of the markings no longer vouches for the lane
SNR_ACCEPTABLE = 10.0  # [-] road S/N (mean grey / noise σ) from which the picture counts as fully usable (ISO 12232: "acceptable")
NOISE_WEIGHT = 0.5  # [-] share of the confidence a picture of pure noise loses by its noise alone (noise blurs what it shows; darkness,
#                     clipping and garbage hide it, and are counted by the other factors)
EVIDENCE_SPREAD = 2.0  # [-] standard deviations of a detection's ridge rows about their mean: the span it is seen over (uniform
#                        rows over a span reach ±1.73 of them)
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
    frame_support: float | None = None  # [0..1] the best side's support in this frame alone (None: the supports above are)
    guidance: str = "two_lines"  # what the confidence measured (lane.GUIDANCE): both boundaries, or one line

    @property
    def guide(self) -> float:
        """How well the best boundary found this frame can steer, whatever the rest of the picture shows: its support ×
        geometry × agreement, the visibility left out. A washed-out or half-hidden picture is not trusted (the confidence
        says so), but a line still found on its readable part, where the track expected it, still says where the lane
        runs: low sun over a model-car track left the solid left line at support 0.42, agreement 1.00, confidence 0.01.
        The support is this frame's own (not what the track holds), of a side whose track once was a side of a lane seen
        well (``paired``): a seam or a verge's edge that was never one guides nothing."""
        best = max(self.support_left, self.support_right) if self.frame_support is None else self.frame_support
        return _unit(best * self.geometry * self.agreement)

    def as_guidance(self, guidance: str) -> float:
        """The confidence these factors give for a track guided by ``guidance`` (``lane.GUIDANCE``); one line has no pair
        geometry (a two-lines reading of a one-line evidence keeps geometry 1: it was not measured)."""
        return _combine(self.support_left, self.support_right, self.geometry, self.agreement, self.visibility, guidance)


def seen_rows(line: LaneLine) -> tuple[float, float] | None:
    """The image rows a detection was seen over: its ridge rows' mean ± EVIDENCE_SPREAD standard deviations (None: not
    known). The agreement compares there, and the lane tracker measures there (``lane_tracker.seen_span``)."""
    if line.rows is None:
        return None
    return (line.rows.mean_v_px - EVIDENCE_SPREAD * line.rows.std_v_px,
            line.rows.mean_v_px + EVIDENCE_SPREAD * line.rows.std_v_px)


def agreement(measured: LaneLine | None, tracked: LaneLine | None, region: RoadRegion, lane_width_px: float) -> float:
    """1 when the detected boundary lies on the tracked one (mid and bottom rows), 0 at AGREEMENT_SCALE of a lane width apart.

    Each row is taken within the span the detection's ridges cover (its rows' mean ± EVIDENCE_SPREAD standard deviations):
    a line through one far dash is compared where the dash is, not where it is extrapolated to."""
    if measured is None or tracked is None or lane_width_px <= 0:
        return 1.0
    rows = (0.5 * (region.top_v_px + region.bottom_v_px), float(region.bottom_v_px))  # the far end swings most in curves
    seen = seen_rows(measured)
    if seen is not None:
        rows = tuple(min(seen[1], max(seen[0], v)) for v in rows)
    err = sum(abs(measured.u_at(v) - tracked.u_at(v)) for v in rows) / len(rows)
    return max(0.0, 1.0 - err / (AGREEMENT_SCALE * lane_width_px))


def lane_confidence(
    left: LaneLine | None, right: LaneLine | None, region: RoadRegion, agreement_left: float = 1.0, agreement_right: float = 1.0,
    occlusion: float = 0.0, clipped_share: float = 0.0, signal_to_noise: float = float("inf"), *, geometry: float | None = None,
    out_of_view: tuple[bool, bool] = (False, False), held: tuple[float, float] | None = None,
    paired: tuple[bool, bool] = (True, True), guidance: str = "two_lines",
) -> LaneEvidence:
    """Confidence 0..1 in the ego lane's boundaries, with its factors. ``geometry``: the plausibility of the pair when
    the caller measured it in the ground plane (a bending lane, ``ground_lanes``), instead of the image lines'.
    ``out_of_view``: a missing side that the lane model places outside the picture (the inner line of a tight curve)
    is not missing evidence — the seen side's support stands for both. ``guidance``: a track guided by one line
    (``lane.GUIDANCE``: a centre line, one edge) is seen when its best line is: that line's support, no pair geometry."""
    s_l = left.support if left is not None else 0.0
    s_r = right.support if right is not None else 0.0
    frame_support = max(s_l if paired[0] else 0.0, s_r if paired[1] else 0.0)  # the guide's: this frame's, lane sides only
    if held is not None:  # the supports the boundaries' tracks hold (a dashed line between two dashes), in a clean picture
        share = _unit(2.0 * signal_to_noise / SNR_ACCEPTABLE - 1.0)
        s_l = max(s_l, share * held[0]) if left is not None else s_l
        s_r = max(s_r, share * held[1]) if right is not None else s_r
    if left is None and out_of_view[0]:
        s_l = s_r
    if right is None and out_of_view[1]:
        s_r = s_l
    one_line = guidance != "two_lines"
    if one_line:
        geometry = 1.0  # one line has no pair to be plausible as
    elif geometry is None:
        geometry = geometry_plausibility(left, right, region) if left is not None and right is not None else 1.0
    agree = min(agreement_left if left is not None else 1.0, agreement_right if right is not None else 1.0)
    visibility = _unit(1.0 - occlusion / OCCLUDED_BLIND) * _unit(1.0 - clipped_share / CLIPPED_BLIND)
    visibility *= 1.0 - NOISE_WEIGHT * (1.0 - _unit(signal_to_noise / SNR_ACCEPTABLE))
    conf = _combine(s_l, s_r, geometry, agree, visibility, guidance)
    return LaneEvidence(conf, s_l, s_r, geometry, agree, visibility, _unit(frame_support), guidance)


def _combine(s_l: float, s_r: float, geometry: float, agree: float, visibility: float, guidance: str) -> float:
    """The confidence from its factors: the sides' mean support, or one line's (its best), × the rest."""
    support = 0.5 * (s_l + s_r) if guidance == "two_lines" else max(s_l, s_r)
    return _unit(support * (geometry if guidance == "two_lines" else 1.0) * agree * visibility)


def _unit(x: float) -> float:
    """x clamped to [0, 1]; NaN (unknown) counts as 0."""
    return float(min(1.0, max(0.0, x))) if x == x else 0.0
