"""The robot-side stand-in for AMCL + Nav2: a localiser and a navigation server.

A plain library (numpy, scipy) at its core, with no transport:

* :mod:`navstack.map_io`: occupancy maps, map_server's YAML + PGM, nav_msgs/OccupancyGrid;
* :mod:`navstack.likelihood_field`: AMCL's likelihood-field laser model, vectorised;
* :mod:`navstack.particle_filter`: the Monte Carlo filter (motion model, KLD resampling,
  clusters, uniform and scan-informed global localisation, augmented MCL);
* :mod:`navstack.amcl`: AMCL's node logic: update thresholds, the pose between updates,
  delocalisation detection and recovery;
* :mod:`navstack.smoothing`: a Kalman filter on the published pose (odometry as motion,
  each estimate as a measurement), against the estimate's update-to-update jitter;
* :mod:`navstack.synthetic`: a synthetic robot and world for tests and benchmarks.

On the runtime's bus (SubSystems, imported on first use):

* :mod:`navstack.localiser`: AMCL's topics (map -> odom on /tf, /amcl_pose);
* :mod:`navstack.navigator`: Nav2's ``/navigate_to_pose`` action (plan, follow, avoid);
* :mod:`navstack.stack`: :class:`NavStack`, both under one SubSystem (actorbt.yaml's
  ``navstack: navstack:NavStack``);
* :mod:`navstack.tf`: the tf listener (from planning) and the map -> odom message.

navstack may import bt_engine and planning, never sim or actors.
"""

from .amcl import Amcl, AmclParams, Scan, Status
from .likelihood_field import LaserModelParams, LikelihoodField
from .map_io import MapError, OccupancyMap, read_map_yaml, write_map_yaml
from .particle_filter import Estimate, FilterParams, ParticleFilter


def __getattr__(name: str):
    # the SubSystems need bt_engine and the ROS messages: imported on first use (PEP 562)
    if name == "NavStack":
        from .stack import NavStack

        return NavStack
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    "NavStack",
    "Amcl",
    "AmclParams",
    "Scan",
    "Status",
    "LaserModelParams",
    "LikelihoodField",
    "MapError",
    "OccupancyMap",
    "read_map_yaml",
    "write_map_yaml",
    "Estimate",
    "FilterParams",
    "ParticleFilter",
]
