"""One frame's cues read against a track profile: familiarity, and the light and the lane as this track has them.

Pure: the profile, the frame and the camera's own measurements in, the cues and the sentences behind them out.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from fearguard.track.features import as_bgr
from fearguard.track.floor import as_occlusion
from fearguard.track.profile import TrackProfile

LANE_SEEN = 0.5  # [0..1] median lane confidence on the recordings from which the camera's lane model sees this track
PARTLY_SEEN = 0.5  # [0..1] where it sees the track only partly (median above 0, below LANE_SEEN), a lane it loses reads
#                    no lower than this: the rule files' "medium" peak, whose fear (low) stays below caution on its own —
#                    on such a track the lane model also loses the lane on clean frames (on every development track it
#                    read 0 on at least a fifth of the recorded frames), so its loss is evidence, not proof


@dataclass(frozen=True)
class AsLearnt:
    """The cues a track changes, and why."""

    familiarity: float
    brightness: float
    lane_confidence: float
    occlusion: float
    facts: tuple[str, ...]


def read_as_learnt(profile: TrackProfile, frame: object, lane_confidence: float, brightness: float, occlusion: float,
                   normal_band: tuple[float, float], occlusion_calm: float) -> AsLearnt:
    """Familiarity of the frame; brightness with the learnt light band mapped onto the rule file's normal band; the lane
    confidence relative to what the camera's lane model reads on this track — or, where it did not see this track's
    guidance on most recorded frames, how like the learnt track the picture is, lowered where it saw the guidance partly
    and loses it now (``partly_seen_lane``; the camera's occlusion, measured over that model's marking region, then does
    not apply and reads 0); otherwise the occlusion relative to what normal driving on this track showed
    (``TrackProfile.occlusion_as_learnt``). With a floor model, the occlusion is at least the share of the usual floor
    hidden, read against the recordings (``floor_hidden``)."""
    fam, why = profile.familiarity(frame)
    facts = [why] if why else []
    lo, hi = profile.brightness_band
    b = profile.brightness_as_learnt(brightness, normal_band)
    if math.isfinite(brightness) and not lo <= brightness <= hi:
        side = "below" if brightness < lo else "above"
        facts.append(f"track: brightness {brightness:.0f} {side} the learnt band {lo:.0f}–{hi:.0f}: read as {b:.0f}")
    seen = profile.lane_confidence_median
    if not (math.isfinite(seen) and seen >= LANE_SEEN):
        saw = "saw this track's guidance only partly" if math.isfinite(seen) and seen > 0.0 else "did not see this track's guidance"
        facts.append(f"track: the camera's lane model {saw} on the recordings (median confidence {seen:.2f}): the lane cue "
                     f"reads how like the learnt track the picture is ({fam:.2f}); the camera's occlusion, measured over "
                     f"that model's marking region, does not apply")
        occ = floor_hidden(profile, frame, 0.0 if math.isfinite(fam) else fam, occlusion_calm, facts)
        return AsLearnt(fam, b, partly_seen_lane(seen, lane_confidence, fam, facts), occ, tuple(facts))
    lane = min(1.0, lane_confidence / seen) if math.isfinite(lane_confidence) else lane_confidence
    occ = profile.occlusion_as_learnt(occlusion, occlusion_calm)
    if math.isfinite(occlusion) and occ != occlusion:
        facts.append(f"track: occlusion {occlusion:.2f} read against {profile.occlusion_usual:.2f} in normal driving on the "
                     f"recordings: {occ:.2f}")
    return AsLearnt(fam, b, lane, floor_hidden(profile, frame, occ, occlusion_calm, facts), tuple(facts))


def partly_seen_lane(seen: float, lane_confidence: float, familiarity: float, facts: list[str]) -> float:
    """The lane cue where the lane model saw this track's guidance only partly on the recordings (median confidence
    ``seen`` above 0, below LANE_SEEN): the familiarity, or lower where this frame's lane reads below that median — from
    1 at the median down to PARTLY_SEEN at 0 (monotone: a lower confidence never raises it; unknown stays the worst).
    Where the lane model never saw the track (median 0) its reading tells nothing and the familiarity is the cue.
    Appends the sentence when the lane decides."""
    if not (math.isfinite(seen) and seen > 0.0):
        return familiarity
    if not math.isfinite(lane_confidence):
        facts.append("track: the lane confidence is unknown: read as the worst")
        return math.nan
    part = PARTLY_SEEN + (1.0 - PARTLY_SEEN) * min(1.0, max(lane_confidence, 0.0) / seen)
    if not part < familiarity:  # NaN familiarity (unknown) stays the worst
        return familiarity
    facts.append(f"track: lane confidence {lane_confidence:.2f} against the recordings' median {seen:.2f}: the lane cue reads "
                 f"{part:.2f} (a lane this model loses reads no lower than {PARTLY_SEEN:.2f})")
    return part


def floor_hidden(profile: TrackProfile, frame: object, occlusion: float, occlusion_calm: float, facts: list[str]) -> float:
    """The occlusion cue, at least the share of the usual floor this picture hides (read against the recordings'
    median); unknown (NaN, the worst) when the frame is not a picture. Appends the sentence when the floor decides."""
    floor = profile.floor
    if floor is None:
        return occlusion
    bgr = as_bgr(frame)
    if bgr is None:
        return math.nan
    hidden = floor.hidden(bgr)
    read = as_occlusion(hidden, floor.hidden_usual, occlusion_calm)
    if not read > occlusion:  # NaN occlusion (unknown) stays the worst
        return occlusion
    facts.append(f"track: {hidden:.2f} of the floor the recordings show ahead is hidden or unlike it (usually "
                 f"{floor.hidden_usual:.2f}): occlusion {read:.2f}")
    return read
