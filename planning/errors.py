"""Exceptions of the planning library.

Every error this package raises derives from :class:`PlanningError`. Planning
*outcomes* that are expected to fail sometimes (an unreachable pose, no path
within the timeout, a blocked corridor) are not raised by the planners: they
come back as a result with ``ok == False`` and a :class:`FailureReason`. Call
``result.raise_for_failure()`` to turn such a result into the matching
exception below.
"""

from __future__ import annotations

__all__ = [
    "PlanningError",
    "ModelError",
    "InvalidInputError",
    "UnreachableError",
    "InvalidStateError",
    "NoPathError",
    "TrajectoryError",
    "SceneError",
]


class PlanningError(Exception):
    """Root of every error raised by :mod:`planning`."""


class ModelError(PlanningError):
    """The robot description cannot be used (missing link or joint, bad chain)."""


class InvalidInputError(PlanningError, ValueError):
    """An argument has the wrong shape, a non-finite value or is out of range."""


class UnreachableError(PlanningError):
    """No inverse-kinematics solution exists within the joint limits."""


class InvalidStateError(PlanningError):
    """A start or goal state is in collision or outside the joint limits."""


class NoPathError(PlanningError):
    """The planner found no collision-free path (timeout, blocked, unknown space)."""


class TrajectoryError(PlanningError):
    """Time parameterisation failed (ruckig rejected the input or the limits)."""


class SceneError(PlanningError):
    """The planning scene was asked for something it does not hold."""
