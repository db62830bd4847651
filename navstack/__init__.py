"""The robot-side stand-in for AMCL + Nav2: a localiser (and, next, a navigation server).

A plain library (numpy, scipy) at its core, with no transport:

* :mod:`navstack.map_io`: occupancy maps, map_server's YAML + PGM, nav_msgs/OccupancyGrid;
* :mod:`navstack.likelihood_field`: AMCL's likelihood-field laser model, vectorised;
* :mod:`navstack.particle_filter`: the Monte Carlo filter (motion model, KLD resampling,
  clusters, uniform and scan-informed global localisation, augmented MCL);
* :mod:`navstack.amcl`: AMCL's node logic: update thresholds, the pose between updates,
  delocalisation detection and recovery;
* :mod:`navstack.synthetic`: a synthetic robot and world for tests and benchmarks.

:mod:`navstack.localiser` puts it on the runtime's bus as a SubSystem (AMCL's topics).
navstack may import bt_engine and planning, never sim or actors.
"""
from .amcl import Amcl, AmclParams, Scan, Status
from .likelihood_field import LaserModelParams, LikelihoodField
from .map_io import MapError, OccupancyMap, read_map_yaml, write_map_yaml
from .particle_filter import Estimate, FilterParams, ParticleFilter

__all__ = ["Amcl", "AmclParams", "Scan", "Status", "LaserModelParams", "LikelihoodField",
           "MapError", "OccupancyMap", "read_map_yaml", "write_map_yaml", "Estimate",
           "FilterParams", "ParticleFilter"]
