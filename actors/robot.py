"""The whole robot: navigation, arm, perception, search, catch, exploration and tidy-up
under one SubSystem."""

from __future__ import annotations

from bt_engine import SubSystem

from .catch import Catcher
from .exploration import Exploration
from .manipulator import Manipulator
from .navigation import Navigation
from .perception import Perception
from .search import Search
from .tidy import Tidy


class Robot(SubSystem):
    """A TurtleBot3-like base with an OpenManipulator-X-like arm, reached through topics
    and actions: the robot's localisation on /tf and its navigation's /navigate_to_pose
    (Nav2 and AMCL on a robot; navstack's stand-in in the simulator), the arm's and the
    gripper's controllers, the camera."""

    def __init__(self) -> None:
        super().__init__()
        self.add_subsystem("navigation", Navigation)
        self.add_subsystem("arm", Manipulator)
        self.add_subsystem("perception", Perception)
        self.add_subsystem("search", Search)
        self.add_subsystem("catch", Catcher)
        self.add_subsystem("exploration", Exploration)
        self.add_subsystem("tidy", Tidy)
