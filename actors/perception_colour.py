"""Colour: how a category looks (its :class:`Appearance`: a colour and a shape) and the
colour model that names each pixel's colour (:data:`PALETTE`, widened around the
categories' hues: :func:`colour_labels`)."""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

import categories
from bt_engine import ActorbtError

#: Named colours by OpenCV hue (0..180). A pixel has a colour when saturated enough.
PALETTE: dict[str, tuple[tuple[int, int], ...]] = {
    "red": ((0, 8), (165, 181)),
    "orange": ((8, 22),),
    "yellow": ((22, 35),),
    "green": ((35, 85),),
    "cyan": ((85, 100),),
    "blue": ((100, 130),),
    "purple": ((130, 165),),
}
MIN_SATURATION = 80  # HSV S (0..255): floor, walls and shadows are below ~40
MIN_VALUE = 20  # HSV V (0..255): darker pixels have no reliable hue
SATURATION_SHARE = 0.55  # a category's segments keep this share of its saturation or more
#                         (light and shade change the value more; brown furniture whose
#                         hue drifts into a category's keeps about 0.45 of its saturation)
HUE_WINDOW = 7  # OpenCV hue units (2 degrees each) either side of a category's hue


class PerceptionError(ActorbtError):
    """A perception request could not be served (no camera frames, bad category)."""


@dataclass(frozen=True)
class Appearance:
    """How a category looks: a colour, and either a body of revolution standing upright
    (``sections``) or a box (``box``: its x, y, z sizes [m]).

    ``sections`` go bottom-up: ``(top height above the base [m], radius [m])``; the first
    section is the body whose radius is fitted to find the axis. A can is one section; a
    wine bottle is body, shoulder and neck.
    """

    name: str
    colour: str
    sections: tuple[tuple[float, float], ...] = ()
    min_confidence: float = 0.3
    description: str = ""
    box: tuple[float, float, float] | None = None
    hue: int | None = None  # its OpenCV hue (0..180): pixels within HUE_WINDOW count
    # as its colour, across a palette boundary
    saturation: int | None = None  # its saturation (0..255): a segment far less saturated
    # (SATURATION_SHARE) is something else of its hue
    label: tuple[float, float] | None = None  # a band round it, from .. to [m] above its base,
    #                                            in another colour (a paper label)

    @property
    def is_box(self) -> bool:
        return self.box is not None

    @property
    def height(self) -> float:
        return self.box[2] if self.box else self.sections[-1][0]

    @property
    def body_radius(self) -> float:
        """The body's radius; for a box, half its narrower side."""
        return 0.5 * min(self.box[:2]) if self.box else self.sections[0][1]

    @property
    def body_top(self) -> float:
        return self.box[2] if self.box else self.sections[0][0]

    def radii_at(self, hs: np.ndarray) -> np.ndarray:
        """:meth:`radius_at` for an array of heights."""
        tops = np.array([t for t, _ in self.sections])
        radii = np.array([r for _, r in self.sections] + [0.0])
        return radii[np.searchsorted(tops, hs, side="left")]

    def radius_at(self, h: float) -> float:
        """Radius at height ``h`` above the base (0 above the top)."""
        for top, r in self.sections:
            if h <= top:
                return r
        return 0.0


def _hsv_of(rgba) -> tuple[int, int, int]:
    """OpenCV's hue (0..180), saturation and value (0..255) of a colour given as rgb(a)
    in 0..1; PerceptionError for a colour with no clear hue (white, grey, black)."""
    px = np.array([[[round(255 * float(c)) for c in reversed(tuple(rgba)[:3])]]], dtype=np.uint8)  # BGR
    h, sat, val = (int(v) for v in cv2.cvtColor(px, cv2.COLOR_BGR2HSV)[0, 0])
    if sat < MIN_SATURATION or val < MIN_VALUE:
        raise PerceptionError(
            f"colour {tuple(rgba)} has no clear hue (saturation {sat}, value {val}): "
            "perception finds objects by a saturated colour"
        )
    return h, sat, val


def hue_of(rgba) -> int:
    """The OpenCV hue (0..180) of a colour given as rgb(a) in 0..1; PerceptionError for a
    colour with no clear hue (white, grey, black)."""
    return _hsv_of(rgba)[0]


def palette_colour(rgba) -> str:
    """The :data:`PALETTE` name of a colour given as rgb(a) in 0..1, as the camera would
    see its hue; PerceptionError for a colour with no clear hue (white, grey, black)."""
    h = hue_of(rgba)
    for name, ranges in PALETTE.items():
        if any(lo <= h < hi for lo, hi in ranges):
            return name
    raise PerceptionError(f"colour {tuple(rgba)} (hue {h}) is in no palette range")


def appearance_of(category: categories.Category) -> Appearance:
    """A category's appearance: the palette colour of its rgba and its shape."""
    shape = category.shape
    hue, sat, _ = _hsv_of(category.rgba)
    colour = palette_colour(category.rgba)
    label = category.label
    band = None
    if label is not None and not _same_colour(label.rgba, colour):
        band = (label.bottom, label.top)
    box: tuple[float, float, float] | None = None
    sections: tuple[tuple[float, float], ...] = ()
    if isinstance(shape, categories.Box):
        box = (shape.x, shape.y, shape.z)
    else:
        sections = tuple(shape.sections)
    return Appearance(
        name=category.name,
        colour=colour,
        sections=sections,
        box=box,
        hue=hue,
        saturation=sat,
        min_confidence=category.min_confidence,
        description=category.description,
        label=band,
    )


def _same_colour(rgba, colour: str) -> bool:
    """Is ``rgba`` the palette colour ``colour`` (a colourless one, white paper, is none)?"""
    try:
        return palette_colour(rgba) == colour
    except PerceptionError:
        return False


def registered_appearances() -> dict[str, Appearance]:
    """Every registered category's appearance, read now (a category registered later is
    seen by the next call)."""
    return {c.name: appearance_of(c) for c in categories.all_categories()}


def _hue_lut(appearances=()) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[str]]:
    """Hue -> palette index, twice: the palette's own ranges, and those ranges widened to
    HUE_WINDOW around each appearance's hue (colour jitter and white balance move a hue
    across a palette boundary: a yellow carton near orange). And hue -> the saturation a
    pixel needs for the widened colour: in a widened part, the share SATURATION_SHARE of
    the appearance's own (brown furniture has hues near a yellow carton's but half its
    saturation; taken for yellow, a wardrobe merges with a carton leaning on it). Returns
    (widened, palette, saturation floor, names)."""
    names = list(PALETTE)
    palette = np.zeros(256, np.uint8)
    for i, name in enumerate(names, 1):
        for lo, hi in PALETTE[name]:
            palette[lo : min(hi, 256)] = i
    widened = palette.copy()
    floor = np.full(256, MIN_SATURATION, np.int32)
    for app in appearances:
        if app.hue is not None and app.colour in names:
            k = names.index(app.colour) + 1
            hues = np.arange(app.hue - HUE_WINDOW, app.hue + HUE_WINDOW + 1) % 180
            widened[hues] = k
            if app.saturation is not None:
                moved = hues[palette[hues] != k]
                floor[moved] = np.maximum(floor[moved], int(SATURATION_SHARE * app.saturation))
    return widened, palette, floor, names


def colour_labels(bgr: np.ndarray, appearances=(), hsv: np.ndarray | None = None) -> tuple[np.ndarray, list[str]]:
    """Per-pixel palette index (0 = no colour) and the palette's names (index - 1);
    ``appearances`` widen their colours' ranges around their hues for pixels saturated
    as they are (see _hue_lut); a duller pixel keeps the palette's colour.
    ``hsv``: the image in HSV, when the caller has it already."""
    if hsv is None:
        hsv = cv2.cvtColor(bgr, cv2.COLOR_BGR2HSV)
    widened, palette, floor, names = _hue_lut(appearances)
    hue, sat = hsv[:, :, 0], hsv[:, :, 1]
    lab = np.where(sat >= floor[hue], widened[hue], palette[hue])
    lab[(sat < MIN_SATURATION) | (hsv[:, :, 2] < MIN_VALUE)] = 0
    return lab, names
