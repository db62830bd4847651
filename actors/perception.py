"""Perception: find cans, bottles and other objects in RGB-D frames with OpenCV.

Pipeline (one frame, :func:`detect`; ``docs/perception.md`` explains each step):

1. **Colour**: every saturated pixel gets a named colour of :data:`PALETTE` (by hue).
2. **Segments**: connected regions of one colour; where two regions of the same colour
   overlap in the image, the depth jump between them cuts the farther one off.
3. **Geometry**: each segment's pixels are back-projected with the depth and the
   intrinsics and put into the map frame with the camera pose of the frame. The support
   height (the floor) comes from the pixels just below the segment; heights are measured
   from it. The object's metric width profile is measured in height bands, across the
   viewing direction.
4. **Category**: an :class:`Appearance` (colour + profile of radius against height) whose
   colour matches is checked against the measured width profile, the height the model
   would show in this image (projected from the fitted axis: the image border may hide a
   bottle's neck), and the fit of a cylinder of its body radius to the body's surface
   points (a flat face or a poor fit rejects it). The best match above
   ``min_confidence`` names the segment; otherwise it is ``unknown`` (a distractor).
5. **Position**: the object's vertical axis is the centre of the circle of the known body
   radius fitted (least squares, robust) to the visible surface points of the body: the
   visible-surface centroid lies a few cm in front of the axis, the fit does not.
   ``z`` is the base (the support height).

Actors (``Perception`` SubSystem; the camera streams are in ``actors/camera.py``):
``object_glance``, ``find_object``, ``pic_find``, ``get_found``, ``measure_distance``
(stream), ``measure_center`` (stream). Detections are plain dicts (see :func:`detect`).

The steps live in modules of their own (``actors/perception_*.py``), and every name
they define is importable from here: ``perception_colour`` (step 1: appearances and the
colour model), ``perception_segments`` (steps 2 and 3), ``perception_round`` and
``perception_box`` (step 4 for bodies of revolution and for boxes; what they share is in
``perception_fit``) and ``perception_detect`` (the pipeline, :func:`detect`, and
:func:`combine_sightings`).
"""

from __future__ import annotations

from typing import Iterator

from bt_engine import SubSystem, actor

from .camera import Camera, RGBDFrame

# Everything the steps' modules define, importable from actors.perception as before the split
from .perception_box import (
    FACE_BOW,
    GRAZING,
    GRAZING_SLACK,
    TILT_FACE_ANGLE,
    _bow,
    _box_centre,
    _box_faces,
    _box_tolerances,
    _face_direction,
    _Rectangle,
    _rectangle_fit,
    _resting_bow,
    _score_box,
    _score_box_resting,
    _score_box_tilted,
    _whole_faces,
)
from .perception_colour import (
    HUE_WINDOW,
    MIN_SATURATION,
    MIN_VALUE,
    PALETTE,
    SATURATION_SHARE,
    Appearance,
    PerceptionError,
    _hsv_of,
    _hue_lut,
    appearance_of,
    colour_labels,
    hue_of,
    palette_colour,
    registered_appearances,
)
from .perception_detect import PATCH_SHARE, UNKNOWN, _axis, _score, base_height, combine_sightings, detect
from .perception_fit import FIT_POINTS, LYING_TILT, MAX_ERROR, UPRIGHT_TILT, _confidence
from .perception_round import (
    MIN_VISIBLE_WIDTH,
    _profile_fit,
    _rise_error,
    _score_posed,
    _score_upright,
    _visible_top,
    fit_circle_fixed,
)
from .perception_segments import (
    DEPTH_NOISE,
    LABEL_GAP,
    MAX_RANGE,
    MAX_UNKNOWN_SIZE,
    MIN_PIXELS,
    OCCLUDER_LOOK,
    OCCLUSION_JUMP,
    _bridge_labels,
    _components,
    _continued_share,
    _measure,
    _occluded_sides,
    _occlusion_cuts,
    _Segment,
    _segment_grid,
    _segments,
    _structure,
    backproject,
)


# ----------------------------------------------------------------------------- subsystem
GLANCE_TIMEOUT = 3.0  # [s] how long one look may wait for a frame
ANY = "any"  # the category that means any known one (the trees' default)


def _targets(dets: list[dict], category: str | None, apps: dict) -> list[dict]:
    if category is None:
        return [d for d in dets if d["category"] in apps]
    return [d for d in dets if d["category"] == category]


class Perception(SubSystem):
    """Object detection, classification and localisation on the robot's RGB-D camera.

    A ``camera`` child subsystem holds the camera's stream actors (``pic``, ``depth``,
    ``camera_info``, ``rgbd``). ``appearances`` maps category names to
    :class:`Appearance`; by default every registered category's, read at each look (so a
    category loaded later is recognised). Other keyword arguments go to
    :class:`actors.camera.Camera` (topics, map and base frames).
    """

    def __init__(self, appearances: dict[str, Appearance] | None = None, **camera: object) -> None:
        super().__init__()
        self.add_subsystem("camera", Camera, **camera)
        self.set_value("appearances", None if appearances is None else dict(appearances))

    def _apps(self) -> dict[str, Appearance]:
        fixed = self.get_value("appearances")
        return registered_appearances() if fixed is None else fixed

    def _check_category(self, category: str | None) -> str | None:
        """``category`` as the looks take it: None for any known category ("any", as the
        search and the trees say it, or None); an error for a category nobody knows."""
        if category in (None, ANY):
            return None
        if category != UNKNOWN and category not in self._apps():
            raise PerceptionError(
                f"unknown category {category!r}; known: {', '.join(sorted(self._apps()))}, {UNKNOWN}, or {ANY}"
            )
        return category

    def _frame(self) -> RGBDFrame:
        return self.run_actor_mode("rgbd", "timed", GLANCE_TIMEOUT)

    @actor(read_only=True)
    def object_glance(self) -> list[dict]:
        """One quick look: every object in the next RGB-D frame (targets and ``unknown``
        distractors), nearest first. See ``detect`` for the fields of a detection."""
        return detect(self._frame(), self._apps())

    @actor(read_only=True)
    def find_object(self, category: str | None = None) -> dict | None:
        """The nearest object of ``category`` (any known category when None) in the next
        RGB-D frame, or None: {category, x, y, z, height, width, distance, bearing,
        confidence, pixel, ...}; x, y is the object's axis and z its base, map frame [m].

        Args:
            category: the object category to look for (can, bottle, or unknown: an
                object of no known category); "any" or None: any known category
        """
        category = self._check_category(category)
        found = _targets(detect(self._frame(), self._apps()), category, self._apps())
        return found[0] if found else None

    @actor(read_only=True)
    def pic_find(self, category: str | None = None, seconds: float = 10.0) -> dict | None:
        """Watch the camera for up to ``seconds`` until an object of ``category`` (any known
        category when None) is seen; the nearest such detection, or None on timeout.

        Args:
            category: the object category to look for (can, bottle, or unknown: an
                object of no known category); "any" or None: any known category
            seconds: how long to watch at most [s]
        """
        category = self._check_category(category)
        ret = None
        with self.run_actor_mode("rgbd", "timed_iterator", seconds) as frames:
            for frame in frames:
                found = _targets(detect(frame, self._apps()), category, self._apps())
                if found:
                    ret = found[0]
                    break
        return ret

    @actor(read_only=True)
    def get_found(
        self, category: str | None = None, looks: int = 5, near: list[float] | None = None, within: float = 0.3
    ) -> dict | None:
        """A reliable estimate from ``looks`` consecutive frames: sightings are grouped by
        position, outliers dropped, and the median kept. Adds ``sightings``, ``looks`` and
        ``spread`` [m] to the detection fields; None when nothing was seen.

        Args:
            category: the object category to look for (can, bottle, or unknown: an
                object of no known category); "any" or None: any known category
            looks: how many consecutive camera frames to combine
            near: [x, y] in the map frame [m]: only objects seen within ``within`` of it
                (what is at that place); None: the object seen most often, then nearest
            within: see ``near`` [m]
        """
        category = self._check_category(category)
        if near is not None and (not isinstance(near, (list, tuple)) or len(near) != 2):
            raise PerceptionError(f"near must be [x, y] in the map frame, got {near!r}")
        looks = max(1, int(looks))
        sightings: list[dict] = []
        n = 0
        with self.run_actor_mode("rgbd", "timed_iterator", GLANCE_TIMEOUT + looks * 0.5) as frames:
            for frame in frames:
                sightings += _targets(detect(frame, self._apps()), category, self._apps())
                n += 1
                if n >= looks:
                    break
        if n == 0:
            raise PerceptionError("no camera frames")
        return combine_sightings(
            sightings, n, near=None if near is None else (float(near[0]), float(near[1])), within=float(within)
        )

    @actor(read_only=True)
    def measure_distance(self, category: str | None = None) -> Iterator[dict | None]:
        """Per frame, the range and bearing to the nearest target (for visual servoing):
        {distance [m], bearing [rad, + left], x, y, category, stamp}, or None when no
        target is in view.

        Args:
            category: the object category to look for (can, bottle, or unknown: an
                object of no known category); "any" or None: any known category
        """
        category = self._check_category(category)
        with self.run_actor_mode("rgbd", "iterator") as frames:
            for frame in frames:
                found = _targets(detect(frame, self._apps()), category, self._apps())
                if not found:
                    yield None
                    continue
                d = found[0]
                yield {
                    "distance": d["distance"],
                    "bearing": d["bearing"],
                    "x": d["x"],
                    "y": d["y"],
                    "category": d["category"],
                    "stamp": d["stamp"],
                }

    @actor(read_only=True)
    def measure_center(self, category: str | None = None) -> Iterator[dict | None]:
        """Per frame, where the nearest target is in the image: {dx, dy} its pixel offset
        from the principal point normalised by half the image size (-1 left/top .. +1
        right/bottom), pixel, category, stamp; None when no target is in view.

        Args:
            category: the object category to look for (can, bottle, or unknown: an
                object of no known category); "any" or None: any known category
        """
        category = self._check_category(category)
        with self.run_actor_mode("rgbd", "iterator") as frames:
            for frame in frames:
                found = _targets(detect(frame, self._apps()), category, self._apps())
                if not found:
                    yield None
                    continue
                d, k = found[0], frame.intrinsics
                u, v = d["pixel"]
                yield {
                    "dx": (u - k.cx) / (k.width / 2),
                    "dy": (v - k.cy) / (k.height / 2),
                    "pixel": d["pixel"],
                    "category": d["category"],
                    "stamp": d["stamp"],
                }
