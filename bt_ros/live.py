"""What ``--bag`` and ``--foxglove`` add to a run (``run``, ``demo``, ``serve``): the
tree's status on /actorbt/status, a bag recorder (with the run's trace, when there is
one run), and a Foxglove view, opened together on one runtime and closed in reverse.
"""

from __future__ import annotations

import sys
from typing import TYPE_CHECKING, Callable, TextIO

from .bag import DEFAULT_TOPICS, BagRecorder, BagTopic
from .live_options import LiveOptions
from .tree_status import TreeStatusPublisher

if TYPE_CHECKING:
    from bt_engine import Runtime
    from bt_engine.trees import Mission, TraceRecorder, TreeHost
    from .foxglove_view import FoxgloveView

__all__ = ["LiveSession", "around_run"]


class LiveSession:
    """Opens what ``options`` ask for on ``rt`` and ``host`` (a TreeHost).

    With ``tree``, the bag also holds that run's trace on /actorbt/trace (a
    :class:`~bt_engine.trees.TraceRecorder` writing into it: ``inputs`` and ``seed`` go
    to its header). Open it before the run starts; :meth:`close` after it ended.

    Raises:
        BagError, FoxgloveError: the bag folder is not new, the port is taken.
    """

    def __init__(
        self,
        rt: Runtime,
        host: TreeHost,
        options: LiveOptions,
        *,
        tree: str | None = None,
        inputs: dict | None = None,
        seed: int | None = None,
        out: TextIO | None = None,
    ) -> None:
        self.options = options
        self.status: TreeStatusPublisher | None = None
        self.view: FoxgloveView | None = None
        self.bag: BagRecorder | None = None
        self.trace: TraceRecorder | None = None
        #: messages the bag holds, once closed
        self.recorded = 0
        try:
            self.status = TreeStatusPublisher(host)
            topics = DEFAULT_TOPICS + tuple(BagTopic(*t) for t in options.topics)
            if options.foxglove is not None:
                from .foxglove_scene import Body
                from .foxglove_view import FoxgloveView

                body = None if options.body is None else Body(*options.body)
                self.view = FoxgloveView(
                    rt, port=options.foxglove, host=options.foxglove_host, topics=topics, body=body
                )
                print(
                    f"actorbt: Foxglove view on {self.view.url} (open it in Foxglove: "
                    "Open connection, Foxglove WebSocket)",
                    file=out or sys.stderr,
                    flush=True,
                )
            if options.bag is not None:
                self.bag = BagRecorder(rt, options.bag, topics)
                if tree is not None:
                    from bt_engine.trees import TraceRecorder

                    self.trace = TraceRecorder(self.bag.trace_sink(), host, tree=tree, inputs=inputs, seed=seed)
        except BaseException:
            self.close()
            raise

    def close(self) -> None:
        """Finish the bag, stop the view, stop publishing the status (idempotent)."""
        for part in ("trace", "bag", "view", "status"):
            item = getattr(self, part)
            if item is not None:
                setattr(self, part, None)
                item.close()
                if part == "bag":
                    self.recorded = sum(item.counts.values())

    def summary(self) -> str:
        """``bag:       DIR (N messages)``, the line ``run`` and ``demo`` end with."""
        if not self.options.bag:
            return ""
        return f"bag:       {self.options.bag} ({self.recorded} messages)"


def around_run(
    options: LiveOptions, seed: int | None = None
) -> Callable[[Runtime, TreeHost, Mission, dict], LiveSession]:
    """For ``run``: ``around(rt, host, mission, inputs)`` opens the session of one run."""

    def around(rt: Runtime, host: TreeHost, mission: Mission, inputs: dict) -> LiveSession:
        return LiveSession(rt, host, options, tree=mission.name, inputs=inputs, seed=seed)

    return around
