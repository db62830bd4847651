"""The errors the catch actors (actors/catch.py) raise."""

from __future__ import annotations

from bt_engine import ActorbtError


class GraspError(ActorbtError):
    """The grasp missed or the object slipped out."""


class ApproachError(ActorbtError):
    """The robot could not line up with the object."""
