"""Why a planning query failed: one enum shared by the arm and base planners."""

from __future__ import annotations

import enum

from .errors import (
    InvalidInputError,
    InvalidStateError,
    NoPathError,
    PlanningError,
    UnreachableError,
)

__all__ = ["FailureReason"]


class FailureReason(enum.Enum):
    """The reason a planning result has ``ok == False``."""

    INVALID_INPUT = "invalid_input"
    """An argument had the wrong length, a non-finite value or an unknown option."""

    UNREACHABLE = "unreachable"
    """Inverse kinematics has no solution inside the joint limits."""

    START_INVALID = "start_invalid"
    """The start is in collision, outside the joint limits, or (base) on an
    occupied or unknown cell."""

    GOAL_INVALID = "goal_invalid"
    """Every goal candidate is in collision or outside the limits, or (base) the
    goal cell is occupied, inflated or unknown."""

    TIMEOUT = "timeout"
    """The planner did not find a path before its time budget ran out."""

    NO_PATH = "no_path"
    """The search space was exhausted: start and goal are not connected."""

    RECHECK_FAILED = "recheck_failed"
    """A path was found but the dense re-check of its segments hit a collision."""

    @property
    def error_type(self) -> type[PlanningError]:
        """The exception class that ``raise_for_failure`` raises for this reason."""
        return _ERRORS[self]


_ERRORS: dict[FailureReason, type[PlanningError]] = {
    FailureReason.INVALID_INPUT: InvalidInputError,
    FailureReason.UNREACHABLE: UnreachableError,
    FailureReason.START_INVALID: InvalidStateError,
    FailureReason.GOAL_INVALID: InvalidStateError,
    FailureReason.TIMEOUT: NoPathError,
    FailureReason.NO_PATH: NoPathError,
    FailureReason.RECHECK_FAILED: NoPathError,
}
