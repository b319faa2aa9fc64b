"""Lighting zones → what the camera's exposure does to one frame (a pure function of s and t).

Effects (each scaled by the zone's strength k in 0..1):
- night: a dark scene lit only by the headlights' pool near the car, and more sensor noise;
- glare: over-exposure (gain and offset, so bright paint clips to the same white as the road) and a
  bloom near the horizon where the low sun is;
- tunnel_exit: the first TUNNEL_PORTAL_AT of the zone is inside a tunnel (dark walls, the exit a blown-out
  hole); after the exit the image is washed out and recovers as auto-exposure adapts;
- shadows: tree shadows on the ground (blobs placed once per zone, seeded), drawn by the renderer;
- normal: no effect (documents a stretch of ordinary light).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from fearguard.sim.scenario_values import LightingZone

BASE_NOISE_SIGMA = 2.0  # [grey levels] sensor noise in daylight
NIGHT_NOISE_SIGMA = 6.0  # [grey levels] extra noise at full night (high gain)
GLARE_GAIN = 0.7  # [-] extra exposure gain at full glare (asphalt ~230, paint clipped at 255: contrast ~20)
GLARE_OFFSET = 50.0  # [grey levels] added at full glare (veiling glare)
TUNNEL_PORTAL_AT = 0.4  # [-] share of a tunnel_exit zone spent inside the tunnel
TUNNEL_INSIDE_GAIN = 0.3  # [-] brightness of the tunnel interior
WASHOUT_GAIN = 1.6  # [-] extra gain just after the exit
WASHOUT_OFFSET = 60.0  # [grey levels] added just after the exit
WASHOUT_DECAY = 0.15  # [-] share of the zone over which the wash-out decays by 1/e


@dataclass(frozen=True)
class LightState:
    """Exposure of one frame: out = in·gain + offset, plus the effects the renderer draws."""

    gain: float = 1.0
    offset: float = 0.0
    bloom: float = 0.0  # [0..1] glare bloom near the horizon
    night: float = 0.0  # [0..1] darkness outside the headlight pool
    tunnel: float = 0.0  # [0..1] inside a tunnel: walls dark, exit portal blown out
    portal_s_m: float | None = None  # where the tunnel exit is (distance-based zones)
    noise_sigma: float = BASE_NOISE_SIGMA
    shadow_zones: tuple[int, ...] = ()  # indices of the active shadows zones


def light_at(zones: Sequence[LightingZone], s_m: float, t_s: float) -> LightState:
    """The combined effect of every zone active at distance s and time t."""
    gain, offset, bloom, night, tunnel, portal, sigma, shadows = 1.0, 0.0, 0.0, 0.0, 0.0, None, BASE_NOISE_SIGMA, []
    for i, z in enumerate(zones):
        if not z.active(s_m, t_s):
            continue
        k = z.strength
        if z.kind == "night":
            night = max(night, k)
            sigma = max(sigma, BASE_NOISE_SIGMA + NIGHT_NOISE_SIGMA * k)
        elif z.kind == "glare":
            gain *= 1.0 + GLARE_GAIN * k
            offset += GLARE_OFFSET * k
            bloom = max(bloom, k)
        elif z.kind == "tunnel_exit":
            p = z.progress(s_m, t_s)
            if p < TUNNEL_PORTAL_AT:
                tunnel = max(tunnel, k)
                if z.from_m is not None and z.to_m is not None:
                    portal = z.from_m + TUNNEL_PORTAL_AT * (z.to_m - z.from_m)
                sigma = max(sigma, BASE_NOISE_SIGMA + 0.5 * NIGHT_NOISE_SIGMA * k)
            else:
                e = math.exp(-(p - TUNNEL_PORTAL_AT) / WASHOUT_DECAY)
                gain *= 1.0 + WASHOUT_GAIN * k * e
                offset += WASHOUT_OFFSET * k * e
        elif z.kind == "shadows":
            shadows.append(i)
    return LightState(gain, offset, bloom, night, tunnel, portal, sigma, tuple(shadows))
