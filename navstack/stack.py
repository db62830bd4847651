"""The Nav2 + AMCL stand-in as one SubSystem: what ``navstack: navstack:NavStack`` in
actorbt.yaml starts next to the robot's actors.

On a real robot, Nav2 and AMCL serve ``/navigate_to_pose`` and publish map -> odom on
``/tf``: leave navstack out there. Here it gives the same interfaces from the same inputs
(``/scan``, ``/odom``, ``/tf``, ``/tf_static``, ``/map``, ``/initialpose``):

* ``localiser`` (:class:`navstack.localiser.Localiser`, AMCL): map -> odom on /tf and
  ``/amcl_pose``; actors ``localisation_status`` and ``localise_globally``;
* ``navigator`` (:class:`navstack.navigator.Navigator`, Nav2's planner, controller and
  recoveries): the ``/navigate_to_pose`` action.

Where the robot starts: the user says so on ``/initialpose`` (RViz's "2D Pose Estimate";
``actorbt demo`` and ``eval`` publish the world's start pose there, as a user would). When
nobody has said so ``global_after`` seconds after the first scan, the localiser finds the
robot on the whole map from its scans (so ``actorbt call goto ...`` works on its own).
"""
from __future__ import annotations

from bt_engine import SubSystem

from .localiser import Localiser
from .navigator import Navigator

#: [s] with no /initialpose this long after the first scan, localise globally
GLOBAL_AFTER = 2.0


class NavStack(SubSystem):
    """AMCL's and Nav2's stand-in: the localiser and the navigation server.

    Args:
        localiser: overrides of the localiser's parameters (AmclParams, FilterParams,
            LaserModelParams) by name
        navigator: overrides of NavigatorParams by name
        seed: the particle filter's random seed
        initial_pose: (x, y, yaw) to start from (AMCL's set_initial_pose); None: wait for
            /initialpose
        global_after: [s] localise globally when no initial pose came this long after
            the first scan (None: wait for it for ever, as AMCL)
    """

    def __init__(self, localiser: dict | None = None, navigator: dict | None = None, seed: int = 0,
                 initial_pose: tuple | None = None, global_after: float | None = GLOBAL_AFTER) -> None:
        super().__init__()
        self.localiser = self.add_subsystem("localiser", Localiser, params=localiser, seed=seed,
                                            initial_pose=initial_pose, global_after=global_after)
        self.navigator = self.add_subsystem("navigator", Navigator, params=navigator)

    def close(self) -> None:
        self.navigator.close()
        self.localiser.close()
