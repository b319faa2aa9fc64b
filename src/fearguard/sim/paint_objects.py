"""Boxes and QR boards in the camera frame: cars and obstacles as shaded boxes, boards as warped codes.

Drawn from far to near so the nearer hides the farther: a box is its visible faces (back-face culled,
shaded per face), a ground shadow and, for a car, a dark underside, a rear window and two tail lights
(returned as emissive polygons: the renderer relights them after a night or tunnel exposure); a board
is the encoder's image warped onto its projected quad on a post, and counts as readable (ground truth
``qr_visible``) when whole in the frame and sharp enough. All projection goes through ``Projector``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import cv2
import numpy as np

from fearguard.sim.boxes import Box
from fearguard.sim.projection import SHIFT, Pose, Projector, fill
from fearguard.sim.qr import QrBoard, board_image, modules_across

CAR_SHADOW_BGR = (28, 28, 30)
UNDERSIDE_BGR = (32, 32, 34)
GLASS_BGR = (62, 52, 46)
TAIL_LIGHT_BGR = (30, 22, 235)  # brighter and purer than a red body (40, 40, 185)
POST_BGR = (70, 70, 72)
BOX_BGR = {
    "red": (40, 40, 185), "blue": (150, 70, 30), "white": (225, 225, 225), "black": (40, 40, 40), "silver": (175, 175, 170),
    "green": (60, 130, 40), "yellow": (40, 200, 220), "orange": (30, 120, 235), "grey": (120, 120, 120),
}
FACE_SHADE = (1.0, 1.0, 0.72, 0.72, 1.15)  # rear, front, right, left, top
# box corners: index = 4·ix + 2·iy + iz (ix 0 rear / 1 front, iy 0 right / 1 left, iz 0 bottom / 1 top)
FACES = ((0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (1, 3, 7, 5))
FACE_NORMALS = np.array([(-1, 0, 0), (1, 0, 0), (0, -1, 0), (0, 1, 0), (0, 0, 1)], dtype=float)
_FACE_INDEX = np.array(FACES)
_CORNER_X = np.repeat([-0.5, 0.5], 4)  # × length
_CORNER_Y = np.tile(np.repeat([-0.5, 0.5], 2), 2)  # × width
_CORNER_Z = np.tile([0.0, 1.0], 4)  # × height
# rear-face details as (a across from right to left, b up) rectangles: underside band, window, two tail lights
_DETAILS = ((0.0, 1.0, 0.0, 0.2), (0.1, 0.9, 0.62, 0.94), (0.04, 0.2, 0.38, 0.54), (0.8, 0.96, 0.38, 0.54))
_DETAIL_A = np.array([[a0, a1, a1, a0] for a0, a1, _, _ in _DETAILS])
_DETAIL_B = np.array([[b0, b0, b1, b1] for _, _, b0, b1 in _DETAILS])
_SHADOW_X = np.array([-0.5, 0.5, 0.5, -0.5])  # × length
_SHADOW_Y = np.array([-0.5, -0.5, 0.5, 0.5])  # × width
CAR_SHADOW_GROWTH = 1.12  # [-] ground shadow / footprint size
QR_MIN_PX_PER_MODULE = 2.5  # [px] a board at least this sharp counts as readable (qr_visible)
QR_MIP_LEVELS = (1, 2, 4, 8)  # [px per module] board images kept at these sharpnesses
QR_CODE_SHARE = 0.8  # [-] the code's share of the board side (inside the quiet zone and frame)


class ObjectPainter:
    """Paints the boxes and boards in view of one camera (the boards of the scenario, placed once)."""

    def __init__(self, projector: Projector, boards: tuple[QrBoard, ...]) -> None:
        self.proj, self._boards = projector, boards
        self.w, self.h = projector.camera.width_px, projector.camera.height_px
        self._face_colours = {name: [tuple(int(v) for v in np.clip(np.array(bgr) * k, 0, 255)) for k in FACE_SHADE]
                              for name, bgr in BOX_BGR.items()}

    def draw(self, frame: np.ndarray, pose: Pose, boxes: Sequence[Box], boards: np.ndarray,
                      board_geo: tuple[np.ndarray, np.ndarray, np.ndarray], emissive: list[np.ndarray]) -> list[str]:
        """Boxes and boards from far to near; returns the readable boards' payloads."""
        cx, cy, _ = pose
        order: list[tuple[float, int, int]] = []  # (distance, kind 0 box / 1 board, index)
        box_polys = self._box_polys(pose, boxes) if boxes else None
        for i, b in enumerate(boxes):
            order.append((math.hypot(b.x_m - cx, b.y_m - cy), 0, i))
        board_polys = self._board_polys(pose, boards, board_geo) if len(boards) else None
        if board_polys is not None:
            for j in range(len(boards)):
                order.append((math.hypot(float(board_polys[0][j][0]) - cx, float(board_polys[0][j][1]) - cy), 1, j))
        order.sort(key=lambda item: -item[0])
        visible: list[str] = []
        for _, kind, i in order:
            if kind == 0 and box_polys is not None:
                self._box(frame, boxes[i], i, box_polys, emissive)
            elif board_polys is not None:
                board = self._boards[int(boards[i])]
                if self._board(frame, board, board_polys[1][i], board_polys[2][i], board_polys[3][i]):
                    visible.append(board.payload)
        return sorted(visible)

    def _box_polys(self, pose: Pose, boxes: Sequence[Box]) -> tuple[list, np.ndarray, int]:
        """Every box's faces (5), rear details (4) and ground shadow (1), projected in one batch; face visibility."""
        b = len(boxes)
        bx, by, yaw, length, width, height = (np.array(v, dtype=float) for v in zip(
            *[(o.x_m, o.y_m, o.yaw_rad, o.length_m, o.width_m, o.height_m) for o in boxes], strict=True))
        c, s = np.cos(yaw)[:, None], np.sin(yaw)[:, None]
        lx, ly = _CORNER_X[None] * length[:, None], _CORNER_Y[None] * width[:, None]
        corners = self.proj.to_camera(pose, bx[:, None] + lx * c - ly * s, by[:, None] + lx * s + ly * c, _CORNER_Z[None] * height[:, None])
        faces = corners[:, _FACE_INDEX]  # (B, 5, 4, 3)
        rel = yaw - pose[2]
        rc, rs = np.cos(rel)[:, None], np.sin(rel)[:, None]
        normals = np.stack([FACE_NORMALS[None, :, 0] * rc - FACE_NORMALS[None, :, 1] * rs,
                            FACE_NORMALS[None, :, 0] * rs + FACE_NORMALS[None, :, 1] * rc,
                            np.broadcast_to(FACE_NORMALS[None, :, 2], (b, 5))], axis=-1)
        visible = (normals * faces.mean(axis=2)).sum(axis=-1) < 0.0  # (B, 5)
        rear = faces[:, 0]  # BR, BL, TL, TR
        br, bl, tr = rear[:, None, None, 0], rear[:, None, None, 1], rear[:, None, None, 3]
        details = br + _DETAIL_A[None, :, :, None] * (bl - br) + _DETAIL_B[None, :, :, None] * (tr - br)  # (B, 4, 4, 3)
        grow = np.where([o.is_vehicle for o in boxes], CAR_SHADOW_GROWTH, 1.05)[:, None]
        sx, sy = _SHADOW_X[None] * length[:, None] * grow, _SHADOW_Y[None] * width[:, None] * grow
        shadow = self.proj.to_camera(pose, bx[:, None] + sx * c - sy * s, by[:, None] + sx * s + sy * c, 0.0)  # (B, 4, 3)
        polys = self.proj.polys_px(np.concatenate([faces.reshape(-1, 4, 3), details.reshape(-1, 4, 3), shadow]))
        return polys, visible, b

    def _box(self, frame: np.ndarray, box: Box, i: int, batch: tuple[list, np.ndarray, int], emissive: list[np.ndarray]) -> None:
        polys, visible, b = batch
        fill(frame, [polys[9 * b + i]], CAR_SHADOW_BGR)
        colours = self._face_colours[box.colour]
        for f in range(5):
            if visible[i, f]:
                fill(frame, [polys[5 * i + f]], colours[f])
        if box.is_vehicle and visible[i, 0]:
            base = 5 * b + 4 * i
            fill(frame, [polys[base]], UNDERSIDE_BGR)
            fill(frame, [polys[base + 1]], GLASS_BGR)
            lights = [p for p in polys[base + 2 : base + 4] if p is not None]
            fill(frame, lights, TAIL_LIGHT_BGR)
            emissive.extend(lights)

    def _board_polys(self, pose: Pose, boards: np.ndarray,
                     geo: tuple[np.ndarray, np.ndarray, np.ndarray]) -> tuple[np.ndarray, list, list, np.ndarray]:
        """Board centres (world), board quads (TL, TR, BR, BL as seen by the car), posts, and which face the car."""
        x, y, h = geo
        lateral = np.array([self._boards[k].lateral_m for k in boards])
        size = np.array([self._boards[k].size_m for k in boards])
        elev = np.array([self._boards[k].elevation_m for k in boards])
        nx, ny = -np.sin(h)[:, None], np.cos(h)[:, None]
        lat = lateral[:, None] + size[:, None] * np.array([[0.5, -0.5, -0.5, 0.5]])
        z = elev[:, None] + size[:, None] * np.array([[1.0, 1.0, 0.0, 0.0]])
        quad = self.proj.to_camera(pose, x[:, None] + lat * nx, y[:, None] + lat * ny, z)  # (K, 4, 3)
        post_lat = lateral[:, None] + size[:, None] * np.array([[0.04, -0.04, -0.04, 0.04]])
        post_z = elev[:, None] * np.array([[1.0, 1.0, 0.0, 0.0]])
        post = self.proj.to_camera(pose, x[:, None] + post_lat * nx, y[:, None] + post_lat * ny, post_z)
        facing = (np.cross(quad[:, 1] - quad[:, 0], quad[:, 3] - quad[:, 0]) * quad.mean(axis=1)).sum(axis=-1) > 0
        whole = (self.proj.depth(quad) >= self.proj.near_m).all(axis=1) & facing
        polys = self.proj.polys_px(np.concatenate([quad, post]))
        k = len(boards)
        centres = np.column_stack([x - lateral * np.sin(h), y + lateral * np.cos(h)])
        return centres, [polys[j] if whole[j] else None for j in range(k)], polys[k:], elev > 0

    def _board(self, frame: np.ndarray, board: QrBoard, quad_px: np.ndarray | None, post_px: np.ndarray | None,
                    has_post: bool) -> bool:
        """Draw one QR board (and its post); True when it is sharp and whole enough to read."""
        if quad_px is None:
            return False
        if has_post:
            fill(frame, [post_px], POST_BGR)
        dst = quad_px.astype(np.float32) / (1 << SHIFT)
        lo = np.floor(dst.min(axis=0)).astype(int)
        hi = np.ceil(dst.max(axis=0)).astype(int) + 1
        x0, y0, x1, y1 = max(lo[0], 0), max(lo[1], 0), min(hi[0], self.w), min(hi[1], self.h)
        if x1 <= x0 or y1 <= y0:
            return False
        side_px = float(np.linalg.norm(dst - np.roll(dst, -1, axis=0), axis=1).min())
        modules = modules_across(board.payload)
        if side_px < modules:  # under a pixel per module: the code is a grey blur inside a white frame
            cv2.fillConvexPoly(frame, quad_px, (235, 235, 235), cv2.LINE_8, SHIFT)
            centre = quad_px.mean(axis=0)
            inner = np.rint(centre + (quad_px - centre) * QR_CODE_SHARE).astype(np.int32)
            cv2.fillConvexPoly(frame, inner, (140, 140, 140), cv2.LINE_8, SHIFT)
            return False
        level = next((k for k in QR_MIP_LEVELS if k * modules >= side_px), QR_MIP_LEVELS[-1])
        image = board_image(board.payload, level)
        n = float(image.shape[0])
        src = np.array([[0, 0], [n, 0], [n, n], [0, n]], np.float32)
        matrix = cv2.getPerspectiveTransform(src, dst - np.array([x0, y0], np.float32))
        cv2.warpPerspective(image, matrix, (x1 - x0, y1 - y0), dst=frame[y0:y1, x0:x1], flags=cv2.INTER_LINEAR,
                            borderMode=cv2.BORDER_TRANSPARENT)
        inside = bool((lo >= 0).all() and hi[0] <= self.w and hi[1] <= self.h)
        return inside and side_px >= QR_MIN_PX_PER_MODULE * modules
