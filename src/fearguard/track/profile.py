"""A track profile: what the car's own recordings look like, and how far a new frame is from them (docs/learning.md).

``TrackProfile`` is a frozen value, saved as one ``.npz`` (format ``FORMAT``/``VERSION``, every array named and
documented in docs/learning.md) and read back by ``load_track``, which checks every key and shape and names the one
that is wrong (``FileError``: exit 2 on the command line).

Familiarity of a frame (the sixth cue): its features (``features.py``), weighted so each block counts alike, projected
on the learnt principal components plus the length of what the components do not explain; the mean distance to its
``NEIGHBOURS`` nearest learnt frames is ``d``. The learning calibrated ``d`` on the recordings themselves: each
calibration frame against the learnt frames more than ``CALIBRATION_GAP_S`` away in time (a frame's own neighbours in
time would make everything look familiar). With ``d_ref`` the ``REFERENCE_PERCENTILE``-th percentile of those
distances and ``d_typ`` their median, familiarity is piecewise linear in ``d``::

    1 up to d_typ (as familiar as the typical recorded frame), FAMILIAR_AT_REFERENCE at d_ref (as familiar as 95 % of
    the recordings), 0 from UNFAMILIAR_RATIO · d_ref

Graded below ``d_ref`` so that the fear still orders frames the rule files call familiar (their "familiar" term rises
from 0.6 to 1): among calm frames, the less typical ones read a little more fear, never enough to slow the car.
The frame's light (``light.py``: the shape of its grey levels) is read against the learnt frames' light the same way
but without the grading (1 up to its own reference, 0 from twice it), and the cue is the lower of the two: lights
switched off in a room whose own frames include a dark floor below a bright window are unlike its light, however like
its layout.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np

from fearguard.errors import FileError
from fearguard.lane import GUIDANCE, MARKINGS
from fearguard.track.features import BLOCK_SIZES, block_slices, features_of, shrink
from fearguard.track.floor import FLOOR_PX, FloorModel
from fearguard.track.light import LIGHT_PERCENTILES, REFERENCE_MIN, LightModel, light_of, light_words

FORMAT = "fearguard-track"
VERSION = 2  # 2: the detail block (features.py); a version-1 file has 207 features and is refused (relearn)
NEIGHBOURS = 3  # [frames] a new frame's distance is the mean to this many nearest learnt frames (one odd frame is no track)
REFERENCE_PERCENTILE = 95.0  # [%] of the recordings' own distances: d_ref, where familiarity reads FAMILIAR_AT_REFERENCE
UNFAMILIAR_RATIO = 2.0  # [-] d / d_ref at which familiarity reaches 0 (unfamiliar)
FAMILIAR_AT_REFERENCE = 0.9  # [0..1] familiarity at d_ref: inside the rule files' "familiar" term (fear very low), below 1
#                              so that frames between the typical one and d_ref are graded (module docstring)
CALIBRATION_GAP_S = 2.0  # [s] a calibration frame is compared only with learnt frames further away in time than this
BAND_PERCENTILES = (2.0, 98.0)  # [%] of the recordings' brightness: the learnt normal light
OCCLUSION_PERCENTILE = 90.0  # [%] of the recordings' occlusion cue: as much of the marking region as normal driving hides
FEATURE_COUNT = int(sum(BLOCK_SIZES))
BAND_EDGE = 0.5  # [grey levels] the learnt band is kept this far from 0, 255 and itself when it is read


@dataclass(frozen=True, eq=False)  # eq=False: holds arrays
class TrackProfile:
    """What was learnt from a car's recordings. Arrays are read-only."""

    source: str  # what it was learnt from (paths), for the reasons and the picture
    frames_learnt: int  # frames whose features were learnt
    mean: np.ndarray  # (F,) feature mean of the learnt frames
    weights: np.ndarray  # (F,) per-feature weight: each block (layout, colour, edges, detail) counts alike
    basis: np.ndarray  # (k, F) principal components of the weighted features (rows, orthonormal)
    bank: np.ndarray  # (M, k + 1) learnt frames: projections and the unexplained length
    calibration_distances: np.ndarray  # (C,) sorted: the recordings' own distances (see the module docstring)
    brightness_band: tuple[float, float]  # [grey level 0..255] the learnt normal light (BAND_PERCENTILES of the cue)
    lane_confidence_median: float  # [0..1] the camera's lane confidence on the recordings (NaN: not measured)
    marking_colours_bgr: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))  # (m, 3) the track's markings, typical BGR
    occlusion_usual: float = math.nan  # [0..1] the OCCLUSION_PERCENTILE of the occlusion cue on the recordings (NaN: not measured)
    floor: FloorModel | None = None  # the floor's colours and where it usually is (None: the recordings showed no steady floor)
    light: LightModel | None = None  # the learnt light's shape (None: a profile learnt before it; familiarity reads layout alone)
    markings: str = "light"  # the track's markings the lane model sees it by (``lane.MARKINGS``; absent in a file: light)
    guidance: str = "two_lines"  # what the track guides the car by (``lane.GUIDANCE``; absent in a file: two lines)

    @cached_property
    def reference_distance(self) -> float:
        """d_ref: the REFERENCE_PERCENTILE-th percentile of the recordings' own distances."""
        return float(np.percentile(self.calibration_distances, REFERENCE_PERCENTILE))

    @cached_property
    def typical_distance(self) -> float:
        """d_typ: the median of the recordings' own distances (module docstring)."""
        return float(np.median(self.calibration_distances))

    @cached_property
    def light_reference(self) -> float:
        """The light's d_ref: the same percentile of its own distances, never below ``light.REFERENCE_MIN`` (NaN: no light)."""
        if self.light is None:
            return math.nan
        return max(float(np.percentile(self.light.calibration, REFERENCE_PERCENTILE)), REFERENCE_MIN)

    def distance(self, features: np.ndarray) -> float:
        """Mean distance of one feature vector to its NEIGHBOURS nearest learnt frames (NaN for non-finite features)."""
        return nearest_mean(self.bank, self.embed(features[None, :])[0])

    def embed(self, features: np.ndarray) -> np.ndarray:
        """(N, F) features → (N, k + 1): the projection on the components and the length they leave unexplained."""
        z = (np.asarray(features, dtype=np.float64) - self.mean) * self.weights
        p = z @ self.basis.T
        rest = z - p @ self.basis
        return np.hstack([p, np.sqrt(np.einsum("ij,ij->i", rest, rest))[:, None]])

    def familiarity_of(self, distance: float) -> float:
        """The cue for a distance (module docstring); NaN stays NaN (unknown = worst)."""
        return familiarity_from(distance, self.reference_distance, self.typical_distance)

    def percentile_of(self, distance: float) -> float:
        """[%] of the recordings' own distances below this one (100: beyond every learnt frame)."""
        c = self.calibration_distances
        return 100.0 * float(np.searchsorted(c, distance, side="right")) / max(c.size, 1)

    def familiarity(self, frame: object) -> tuple[float, str]:
        """The cue for one frame and the sentence behind it ('' when fully familiar); NaN when it is not a picture."""
        shrunk = shrink(frame)
        if shrunk is None:
            return math.nan, "track: no picture to compare with the learnt track: familiarity unknown (worst)"
        d = self.distance(features_of(*shrunk))
        fam = self.familiarity_of(d)
        if not math.isfinite(fam):
            return math.nan, "track: the picture's features are not finite: familiarity unknown (worst)"
        lit, lit_why = self._light_familiarity(light_of(shrunk[1]))
        why = ""
        if fam < 1.0:
            where = ("beyond every learnt frame" if d > self.calibration_distances[-1]
                     else f"at the {self.percentile_of(d):.1f}th percentile of the learnt frames")
            why = (f"unlike the learnt track: distance {d / self.reference_distance:.2f}× the reference, "
                   f"{where}: familiarity {fam:.2f}")
        said = "; ".join(w for w in (why, lit_why) if w)
        return min(fam, lit), f"track: {said}" if said else ""

    def _light_familiarity(self, light: np.ndarray) -> tuple[float, str]:
        """The light's own familiarity (1 without a learnt light) and its sentence."""
        if self.light is None:
            return 1.0, ""
        ref = self.light_reference
        d = nearest_mean(self.light.levels, light)
        fam = familiarity_from(d, ref)
        if not fam < 1.0:
            return 1.0, ""
        return fam, (f"the light is unlike the learnt light: {light_words(light, self.light.nearest(light))}, "
                     f"distance {d / ref:.2f}× the reference: familiarity {fam:.2f}")

    def brightness_as_learnt(self, brightness: float, normal_band: tuple[float, float]) -> float:
        """The measured brightness read against the learnt light: the learnt band maps onto the rule file's normal band,
        0 stays 0 and 255 stays 255, linear between (monotone: darker stays darker). A dim carpet arena is normal
        for the car that learnt it; a blackout is still dark."""
        if not math.isfinite(brightness):
            return brightness
        lo = min(max(self.brightness_band[0], BAND_EDGE), 255.0 - 2.0 * BAND_EDGE)  # a band touching 0 or 255, or a point:
        hi = min(max(self.brightness_band[1], lo + BAND_EDGE), 255.0 - BAND_EDGE)  # widened so the map stays a function
        n_lo, n_hi = normal_band
        return float(np.interp(brightness, [0.0, lo, hi, 255.0], [0.0, n_lo, n_hi, 255.0]))


    def occlusion_as_learnt(self, occlusion: float, calm_top: float) -> float:
        """The occlusion cue read against the recordings: up to what normal driving on this track showed
        (``occlusion_usual``) maps onto the rule file's calm term (0..``calm_top``), the rest linearly up to 1 (monotone,
        0 and 1 fixed). Where the camera's marking region is mostly "hidden" on every normal frame (the lane model does
        not find this track's guidance) the cue carries nothing, and it must not stop the car; on a track where normal
        driving shows it calm (usual ≤ calm_top) it is unchanged."""
        usual = self.occlusion_usual
        if not math.isfinite(occlusion) or not math.isfinite(usual) or usual <= calm_top:
            return occlusion
        usual = min(usual, 1.0 - BAND_EDGE / 255.0)
        return float(np.interp(occlusion, [0.0, usual, 1.0], [0.0, calm_top, 1.0]))


def nearest_mean(bank: np.ndarray, q: np.ndarray) -> float:
    """Mean distance of ``q`` to its NEIGHBOURS nearest rows of ``bank`` (NaN for a non-finite ``q``): the familiarity's
    distance and the light's."""
    if not np.all(np.isfinite(q)):
        return math.nan
    d2 = np.einsum("ij,ij->i", bank - q, bank - q)
    k = min(NEIGHBOURS, d2.size)
    return float(np.sqrt(np.partition(d2, k - 1)[:k]).mean())


def familiarity_from(distance: float, reference: float, typical: float | None = None) -> float:
    """1 up to the typical distance, ``FAMILIAR_AT_REFERENCE`` at the reference, 0 from ``UNFAMILIAR_RATIO`` times it,
    linear between (without a typical distance: 1 up to the reference, then linear to 0); NaN stays NaN (worst)."""
    if not math.isfinite(distance):
        return math.nan
    ratio = distance / max(reference, 1e-12)
    if typical is None:
        return float(np.clip((UNFAMILIAR_RATIO - ratio) / (UNFAMILIAR_RATIO - 1.0), 0.0, 1.0))
    if ratio >= 1.0:
        return float(max(0.0, FAMILIAR_AT_REFERENCE * (UNFAMILIAR_RATIO - ratio) / (UNFAMILIAR_RATIO - 1.0)))
    typ = min(typical / max(reference, 1e-12), 1.0)
    if ratio <= typ:
        return 1.0
    return float(1.0 - (1.0 - FAMILIAR_AT_REFERENCE) * (ratio - typ) / (1.0 - typ))


def ratio_at(familiarity: float) -> float:
    """d / d_ref at which a familiarity at or below ``FAMILIAR_AT_REFERENCE`` is read (``familiarity_from``'s line beyond
    the reference, inverted: the picture marks its levels)."""
    return UNFAMILIAR_RATIO - familiarity / FAMILIAR_AT_REFERENCE * (UNFAMILIAR_RATIO - 1.0)


def load_track(path: str | Path) -> TrackProfile:
    """A profile written by ``fearguard learn``; a wrong file is a ``FileError`` naming the file and the key."""
    p = Path(path)
    try:
        with np.load(p, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files}
    except FileNotFoundError:
        raise FileError(str(p), "file", "no such file (write one with `fearguard learn RECORDING --out track.npz`)") from None
    except (OSError, ValueError, EOFError) as exc:
        raise FileError(str(p), "file", f"not a track profile (.npz written by `fearguard learn`): {exc}") from None
    return profile_from_arrays(data, str(p))


def profile_from_arrays(data: dict[str, np.ndarray], where: str) -> TrackProfile:
    """Check every key of a saved profile and build it."""

    def need(key: str, ndim: int, cols: int | None = None) -> np.ndarray:
        if key not in data:
            raise FileError(where, key, "missing: not a complete track profile (relearn with `fearguard learn`)")
        a = data[key]
        if a.dtype.kind not in "fiu" or a.ndim != ndim or (cols is not None and a.shape[-1] != cols):
            raise FileError(where, key, f"expected a {ndim}-d array of numbers{f' with {cols} columns' if cols else ''}, "
                                        f"got {a.dtype} {a.shape}")
        a = a.astype(np.float64)
        if not np.all(np.isfinite(a)):
            raise FileError(where, key, "has values that are not finite numbers")
        a.setflags(write=False)
        return a

    fmt = str(data["format"]) if "format" in data else ""
    if fmt != FORMAT:
        raise FileError(where, "format", f"expected {FORMAT!r}, got {fmt!r}: not a fearguard track profile")
    version = need("version", 0)
    if int(version) != VERSION:
        raise FileError(where, "version", f"version {int(version)} is not {VERSION}: relearn with this fearguard")
    mean, weights = need("mean", 1, FEATURE_COUNT), need("weights", 1, FEATURE_COUNT)
    basis = need("basis", 2, FEATURE_COUNT)
    bank = need("bank", 2, basis.shape[0] + 1)
    calib = need("calibration_distances", 1)
    band = need("brightness_band", 1, 2)
    if bank.shape[0] < 1 or calib.size < 1:
        raise FileError(where, "bank", "no learnt frames")
    if not 0.0 <= band[0] <= band[1] <= 255.0:
        raise FileError(where, "brightness_band", f"expected 0 ≤ low ≤ high ≤ 255, got {band.tolist()}")
    lane = data.get("lane_confidence_median", np.array(math.nan))
    occ = data.get("occlusion_usual", np.array(math.nan))
    occ_usual = float(occ) if np.ndim(occ) == 0 and occ.dtype.kind in "fiu" else math.nan
    if not (math.isnan(occ_usual) or 0.0 <= occ_usual <= 1.0):
        raise FileError(where, "occlusion_usual", f"expected a share 0..1 (or NaN), got {occ_usual!r}")
    colours = need("marking_colours_bgr", 2, 3) if "marking_colours_bgr" in data else np.zeros((0, 3))
    floor = _floor_from_arrays(data, need, where) if "floor_colours_lab" in data else None  # none before the floor model
    light = _light_from_arrays(data, need, where) if "light_levels" in data or "light_calibration" in data else None
    markings = str(data["markings"]) if "markings" in data else "light"  # profiles learnt before 2026-12-07 have none
    if markings not in MARKINGS:
        raise FileError(where, "markings", f"expected one of {', '.join(MARKINGS)}, got {markings!r}")
    guidance = str(data["guidance"]) if "guidance" in data else "two_lines"  # none before 2026-12-07
    if guidance not in GUIDANCE:
        raise FileError(where, "guidance", f"expected one of {', '.join(GUIDANCE)}, got {guidance!r}")
    return TrackProfile(
        source=str(data.get("source", "")), frames_learnt=int(need("frames_learnt", 0)), mean=mean, weights=weights,
        basis=basis, bank=bank, calibration_distances=np.sort(calib), brightness_band=(float(band[0]), float(band[1])),
        lane_confidence_median=float(lane) if np.ndim(lane) == 0 and lane.dtype.kind in "fiu" else math.nan,
        marking_colours_bgr=colours, occlusion_usual=occ_usual, floor=floor, light=light, markings=markings,
        guidance=guidance,
    )


def _light_from_arrays(data: dict[str, np.ndarray], need: Callable[..., np.ndarray], where: str) -> LightModel:
    """The learnt light's keys of a saved profile, checked (profiles learnt before it have neither)."""
    levels, calib = need("light_levels", 2, len(LIGHT_PERCENTILES)), need("light_calibration", 1)
    if levels.shape[0] < 1 or not 0.0 <= levels.min() <= levels.max() <= 1.0:
        raise FileError(where, "light_levels", f"expected 1 or more lights 0..1, got {levels.shape[0]} frames")
    if calib.size < 1 or calib.min() < 0.0:
        raise FileError(where, "light_calibration", f"expected 1 or more distances ≥ 0, got {calib.size}")
    return LightModel(levels, np.sort(calib))


def _floor_from_arrays(data: dict[str, np.ndarray], need: Callable[..., np.ndarray], where: str) -> FloorModel:
    """The floor model's keys of a saved profile, checked (``need`` checks one key)."""
    floor_colours, radius, usual = need("floor_colours_lab", 2, 3), need("floor_radius_lab", 0), need("floor_usual", 2)
    hidden = need("floor_hidden_usual", 0)
    if floor_colours.shape[0] < 1 or not 0.0 <= floor_colours.min() <= floor_colours.max() <= 255.0:
        raise FileError(where, "floor_colours_lab", f"expected 1 or more Lab colours 0..255, got {floor_colours.shape[0]}")
    if not float(radius) > 0.0:
        raise FileError(where, "floor_radius_lab", f"expected a distance > 0, got {float(radius)!r}")
    if usual.shape != (FLOOR_PX[1], FLOOR_PX[0]) or not 0.0 <= usual.min() <= usual.max() <= 1.0:
        raise FileError(where, "floor_usual", f"expected shares 0..1 of shape {(FLOOR_PX[1], FLOOR_PX[0])}, got {usual.shape}")
    if not 0.0 <= float(hidden) <= 1.0:
        raise FileError(where, "floor_hidden_usual", f"expected a share 0..1, got {float(hidden)!r}")
    texture = None
    if "floor_texture_low" in data:  # profiles learnt before the texture test have none
        texture = need("floor_texture_low", 2)
        if texture.shape != usual.shape or texture.min() < 0.0:
            raise FileError(where, "floor_texture_low", f"expected textures ≥ 0 of shape {usual.shape}, got {texture.shape}")
    return FloorModel(floor_colours, float(radius), usual, float(hidden), texture)


def save_track(profile: TrackProfile, path: str | Path) -> Path:
    """Write the profile as one .npz (docs/learning.md lists the keys)."""
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    with p.open("wb") as fh:
        np.savez_compressed(
            fh, format=np.array(FORMAT), version=np.array(VERSION), source=np.array(profile.source),
            frames_learnt=np.array(profile.frames_learnt), mean=profile.mean, weights=profile.weights, basis=profile.basis,
            bank=profile.bank, calibration_distances=profile.calibration_distances,
            brightness_band=np.array(profile.brightness_band), lane_confidence_median=np.array(profile.lane_confidence_median),
            marking_colours_bgr=profile.marking_colours_bgr, occlusion_usual=np.array(profile.occlusion_usual),
            markings=np.array(profile.markings), guidance=np.array(profile.guidance),
            **_floor_arrays(profile.floor),
            **({"light_levels": profile.light.levels, "light_calibration": profile.light.calibration} if profile.light else {}),
        )
    return p


def _floor_arrays(floor: FloorModel | None) -> dict[str, np.ndarray]:
    if floor is None:
        return {}
    return {"floor_colours_lab": floor.colours_lab, "floor_radius_lab": np.array(floor.radius_lab),
            "floor_usual": floor.usual, "floor_hidden_usual": np.array(floor.hidden_usual),
            **({"floor_texture_low": floor.texture_low} if floor.texture_low is not None else {})}


def block_weights(features: np.ndarray) -> np.ndarray:
    """Per-feature weights so that each block's total spread over the learnt frames is 1 (a block with 192 pixels
    must not drown one with 6 colour statistics)."""
    w = np.ones(features.shape[1])
    centred = features - features.mean(axis=0)
    for s in block_slices():
        spread = math.sqrt(float((centred[:, s] ** 2).sum(axis=1).mean()))
        w[s] = 1.0 / max(spread, 1e-3)
    return w
