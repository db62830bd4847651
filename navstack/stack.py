"""The Nav2 + AMCL stand-in as one SubSystem: what ``navstack: navstack:NavStack`` in
actorbt.yaml starts next to the robot's actors.

On a real robot, Nav2 and AMCL serve ``/navigate_to_pose`` and publish map -> odom on
``/tf``: leave navstack out there. Here it gives the same interfaces from the same inputs
(``/scan``, ``/odom``, ``/tf``, ``/tf_static``, ``/map``, ``/initialpose``):

* ``localiser`` (:class:`navstack.localiser.Localiser`, AMCL): map -> odom on /tf and
  ``/amcl_pose``; actors ``localisation_status`` and ``localise_globally``;
* ``navigator`` (:class:`navstack.navigator.Navigator`, Nav2's planner, controller and
  recoveries): the ``/navigate_to_pose`` action;
* ``mapper`` (:class:`navstack.mapper.Mapper`, slam_toolbox), made by ``start_mapping`` in
  a world with no map server: the localiser pauses while the mapper publishes /map and
  map -> odom; ``localise_on_map`` hands back to the localiser on the map made.

Where the robot starts: the user says so on ``/initialpose`` (RViz's "2D Pose Estimate";
``actorbt demo`` and ``eval`` publish the world's start pose there, as a user would). When
nobody has said so ``global_after`` seconds after the first scan, the localiser finds the
robot on the whole map from its scans (so ``actorbt call goto ...`` works on its own).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from bt_engine import ActorbtError, SubSystem, actor

from .localiser import Localiser
from .navigator import Navigator

if TYPE_CHECKING:
    from .mapper import Mapper

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
        mapper: keyword arguments of :class:`navstack.mapper.Mapper` (start_mapping)
    """

    def __init__(
        self,
        localiser: dict | None = None,
        navigator: dict | None = None,
        seed: int = 0,
        initial_pose: tuple | None = None,
        global_after: float | None = GLOBAL_AFTER,
        mapper: dict | None = None,
    ) -> None:
        super().__init__()
        self.localiser = self.add_subsystem(
            "localiser",
            Localiser,
            params=localiser,
            seed=seed,
            initial_pose=initial_pose,
            global_after=global_after,
        )
        self.navigator = self.add_subsystem("navigator", Navigator, params=navigator)
        self.mapper: Mapper | None = None  # made by start_mapping
        self._mapper_args = dict(mapper or {})

    @actor
    def start_mapping(self) -> list[float] | None:
        """Map the world from /scan and /odom (slam_toolbox's job) instead of localising on
        a given map: the mapper publishes /map and map -> odom from now on, starting from the
        pose the user gave (/initialpose) or the current estimate. For a world with no map
        server. Returns that start pose [x m, y m, yaw rad] (None: the origin)."""
        from .mapper import Mapper  # here: the SLAM code is not needed by every run

        if self.mapper is not None:
            raise ActorbtError("the robot maps already (one mapping per run)")
        start = self.localiser.pause()
        args = dict(self._mapper_args)
        if start is not None:
            args.setdefault("start_pose", start)
        self.mapper = self.add_subsystem("mapper", Mapper, **args)
        return [float(v) for v in start] if start is not None else None

    @actor
    def localise_on_map(self) -> list[float]:
        """Stop mapping (the map stays on /map, latched, as map_server would serve it) and
        localise on it from where the mapper has the robot now (slam_toolbox's hand-over to
        AMCL). Returns that pose [x m, y m, yaw rad]."""
        mapper = self._mapping()
        pose = mapper.stop()
        map_msg = mapper.map_msg()
        assert map_msg is not None  # stop() raised unless a scan has started the map
        self.localiser.resume(tuple(pose), map_msg)
        return pose

    def _mapping(self) -> Mapper:
        if self.mapper is None:
            raise ActorbtError("not mapping: call start_mapping first (in a world with no map server)")
        return self.mapper

    @actor
    def save_map(self, path: str) -> dict:
        """Write the map being made as map_server YAML + PGM (nav2's map_saver). Returns
        the files, the size in cells, the resolution [m], keyframes and metres travelled.

        Args:
            path: the YAML file to write (the PGM goes beside it), or a folder for map.yaml
        """
        return self._mapping().save(path)

    @actor(read_only=True)
    def mapping_status(self) -> dict:
        """How the mapping is doing: scans taken, keyframes, loop closures, the pose
        [x m, y m, yaw rad] in the map frame, and whether it has stopped (frozen)."""
        return self._mapping().status()

    def close(self) -> None:
        self.navigator.close()
        self.localiser.close()
        if self.mapper is not None:
            self.mapper.close()
