"""The first step of an episode that went wrong (an observer of its trees).

A failed episode's tree fails at its last step (a search that finds nothing more); what
went wrong first is often earlier (the grasps that knocked the object over). Calls end
innermost first, so the first failed call is the step itself, not a tree around it.
"""

from __future__ import annotations

from typing import Any

from bt_engine.trees import TreeObserver


class FirstFailure(TreeObserver):
    """``node`` (``tree:path``) and ``reason`` of the first actor call that raised; empty
    while none did."""

    def __init__(self) -> None:
        self.node = ""
        self.reason = ""

    def actor_finished(self, run: Any, leaf: Any, txn: Any) -> None:
        if self.node or txn.state.value != "failed":
            return
        self.node = f"{run.mission.name}:{leaf.path}"
        self.reason = f"{leaf.node.actor}: {type(txn.error).__name__}: {txn.error}"
