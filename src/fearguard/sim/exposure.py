"""What the camera does to a drawn frame: exposure (night, glare, tunnel exit) and sensor noise.

``lighting.py`` turns the scenario's zones into a ``LightState`` for one moment; this module applies it
to the painted frame in place: the tunnel (dark walls, the exit portal blown out), the night map (the
headlights' pool on the road, dark elsewhere), gain and offset (glare, wash-out), bloom near the low
sun, then zero-mean sensor noise cropped from one pre-drawn sheet at a random offset per frame.
Everything is a few cv2 calls on uint8 images; the maps are cached per strength.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from fearguard.sim.lighting import TUNNEL_INSIDE_GAIN, LightState
from fearguard.sim.projection import Pose, Projector, fill
from fearguard.sim.road import Road

NOISE_SHEET_PAD = 64  # [px] noise is cropped from a larger sheet at a random offset each frame
NIGHT_FLOOR = 0.07  # [-] brightness of the unlit night scene
HEADLIGHT_PEAK = 0.6  # [-] brightness of the headlights' pool on the road, relative to daylight
NIGHT_REACH = 6.0  # [mount heights] headlight pool: full light out to this ground range
HEADLIGHT_SPREAD_DEG = 28.0  # [deg] sigma of the headlights' horizontal spread
BLOOM_RADIUS = 0.45  # [-] of the image width
PORTAL_GAIN = 1.6  # [-] extra gain of the exit portal at full strength
PORTAL_OFFSET = 70.0  # [grey levels] added to the exit portal at full strength
PORTAL_WIDTH = 1.15  # [-] the portal is this much wider than the road edges
PORTAL_HEIGHT = 2.2  # [half road widths] height of the portal


class Exposure:
    """Exposure and noise of one camera over one road (the portal of a tunnel exit is placed on it)."""

    def __init__(self, projector: Projector, road: Road, edges_m: tuple[float, float], half_road_m: float,
                 scenery_rng: np.random.Generator, noise_rng: np.random.Generator) -> None:
        """``edges_m``: lateral offsets of the left and right road edges; ``scenery_rng`` draws the noise sheet once."""
        cam = projector.camera
        self.proj, self.road, self.camera = projector, road, cam
        self.w, self.h = cam.width_px, cam.height_px
        self._edges_m, self._half_road_m = edges_m, half_road_m
        self._rng = noise_rng
        self._noise_unit = scenery_rng.standard_normal((self.h + NOISE_SHEET_PAD, self.w + NOISE_SHEET_PAD)).astype(np.float32)
        self._noise: dict[float, tuple[np.ndarray, np.ndarray]] = {}
        self._night: dict[float, np.ndarray] = {}
        self._bloom = self._make_bloom(cam.horizon_v_px())

    def expose(self, frame: np.ndarray, pose: Pose, light: LightState) -> None:
        """Tunnel, night, gain/offset and bloom, in that order, in place."""
        if light.tunnel > 0:
            self._tunnel(frame, pose, light)
        if light.night > 0:
            cv2.multiply(frame, self._night_map(light.night), dst=frame, scale=1.0 / 255.0)
        if light.gain != 1.0 or light.offset != 0.0:
            cv2.convertScaleAbs(frame, dst=frame, alpha=light.gain, beta=light.offset)
        if light.bloom > 0:
            cv2.add(frame, cv2.convertScaleAbs(self._bloom, alpha=light.bloom), dst=frame)

    def add_noise(self, frame: np.ndarray, sigma: float) -> None:
        """Zero-mean sensor noise of ``sigma`` grey levels, in place (one draw of the noise generator per frame)."""
        if sigma <= 0:
            return
        pos, neg = self._noise_pair(sigma)
        du, dv = (int(k) for k in self._rng.integers(0, NOISE_SHEET_PAD, 2))
        cv2.add(frame, pos[dv : dv + self.h, du : du + self.w], dst=frame)
        cv2.subtract(frame, neg[dv : dv + self.h, du : du + self.w], dst=frame)

    def _make_bloom(self, horizon_v: float) -> np.ndarray:
        u0, v0 = 0.62 * self.w, horizon_v - 0.06 * self.h
        v, u = np.mgrid[0 : self.h, 0 : self.w].astype(np.float32)
        r = np.hypot(u - u0, v - v0) / (BLOOM_RADIUS * self.w)
        glow = 255.0 * np.exp(-(r**2) * 2.0)
        return np.repeat(glow[:, :, None], 3, axis=2).astype(np.uint8)

    def _noise_pair(self, sigma: float) -> tuple[np.ndarray, np.ndarray]:
        key = round(sigma, 1)
        if key not in self._noise:
            n = self._noise_unit * key
            pos = np.clip(n, 0, 255).astype(np.uint8)
            neg = np.clip(-n, 0, 255).astype(np.uint8)
            self._noise[key] = (np.repeat(pos[:, :, None], 3, axis=2), np.repeat(neg[:, :, None], 3, axis=2))
        return self._noise[key]

    def _night_map(self, strength: float) -> np.ndarray:
        key = round(strength, 2)
        if key not in self._night:
            cam = self.camera
            v, u = np.mgrid[0 : self.h, 0 : self.w].astype(np.float64)
            angle = math.radians(cam.pitch_deg) + np.arctan2(v - cam.cy_px, cam.fy_px)
            h = cam.mount_height_m or 1.0
            ground = np.where(angle > 1e-3, h / np.tan(np.maximum(angle, 1e-3)), np.inf)
            reach = NIGHT_REACH * h
            pool = np.minimum(1.0, (reach / ground) ** 2)
            bearing = np.degrees(np.arctan2(u - cam.cx_px, cam.fx_px))
            pool *= np.exp(-0.5 * (bearing / HEADLIGHT_SPREAD_DEG) ** 2)
            lit = NIGHT_FLOOR + (HEADLIGHT_PEAK - NIGHT_FLOOR) * pool
            gain = 1.0 - key * (1.0 - lit)
            self._night[key] = np.repeat((255.0 * gain)[:, :, None], 3, axis=2).astype(np.uint8)
        return self._night[key]

    def _tunnel(self, frame: np.ndarray, pose: Pose, light: LightState) -> None:
        """Inside a tunnel: everything dark except the exit portal, which is blown out."""
        k = light.tunnel
        dark = cv2.convertScaleAbs(frame, alpha=1.0 - k * (1.0 - TUNNEL_INSIDE_GAIN))
        if light.portal_s_m is None:
            frame[:] = dark
            return
        x, y, h = self.road.pose_at(light.portal_s_m)
        nx, ny = -math.sin(float(h)), math.cos(float(h))
        left, right = self._edges_m
        lat = np.array([left, right, right, left]) * PORTAL_WIDTH
        height = PORTAL_HEIGHT * self._half_road_m
        quad = self.proj.to_camera(pose, float(x) + lat * nx, float(y) + lat * ny, np.array([height, height, 0.0, 0.0]))
        mask = np.zeros((self.h, self.w), np.uint8)
        fill(mask, self.proj.polys_px(quad[None]), 255)
        bright = cv2.convertScaleAbs(frame, alpha=1.0 + PORTAL_GAIN * k, beta=PORTAL_OFFSET * k)
        cv2.copyTo(bright, mask, dark)
        frame[:] = dark
