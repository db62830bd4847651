"""The types a world description is read into (sim/description.py reads the YAML):
the world, its static boxes, the objects' start poses, the ``poses:`` mix and the
``distractors:``. Kept apart from the reader so that the modules it uses (gridmap,
map_world, varied) can build worlds without importing it back.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from bt_engine.errors import ActorbtError

from .appearance import Appearance, Lighting
from .objects import DECOYS

POSE_KINDS = ("upright", "lying", "tilted")


class WorldError(ActorbtError, ValueError):
    """A world description is invalid or cannot be realised; the message names file:line
    (an ``ActorbtError``: the command line prints it in one line, exit status 2)."""


@dataclass(frozen=True)
class Box:
    """A static box: centre (x, y) on the floor, size (sx, sy, sz), yaw."""

    name: str
    x: float
    y: float
    sx: float
    sy: float
    sz: float
    yaw: float = 0.0
    rgba: tuple = (0.8, 0.8, 0.8, 1.0)
    support: bool = False  # a low table objects may stand on (worlds with ``poses``)

    def distance(self, px, py):
        """Distance from point(s) to the box footprint (0 inside)."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        dx, dy = np.asarray(px) - self.x, np.asarray(py) - self.y
        u, v = c * dx + s * dy, -s * dx + c * dy
        qu = np.maximum(np.abs(u) - self.sx / 2, 0.0)
        qv = np.maximum(np.abs(v) - self.sy / 2, 0.0)
        return np.hypot(qu, qv)

    def corners(self):
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        out = []
        for su, sv in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
            u, v = su * self.sx / 2, sv * self.sy / 2
            out.append((self.x + c * u - s * v, self.y + s * u + c * v))
        return out


@dataclass(frozen=True)
class PlacedObject:
    """Where an object starts: its frame (the centre of its bounding box) at (x, y) and, by
    default, standing on the floor turned by ``yaw``. In worlds with ``poses``: ``z`` (None:
    standing on the floor), ``quat`` (x, y, z, w; None: upright at ``yaw``), ``pose_kind``
    (upright, lying, tilted), ``support`` (floor, or the furniture it stands on or leans
    against) and ``rgba`` (None: the model's colour)."""

    name: str
    category: str
    x: float
    y: float
    yaw: float
    z: float | None = None
    quat: tuple | None = None
    pose_kind: str = "upright"
    support: str = "floor"
    rgba: tuple | None = None


@dataclass(frozen=True)
class PoseMix:
    """``poses:`` of a world description."""

    weights: tuple[tuple[str, float], ...] = (("upright", 0.5), ("lying", 0.3), ("tilted", 0.2))
    tilt_deg: tuple[float, float] = (15.0, 35.0)
    on_tables: float = 0.4  # chance an upright object in a room with a table stands on it
    settle_steps: int = 300  # physics steps at world creation (before the robot's loop)

    def fraction(self, kind: str) -> float:
        total = sum(w for _, w in self.weights)
        return dict(self.weights).get(kind, 0.0) / total

    def pick(self, u: float) -> str:
        """The kind at ``u`` in 0..1 (a uniform draw)."""
        u, acc = u * sum(w for _, w in self.weights), 0.0
        for kind, w in self.weights:
            acc += w
            if u < acc:
                return kind
        return self.weights[-1][0]


@dataclass(frozen=True)
class Distractors:
    """``distractors:`` of a world description."""

    count: tuple[int, int] = (4, 7)
    kinds: tuple[str, ...] = tuple(DECOYS)
    on_tables: float = 0.3


@dataclass
class WorldSpec:
    name: str
    source: str
    bounds: tuple
    walls: list = field(default_factory=list)  # [Box]
    rooms: dict = field(default_factory=dict)  # name -> (xmin, ymin, xmax, ymax)
    furniture: list = field(default_factory=list)  # [Box]
    place: Box | None = None
    robot_start: tuple = (0.0, 0.0, 0.0)
    objects: list = field(default_factory=list)  # [PlacedObject]
    search_locations: list = field(default_factory=list)  # [(x, y)]; empty: from the map
    seed: int = 0
    appearance: Appearance = field(default_factory=Appearance)  # all off: plain colours
    lighting: Lighting | None = None  # this seed's lighting (appearance.lighting)
    poses: PoseMix | None = None  # varied poses (None: every object upright on the floor)

    @property
    def settle_steps(self) -> int:
        """Physics steps to let the objects come to rest at world creation."""
        return self.poses.settle_steps if self.poses is not None else 0

    @property
    def obstacles(self):
        """Everything static that stands on the floor (walls, furniture, place location)."""
        return list(self.walls) + list(self.furniture) + ([self.place] if self.place else [])

    def room_of(self, x, y):
        for name, (x0, y0, x1, y1) in self.rooms.items():
            if x0 <= x <= x1 and y0 <= y <= y1:
                return name
        return None
