"""What the live view draws besides the robot's topics: the robot's body (when the
configuration gives one), the detections and the navigation goals, as one Foxglove
``SceneUpdate``, and the robot's path as ``PosesInFrame``. Plain data in, Foxglove
messages out; :mod:`.foxglove_view` feeds it.

Where the data comes from (the view watches every actor call, see there):

- a **detection** is any actor result (or a value inside one: a list, a tree's outputs)
  that is a mapping with a ``category`` and numeric ``x`` and ``y`` in the map frame, as
  ``watch``, ``survey`` and the catch actors return them. A detection within
  :data:`SAME_OBJECT` of an earlier one of the same category replaces it.
- a **goal** is the goal message of any action call whose goal carries a
  geometry_msgs/PoseStamped ``pose`` (nav2_msgs/NavigateToPose, as ``goto`` sends it).
- the **path** is the odometry (``/odom``, in its ``odom`` frame): a pose every
  :data:`PATH_STEP` metres or :data:`PATH_TURN` radians.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from types import ModuleType
from typing import TYPE_CHECKING, Iterable, Iterator, TypeGuard

from .rostypes import Value

if TYPE_CHECKING:
    # the SDK is imported when a view starts; ``fm`` below is this module
    from foxglove.messages import Pose, PosesInFrame, SceneEntity, SceneUpdate, Timestamp

__all__ = ["Body", "Detection", "Goal", "Scene", "detections_in", "goal_of"]

#: [m] a detection this near an earlier one of the same category is the same object
SAME_OBJECT = 0.3
#: how many detections and goals are kept (the oldest go first)
KEEP = 100
#: [m], [rad] the path gets a pose when the robot moved or turned this much
PATH_STEP, PATH_TURN = 0.02, 0.1
#: poses kept in the path
PATH_KEEP = 20000


@dataclass(frozen=True)
class Body:
    """The robot drawn as a box: its size (``sx``, ``sy``, ``sz``) [m], standing on the
    ground with its centre ``x`` [m] ahead of base_footprint (``robot: body:`` in
    actorbt.yaml)."""

    sx: float
    sy: float
    sz: float
    x: float = 0.0


@dataclass(frozen=True)
class Detection:
    """An object seen: ``category`` at (``x``, ``y``, ``z``) [m] in ``frame``."""

    category: str
    x: float
    y: float
    z: float = 0.0
    frame: str = "map"


@dataclass(frozen=True)
class Goal:
    """A navigation goal: (``x``, ``y``) [m] and heading ``yaw`` [rad] in ``frame``."""

    x: float
    y: float
    yaw: float
    frame: str = "map"


def _number(value: object) -> TypeGuard[float]:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def detections_in(value: Value, depth: int = 3) -> Iterator[Detection]:
    """The detections in an actor's result (see the module docstring)."""
    if isinstance(value, dict):
        if isinstance(value.get("category"), str) and _number(value.get("x")) and _number(value.get("y")):
            z = value.get("z")
            yield Detection(
                value["category"],
                float(value["x"]),
                float(value["y"]),
                float(z) if _number(z) else 0.0,
                str(value.get("frame", "map")),
            )
            return
        children: Iterable[Value] = value.values()
    elif isinstance(value, (list, tuple)):
        children = value
    else:
        return
    if depth > 0:
        for child in children:
            yield from detections_in(child, depth - 1)


def goal_of(args: tuple) -> Goal | None:
    """The goal an action call's arguments carry, if it is a pose (see the module docstring)."""
    if not args:
        return None
    stamped = getattr(args[0], "pose", None)
    pose = getattr(stamped, "pose", None)
    header = getattr(stamped, "header", None)
    if pose is None or header is None or not hasattr(pose, "position"):
        return None
    q = pose.orientation
    yaw = math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))
    return Goal(float(pose.position.x), float(pose.position.y), yaw, header.frame_id or "map")


def _hue(name: str) -> tuple[float, float, float]:
    """A steady colour per category name."""
    import colorsys

    h = (sum(name.encode()) * 0.618033988749895) % 1.0
    return colorsys.hsv_to_rgb(h, 0.75, 0.95)


class Scene:
    """The view's own markers; ``update(t)`` is the SceneUpdate to send at ``t`` [s]."""

    def __init__(self, body: Body | None = None) -> None:
        #: the robot's box, None: not drawn (the robot's own topics still show it)
        self.body = body
        self.detections: list[Detection] = []
        self.goals: list[Goal] = []
        self.path: list[tuple[float, float, float]] = []  # (x, y, yaw) in the odom frame
        self.path_frame = "odom"

    # -- what happens ----------------------------------------------------------------------
    def add_detection(self, d: Detection) -> bool:
        """Keep ``d`` (replacing the same object seen before). True: the scene changed."""
        for i, old in enumerate(self.detections):
            if old.category == d.category and math.hypot(old.x - d.x, old.y - d.y) < SAME_OBJECT:
                if old == d:
                    return False
                del self.detections[i]
                break
        self.detections.append(d)
        del self.detections[:-KEEP]
        return True

    def add_goal(self, g: Goal) -> None:
        self.goals.append(g)
        del self.goals[:-KEEP]

    def add_odometry(self, x: float, y: float, yaw: float, frame: str = "odom") -> bool:
        """A pose of the robot; True when the path got it (moved or turned enough)."""
        if self.path:
            px, py, pyaw = self.path[-1]
            turned = abs(math.atan2(math.sin(yaw - pyaw), math.cos(yaw - pyaw)))
            if math.hypot(x - px, y - py) < PATH_STEP and turned < PATH_TURN:
                return False
        self.path_frame = frame
        self.path.append((x, y, yaw))
        del self.path[:-PATH_KEEP]
        return True

    # -- Foxglove messages -----------------------------------------------------------------
    def update(self, t: float) -> SceneUpdate:
        """Every entity, as one foxglove SceneUpdate (entities with an id replace the
        ones the client has)."""
        import foxglove.messages as fm

        stamp = _timestamp(t)
        entities = [] if self.body is None else [self._robot(fm, stamp, self.body)]
        entities += [self._detection(fm, stamp, i, d) for i, d in enumerate(self.detections)]
        entities += [self._goal(fm, stamp, i, g, latest=i == len(self.goals) - 1) for i, g in enumerate(self.goals)]
        return fm.SceneUpdate(entities=entities)

    def path_message(self, t: float) -> PosesInFrame:
        import foxglove.messages as fm

        return fm.PosesInFrame(
            timestamp=_timestamp(t),
            frame_id=self.path_frame,
            poses=[_pose(fm, x, y, 0.0, yaw) for x, y, yaw in self.path],
        )

    @staticmethod
    def _robot(fm: ModuleType, stamp: Timestamp, body: Body) -> SceneEntity:
        return fm.SceneEntity(
            timestamp=stamp,
            frame_id="base_footprint",
            id="robot",
            frame_locked=True,
            cubes=[
                fm.CubePrimitive(
                    pose=_pose(fm, body.x, 0.0, body.sz / 2 + 0.01, 0.0),
                    size=fm.Vector3(x=body.sx, y=body.sy, z=body.sz),
                    color=fm.Color(r=0.25, g=0.35, b=0.45, a=0.6),
                )
            ],
        )

    @staticmethod
    def _detection(fm: ModuleType, stamp: Timestamp, i: int, d: Detection) -> SceneEntity:
        r, g, b = _hue(d.category)
        return fm.SceneEntity(
            timestamp=stamp,
            frame_id=d.frame,
            id=f"detection/{i}",
            cylinders=[
                fm.CylinderPrimitive(
                    pose=_pose(fm, d.x, d.y, d.z + 0.06, 0.0),
                    size=fm.Vector3(x=0.08, y=0.08, z=0.12),
                    bottom_scale=1.0,
                    top_scale=1.0,
                    color=fm.Color(r=r, g=g, b=b, a=0.8),
                )
            ],
            texts=[
                fm.TextPrimitive(
                    pose=_pose(fm, d.x, d.y, d.z + 0.25, 0.0),
                    billboard=True,
                    font_size=14.0,
                    scale_invariant=True,
                    text=d.category,
                    color=fm.Color(r=1.0, g=1.0, b=1.0, a=1.0),
                )
            ],
        )

    @staticmethod
    def _goal(fm: ModuleType, stamp: Timestamp, i: int, g: Goal, latest: bool) -> SceneEntity:
        a = 1.0 if latest else 0.35
        return fm.SceneEntity(
            timestamp=stamp,
            frame_id=g.frame,
            id=f"goal/{i}",
            arrows=[
                fm.ArrowPrimitive(
                    pose=_pose(fm, g.x, g.y, 0.02, g.yaw),
                    shaft_length=0.25,
                    shaft_diameter=0.04,
                    head_length=0.1,
                    head_diameter=0.1,
                    color=fm.Color(r=0.1, g=0.9, b=0.2, a=a),
                )
            ],
        )


def _timestamp(t: float) -> Timestamp:
    import foxglove.messages as fm

    sec, nsec = divmod(int(round(t * 1e9)), 1_000_000_000)
    return fm.Timestamp(sec, nsec)


def _pose(fm: ModuleType, x: float, y: float, z: float, yaw: float) -> Pose:
    return fm.Pose(
        position=fm.Vector3(x=x, y=y, z=z),
        orientation=fm.Quaternion(x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2)),
    )
