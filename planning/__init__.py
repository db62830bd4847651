"""planning: the MoveIt stand-in of actorbt.

Layering: this is a plain library. It imports neither ``bt_engine`` nor ``sim``
nor ``actors``; ``actors`` import it. It reads the robot URDF from
``sim/models`` as a file, which imports nothing.

Modules, one concept each:

* :mod:`planning.urdf`: URDF reader (links, joints, limits).
* :mod:`planning.kinematics`: FK and analytic IK of the 4-DOF arm.
* :mod:`planning.scene`: the planning scene, a pybullet ``DIRECT`` collision model.
* :mod:`planning.motion`: joint-space planning (straight line, else OMPL).
* :mod:`planning.trajectory`: ruckig timing and the jerk-limited stop.
* :mod:`planning.grid`: occupancy grids and their inflation.
* :mod:`planning.base_planner`: base paths on the inflated grid.
* :mod:`planning.viewpoints`: places from which a search sees a whole map.
* :mod:`planning.frontiers`: where to drive next to map more (frontier exploration).
* :mod:`planning.tf_buffer`: the transform tree (tf2's buffer) fed from ``/tf``.
* :mod:`planning.tf_listener`: that buffer kept up to date from a bus (tf2_ros's listener).
* :mod:`planning.errors`, :mod:`planning.failure`: exceptions and failure reasons.

Planners return frozen result values with ``ok``, ``failure`` and ``message``
instead of raising for queries that cannot be solved; ``raise_for_failure()``
turns them into :class:`PlanningError` subclasses.
"""

from .base_planner import BasePath, GridPlanner, plan_base_path
from .errors import (
    InvalidInputError,
    InvalidStateError,
    ModelError,
    NoPathError,
    PlanningError,
    SceneError,
    TrajectoryError,
    UnreachableError,
)
from .failure import FailureReason
from .grid import Costmap, OccupancyGrid, inflate, with_obstacles
from .kinematics import ArmKinematics, ArmPose, IKResult, IKSolution
from .motion import PLANNERS, MotionPlan, path_length, plan_joint_motion, plan_pose_motion, seed_planners
from .scene import CollisionReport, Contact, Obstacle, PlanningScene
from .trajectory import JointLimits, SampledTrajectory, TimedTrajectory, stop_trajectory, time_trajectory
from .urdf import UrdfJoint, UrdfRobot, default_urdf_path, read_urdf

__all__ = [
    # errors
    "PlanningError",
    "ModelError",
    "InvalidInputError",
    "UnreachableError",
    "InvalidStateError",
    "NoPathError",
    "TrajectoryError",
    "SceneError",
    "FailureReason",
    # robot model
    "UrdfJoint",
    "UrdfRobot",
    "read_urdf",
    "default_urdf_path",
    "ArmKinematics",
    "ArmPose",
    "IKResult",
    "IKSolution",
    # planning scene
    "PlanningScene",
    "Obstacle",
    "Contact",
    "CollisionReport",
    # arm motion
    "MotionPlan",
    "PLANNERS",
    "plan_joint_motion",
    "plan_pose_motion",
    "path_length",
    "seed_planners",
    # timing
    "JointLimits",
    "TimedTrajectory",
    "SampledTrajectory",
    "time_trajectory",
    "stop_trajectory",
    # base
    "OccupancyGrid",
    "Costmap",
    "inflate",
    "with_obstacles",
    "GridPlanner",
    "BasePath",
    "plan_base_path",
]
