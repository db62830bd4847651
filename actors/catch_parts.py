"""What Catcher's mixins (catch_approach.Approaching, catch_place.Placing) use of the
Catcher they are part of (actors/catch.py), declared once for the type checker. At run
time the mixins are plain classes: Catcher adds SubSystem and defines these helpers.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from bt_engine import SubSystem

    from .strategies import GraspPlan, Strategy

    class CatcherParts(SubSystem):
        # Catcher's own (actors/catch.py)
        def _strategy(self, target: Any, category: str | None) -> Strategy: ...
        def _where_now(self, target: dict) -> dict: ...
        @staticmethod
        def _plan(strategy: Strategy, target: dict) -> GraspPlan: ...
        def _face(self, xy: tuple[float, float], strategy: Strategy) -> float: ...
        def _drive_in(self, distance: float) -> float: ...
        def _pass_over(self, xy: tuple[float, float], category: str) -> None: ...
        def _fresh_views_first(
            self, poses: list[tuple[float, float, float]], xy: tuple[float, float]
        ) -> list[tuple[float, float, float]]: ...

        # Approaching's, which Placing uses too
        def _free_standoff(
            self,
            robot_xy: tuple[float, float],
            xy: tuple[float, float],
            strategy: Strategy,
            extra: float = 0.0,
            others: Sequence[dict] = (),
            corridor: bool = True,
            object_yaw: float | None = None,
            plan: GraspPlan | None = None,
        ) -> list[tuple[float, float, float]]: ...
else:
    CatcherParts = object
