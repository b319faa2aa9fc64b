"""Renderer: things appear where the camera model projects them; lighting and camera faults do what they say."""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from tests.scenario_text import scenario_from

from fearguard.camera import CameraModel
from fearguard.sim.projection import clip_near as _clip_near
from fearguard.sim.scenario import Scenario
from fearguard.sim.world import World

ROAD = """
[road]
left_marking = "solid"
right_marking = "dashed"
right_colour = "yellow"
[[road.segments]]
kind = "straight"
length_m = 20.0
"""


def scenario(tmp_path: Path, body: str = "", head: str = "") -> Scenario:
    return scenario_from(tmp_path, head, ROAD, body, "r.toml")


def pixel_of(world: World, s_m: float, lateral_m: float, up_m: float = 0.0) -> tuple[int, int]:
    """Image (u, v) of a road point (route s, lateral, height) seen from the world's camera now."""
    cx, cy, yaw = world.camera_pose()
    x, y = world.road.point_at(s_m, lateral_m)
    dx, dy = float(x) - cx, float(y) - cy
    fwd, left = dx * math.cos(yaw) + dy * math.sin(yaw), -dx * math.sin(yaw) + dy * math.cos(yaw)
    u, v, front = world.camera.project_points(np.array([fwd]), np.array([left]), np.array([up_m - world.camera.mount_height_m]))
    assert front[0]
    return round(float(u[0])), round(float(v[0]))


def grey_at(frame: np.ndarray, uv: tuple[int, int]) -> float:
    u, v = uv
    return float(cv2.cvtColor(frame[v - 1 : v + 2, u - 1 : u + 2], cv2.COLOR_BGR2GRAY).mean())


@given(st.floats(0.3, 8.0), st.floats(-1.0, 1.0))
def test_projection_agrees_with_the_camera_models_range_and_bearing(ahead_m: float, left_share: float) -> None:
    # render's projection must agree with what perception inverts: ground_range_m, bearing_deg, horizon_v_px
    height, pitch = 0.15, math.radians(13.0)
    cam = CameraModel.default(320, 240, 62.2, height, 13.0)
    left = left_share * ahead_m * 0.5
    u, v, front = cam.project_points(np.array([ahead_m]), np.array([left]), np.array([-height]))
    assert front[0]
    assert cam.ground_range_m(float(v[0])) == pytest.approx(ahead_m, rel=1e-9)
    depth = ahead_m * math.cos(pitch) + height * math.sin(pitch)
    assert cam.bearing_deg(float(u[0])) == pytest.approx(math.degrees(math.atan2(left, depth)))
    _, far_v, _ = cam.project_points(np.array([1e6]), np.array([0.0]), np.array([-height]))
    assert float(far_v[0]) == pytest.approx(cam.horizon_v_px(), abs=1e-3)


def test_markings_are_drawn_where_the_camera_model_projects_them(tmp_path: Path) -> None:
    sc = scenario(tmp_path)
    world = World(sc)
    frame = world.sense().frame_bgr
    half = sc.road.lane_width_m / 2
    white = grey_at(frame, pixel_of(world, 1.8, half))
    asphalt = grey_at(frame, pixel_of(world, 1.8, 0.0))
    verge = pixel_of(world, 1.8, half + 0.25)
    assert white > 190 and 80 < asphalt < 130
    assert white - asphalt > 60  # a marking is a bright line on darker road, as a Hough detector expects
    # the dashed yellow line: s in [0.9, 1.2] is paint, [1.2, 1.8] is a gap (0.3 m dashes, 0.6 m gaps)
    dash = frame[pixel_of(world, 1.05, -half)[1], pixel_of(world, 1.05, -half)[0]].astype(int)
    gap = grey_at(frame, pixel_of(world, 1.5, -half))
    b, g, r = dash
    assert r > 180 and g > 140 and b < 100  # yellow paint
    assert 80 < gap < 130
    b, g, r = frame[verge[1], verge[0]].astype(int)
    assert g > r and g > b  # grass beside the road


def test_a_vehicle_ahead_appears_as_a_box_at_its_projected_place(tmp_path: Path) -> None:
    sc = scenario(tmp_path, '[[vehicles]]\nstart_gap_m = 1.2\nspeed_mps = 1.5\ncolour = "blue"\n')
    world = World(sc)
    frame = world.sense().frame_bgr
    car = sc.vehicles[0]
    rear_s = car.start_s_m - car.length_m / 2
    b, g, r = frame[pixel_of(world, rear_s, 0.0, car.height_m * 0.5)[::-1]].astype(int)
    assert b > g + 40 and b > r + 60  # the blue body
    u, v = pixel_of(world, rear_s, 0.0, car.height_m * 0.05)
    assert grey_at(frame, (u, v)) < 60  # dark underside at the bottom of the rear face
    b, g, r = frame[pixel_of(world, rear_s, 0.0, car.height_m * 1.6)[::-1]].astype(int)
    assert not (b > g + 40 and b > r + 60)  # nothing blue above the roof
    lights = frame[pixel_of(world, rear_s, car.width_m * 0.38, car.height_m * 0.46)[::-1]].astype(int)
    assert lights[2] > lights[0] + 80  # a red tail light on the left of the rear face
    assert world.truth().lead_visible


def test_night_is_darker_and_glare_brighter(tmp_path: Path) -> None:
    day = World(scenario(tmp_path)).sense().frame_bgr
    night = World(scenario(tmp_path, '[[lighting]]\nkind = "night"\n')).sense().frame_bgr
    glare = World(scenario(tmp_path, '[[lighting]]\nkind = "glare"\nstrength = 0.8\n')).sense().frame_bgr
    road = slice(140, 240)
    means = [float(cv2.cvtColor(f[road], cv2.COLOR_BGR2GRAY).mean()) for f in (night, day, glare)]
    assert means[0] < 0.7 * means[1] < means[1] < means[2]
    assert means[2] > 190
    top = [float(f[:40].mean()) for f in (night, day)]
    assert top[0] < 40 < top[1]  # a night sky is dark


def test_zones_over_distance_switch_on_along_the_route(tmp_path: Path) -> None:
    sc = scenario(tmp_path, '[[lighting]]\nkind = "glare"\nfrom_m = 1.0\nto_m = 2.0\n')
    world = World(sc)
    before = world.sense().frame_bgr.mean()
    for _ in range(20):  # 1.5 m later the camera (0.25 m ahead of the axle) is inside the zone
        world.advance(0.0, 1.5)
    assert world.sense().frame_bgr.mean() > before + 40


def test_tree_shadows_darken_the_road(tmp_path: Path) -> None:
    plain = World(scenario(tmp_path)).sense().frame_bgr
    shaded = World(scenario(tmp_path, '[[lighting]]\nkind = "shadows"\ndensity = 0.6\n')).sense().frame_bgr
    road = slice(150, 240)
    assert shaded[road].mean() < plain[road].mean() - 10


def test_black_and_frozen_camera_faults(tmp_path: Path) -> None:
    world = World(scenario(tmp_path, "[faults.camera]\nblack = [[0.0, 0.1]]\nfrozen = [[0.2, 0.3]]\n"))
    frames = []
    for _ in range(8):
        live = world.sense().frame_bgr
        frames.append(live.copy())
        live[:] = 7  # the caller may draw on its frame: the frozen fault must repeat what the camera saw
        world.advance(0.0, 1.5)
    assert not frames[0].any() and not frames[1].any()  # t = 0.0, 0.05: black
    assert frames[2].any()
    assert np.array_equal(frames[4], frames[3]) and np.array_equal(frames[5], frames[3])  # t = 0.2, 0.25 repeat t = 0.15
    assert not np.array_equal(frames[6], frames[3])  # t = 0.3: live again
    assert world.sense().qr_visible == ()


def test_a_qr_board_near_the_car_decodes_with_opencv(tmp_path: Path) -> None:
    sc = scenario(tmp_path, '[[qr_boards]]\nroute = "B"\nstart_m = 2.5\nspacing_m = 5.0\ncount = 2\nside = "right"\n')
    world = World(sc)
    detector = cv2.QRCodeDetector()
    visible, decoded = [], []
    for _ in range(30):
        sens = world.sense()
        if sens.qr_visible:
            visible.append(sens.qr_visible)
            text = detector.detectAndDecode(sens.frame_bgr)[0]
            decoded.append(text)
        world.advance(0.0, 1.0)
    assert visible, "the board never came into readable view"
    assert all(v == ("FG1;route=B;sector=0;pos_m=2.5",) for v in visible)
    assert "FG1;route=B;sector=0;pos_m=2.5" in decoded


def test_near_plane_clipping_keeps_a_low_box_beside_the_camera_below_the_horizon(tmp_path: Path) -> None:
    # a long, low box beside the car reaches behind the camera: unclipped, its rear corners would fold into the sky
    plain = World(scenario(tmp_path)).sense().frame_bgr
    beside = World(scenario(tmp_path, "[[obstacles]]\ns_m = 0.3\nlateral_m = 0.32\nlength_m = 1.2\nwidth_m = 0.1\n"
                                      "height_m = 0.05\n")).sense().frame_bgr
    horizon = int(World(scenario(tmp_path)).camera.horizon_v_px())
    assert np.array_equal(beside[: horizon - 2], plain[: horizon - 2])
    assert not np.array_equal(beside, plain)


def test_clip_near_keeps_the_part_in_front() -> None:
    square = [[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 1.0, 0.0]]
    clipped = _clip_near(square, [p[0] for p in square], 0.5)
    assert sorted(map(tuple, clipped)) == [(0.5, -1.0, 0.0), (0.5, 1.0, 0.0), (1.0, -1.0, 0.0), (1.0, 1.0, 0.0)]
    assert _clip_near(square, [2.0] * 4, 0.5) == square
    assert _clip_near(square, [0.0] * 4, 0.5) == []


def test_road_scale_frame_looks_like_a_dash_cam(tmp_path: Path) -> None:
    sc = scenario(tmp_path, head='scale = "road"\n')
    world = World(sc)
    frame = world.sense().frame_bgr
    half = sc.road.lane_width_m / 2
    assert grey_at(frame, pixel_of(world, 12.0, half)) > 190  # the solid left line, 12 m ahead
    horizon = world.camera.horizon_v_px()
    assert 0.3 * 240 < horizon < 0.5 * 240  # the horizon a little above the middle, like a dash-cam


def test_light_at_follows_the_zones() -> None:
    from fearguard.sim.lighting import TUNNEL_PORTAL_AT, light_at
    from fearguard.sim.scenario import LightingZone

    zones = (LightingZone("tunnel_exit", from_m=10.0, to_m=20.0), LightingZone("glare", from_s=5.0, to_s=6.0, strength=0.5),
             LightingZone("shadows", from_m=0.0, to_m=12.0))
    assert light_at(zones, 5.0, 0.0).shadow_zones == (2,)
    inside = light_at(zones, 11.0, 0.0)
    assert inside.tunnel == 1.0 and inside.portal_s_m == pytest.approx(10.0 + TUNNEL_PORTAL_AT * 10.0) and inside.gain == 1.0
    just_out, later = light_at(zones, 14.5, 0.0), light_at(zones, 19.5, 0.0)
    assert just_out.tunnel == 0.0 and just_out.gain > later.gain > 1.0  # washed out, recovering
    glare = light_at(zones, 30.0, 5.5)
    assert glare.gain > 1.0 and glare.offset > 0.0 and glare.bloom == 0.5
    assert light_at(zones, 30.0, 6.0) == light_at((), 0.0, 0.0)  # every zone over: plain daylight
