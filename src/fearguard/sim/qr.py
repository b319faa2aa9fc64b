"""QR boards beside the route: where they stand, what they say, and their image (cv2.QRCodeEncoder).

Payload: ``FG1;route=<route>;sector=<i>;pos_m=<s with 1 decimal>`` where i is the board's index in its
group and s its distance along the route. A board stands upright beside the road, facing the
oncoming car, its near edge ``offset_m`` beyond the outermost lane on its side.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import cv2
import numpy as np

from fearguard.sim.scenario_values import QrBoardGroup, RoadSpec

BOARD_MARGIN = 0.03  # [-] white frame around the code (beyond its quiet zone), share of the board side


@dataclass(frozen=True)
class QrBoard:
    index: int
    s_m: float  # along the route
    lateral_m: float  # board centre, + = left
    size_m: float
    elevation_m: float  # bottom edge above the ground
    payload: str


def payload(route: str, index: int, pos_m: float) -> str:
    """The text a board encodes."""
    return f"FG1;route={route};sector={index};pos_m={pos_m:.1f}"


def place_boards(group: QrBoardGroup, road: RoadSpec) -> tuple[QrBoard, ...]:
    """The boards of a group that are there (``missing`` ones left out)."""
    lanes = road.lanes_left if group.side == "left" else road.lanes_right
    edge = road.lane_width_m / 2 + lanes * road.lane_width_m + road.shoulder_m
    lateral = (edge + group.offset_m + group.size_m / 2) * (1.0 if group.side == "left" else -1.0)
    boards = []
    for i in range(group.count):
        if i in group.missing:
            continue
        s = group.start_m + i * group.spacing_m
        boards.append(QrBoard(i, s, lateral, group.size_m, group.elevation_m, payload(group.route, i, s)))
    return tuple(boards)


@lru_cache(maxsize=2048)
def board_image(text: str, px_per_module: int = 8) -> np.ndarray:
    """The board face (BGR uint8, square, read-only): the QR code with a white frame, at a given sharpness.

    The renderer picks the level nearest above the board's on-screen size (a mipmap): warping a much
    larger image down with linear interpolation would alias the modules into noise.
    """
    params = cv2.QRCodeEncoder_Params()
    params.correction_level = cv2.QRCodeEncoder_CORRECT_LEVEL_L  # smallest version: biggest modules on the board
    code = cv2.QRCodeEncoder.create(params).encode(text)
    pad = _frame_modules(code.shape[0])
    code = cv2.copyMakeBorder(code, pad, pad, pad, pad, cv2.BORDER_CONSTANT, value=255)
    big = cv2.resize(code, None, fx=px_per_module, fy=px_per_module, interpolation=cv2.INTER_NEAREST)
    image = cv2.cvtColor(big, cv2.COLOR_GRAY2BGR)
    image.flags.writeable = False  # shared by the cache
    return image


def _frame_modules(side: int) -> int:
    return max(1, round(side * BOARD_MARGIN / (1 - 2 * BOARD_MARGIN)))


@lru_cache(maxsize=512)
def modules_across(text: str) -> int:
    """Modules across the whole board image (code + quiet zone + frame), for a decodability estimate."""
    params = cv2.QRCodeEncoder_Params()
    params.correction_level = cv2.QRCodeEncoder_CORRECT_LEVEL_L
    side = cv2.QRCodeEncoder.create(params).encode(text).shape[0]
    return side + 2 * _frame_modules(side)
