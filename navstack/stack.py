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

from bt_engine import ActorbtError, SubSystem, actor

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


class MappingStack(SubSystem):
    """slam_toolbox's and Nav2's stand-in while the robot maps: the mapper (``/map`` and
    map -> odom from /scan and /odom) and the navigation server, with no map_server and
    no localiser. ``localise_on_map`` then switches to the localiser on the map just
    made, as slam_toolbox's localization mode does.

    Args:
        mapper: keyword arguments of :class:`navstack.mapper.Mapper`
        navigator: overrides of NavigatorParams by name
        localiser: overrides of the localiser's parameters, for after the mapping
        seed: the localiser's random seed
    """

    def __init__(self, mapper: dict | None = None, navigator: dict | None = None,
                 localiser: dict | None = None, seed: int = 0) -> None:
        super().__init__()
        from .mapper import Mapper   # here: the SLAM code is not needed by every run
        self._localiser_args = {"params": localiser, "seed": seed}
        self.mapper = self.add_subsystem("mapper", Mapper, **(mapper or {}))
        self.navigator = self.add_subsystem("navigator", Navigator, params=navigator)
        self.localiser: Localiser | None = None

    @actor
    def localise_on_map(self) -> list[float]:
        """Stop mapping (the map stays on /map, latched) and localise on it from where
        the robot is now. Returns that pose [x m, y m, yaw rad]."""
        if self.localiser is not None:
            raise ActorbtError("already localising on the map made")
        pose = self.run_actor("stop_mapping")
        self.localiser = self.add_subsystem("localiser", Localiser, initial_pose=tuple(pose),
                                            **self._localiser_args)
        return pose

    def close(self) -> None:
        self.navigator.close()
        self.mapper.close()
        if self.localiser is not None:
            self.localiser.close()
