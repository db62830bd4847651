"""Object shapes: what a category's object looks like in 3-D, in one description that the
simulator builds a body from and perception measures against.

Every shape is given standing upright, its frame at the centre of its bounding box, z up.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Revolution:
    """A body of revolution about the vertical axis, as stacked cylinders.

    ``sections`` go bottom-up: ``(top height above the base [m], radius [m])``. The first
    section is the body: perception fits its radius to find the axis, and it is what the
    gripper holds. A can is one section; a wine bottle is body, shoulder and neck.
    """

    sections: tuple[tuple[float, float], ...]

    def __post_init__(self) -> None:
        if not self.sections:
            raise ValueError("a Revolution needs at least one (top, radius) section")
        last = 0.0
        for top, r in self.sections:
            if top <= last or r <= 0:
                raise ValueError(f"sections must rise and have positive radii, got {self.sections}")
            last = top

    kind = "revolution"

    @property
    def height(self) -> float:
        return self.sections[-1][0]

    @property
    def body_radius(self) -> float:
        return self.sections[0][1]

    @property
    def body_top(self) -> float:
        return self.sections[0][0]

    @property
    def footprint_radius(self) -> float:
        """Radius of the smallest circle around the footprint [m]."""
        return max(r for _, r in self.sections)

    def radius_at(self, h: float) -> float:
        """Radius at height ``h`` above the base (0 above the top)."""
        for top, r in self.sections:
            if h <= top:
                return r
        return 0.0

    def width_across(self, heading: float) -> float:
        """Width the fingers close on, the hand approaching along ``heading`` [rad] relative
        to the object's yaw: the body's diameter, whatever the heading."""
        return 2 * self.body_radius

    def parts(self) -> tuple:
        """Primitives in the object's frame: ("cylinder", radius, length, z_centre)."""
        out, bottom, z0 = [], 0.0, -self.height / 2
        for top, r in self.sections:
            out.append(("cylinder", r, top - bottom, z0 + (bottom + top) / 2))
            bottom = top
        return tuple(out)

    def volumes(self) -> list[float]:
        return [math.pi * p[1] ** 2 * p[2] for p in self.parts()]


def Cylinder(radius: float, height: float) -> Revolution:
    """A plain cylinder (a can): one section."""
    return Revolution(((height, radius),))


@dataclass(frozen=True)
class Box:
    """A box ``x`` by ``y`` wide and ``z`` high [m], standing on its ``x``-``y`` face."""

    x: float
    y: float
    z: float

    kind = "box"

    def __post_init__(self) -> None:
        if min(self.x, self.y, self.z) <= 0:
            raise ValueError(f"a Box needs positive sizes, got {self.x} x {self.y} x {self.z}")

    @property
    def height(self) -> float:
        return self.z

    @property
    def footprint_radius(self) -> float:
        return 0.5 * math.hypot(self.x, self.y)

    @property
    def body_top(self) -> float:
        return self.z

    def width_across(self, heading: float) -> float:
        """Width the fingers close on, the hand approaching along ``heading`` [rad] relative
        to the box's x axis: along x they close across y, along y across x."""
        c, s = abs(math.cos(heading)), abs(math.sin(heading))
        return self.y * c + self.x * s

    def rests(self) -> list[tuple[str, tuple[float, float], float]]:
        """The ways the box rests on a flat support: (pose, its top-view sides, height).
        ``upright`` stands on its x-y face, sides (x, y). ``lying`` lies on a face along z,
        its z side horizontal and named first (as a lying body's axis), then the side the
        fingers close across from above."""
        out = [("upright", (self.x, self.y), self.z)]
        for across, height in ((self.x, self.y), (self.y, self.x)):
            if not any(math.isclose(height, h) and math.isclose(across, min(f)) for _, f, h in out):
                out.append(("lying", (self.z, across), height))
        return out

    def parts(self) -> tuple:
        return (("box", (self.x, self.y, self.z), 0.0),)

    def volumes(self) -> list[float]:
        return [self.x * self.y * self.z]


Shape = Revolution | Box


@dataclass(frozen=True)
class Label:
    """A printed label around the body, from ``bottom`` to ``top`` [m] above its base:
    paper of ``rgba`` with print of ``print_rgba`` covering ``coverage`` of it. Worlds that
    show labels (``house_hard``) draw it; perception must see past it."""

    bottom: float
    top: float
    rgba: tuple[float, float, float, float] = (0.95, 0.94, 0.90, 1.0)
    print_rgba: tuple[float, float, float, float] = (0.15, 0.15, 0.15, 1.0)
    coverage: float = 0.3

    def __post_init__(self) -> None:
        if not 0 <= self.bottom < self.top:
            raise ValueError(f"a Label needs 0 <= bottom < top, got {self.bottom}..{self.top}")
        if not 0 <= self.coverage <= 1:
            raise ValueError(f"a Label's coverage is a fraction, got {self.coverage}")
