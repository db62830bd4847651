"""``/actorbt/describe`` (``actorbt_interfaces/srv/Describe``): what ``actorbt serve``
offers, as JSON Schema, so a ROS client can build goals without reading our source.

The response's ``tools_json`` is a JSON object::

    {"namespace": "/robot1", "call_action": "/robot1/actorbt/call",
     "tools": [{"name": "steps_tree", "description": ..., "parameters": {JSON Schema},
                "returns": ..., "is_tree": true,
                "action": "/robot1/actorbt/tree/steps_tree",
                "action_type": "actorbt_interfaces/action/RunTree"}, ...]}

Each tool is the catalog's description (:func:`bt_engine.catalog.tool_schema`, what
``actorbt catalog --json`` prints) plus the action that runs it: a served tree its own
RunTree action, any other actor ``/actorbt/call``. The request's ``name`` narrows the
list to one tree or actor (its path; else every actor of that name) or a subsystem's
actors; a name that matches nothing answers ``UNKNOWN_NAME`` with close matches.
"""

from __future__ import annotations

import difflib
import json
import logging
from typing import TYPE_CHECKING, Callable, TypedDict

from bt_engine.catalog import tool_schema
from .rostypes import Json

if TYPE_CHECKING:
    from rclpy.node import Node
    from rclpy.service import Service

    from bt_engine import ActorRef, Runtime
    from bt_engine.bus.messages import RosMessage

log = logging.getLogger("actorbt.ros.server")

__all__ = ["DescribeService", "describe"]

RUN_TREE = "actorbt_interfaces/action/RunTree"
CALL_ACTOR = "actorbt_interfaces/action/CallActor"


class Description(TypedDict):
    """The describe document (``tools_json``)."""

    namespace: str
    call_action: str
    #: each actor's JSON Schema (bt_engine.catalog.tool_schema) with ``action`` and ``action_type``
    tools: list[dict[str, Json]]


def describe(
    refs: list[ActorRef], tree_actions: dict[str, str], call_action: str, namespace: str, name: str = ""
) -> tuple[Description, list[str]]:
    """The describe document for actors ``refs`` (``tree_actions``: tree path -> its
    action), narrowed to ``name``; and, when nothing matched, the close matches."""
    # an exact path wins: "steps_tree" is the tree, not also some "nav.steps_tree"
    chosen = [r for r in refs if r.path == name] or [r for r in refs if _matches(r, name)] if name else list(refs)
    tools = []
    for ref in sorted(chosen, key=lambda r: r.path):
        try:
            tool = tool_schema(ref)
        except Exception as e:  # one odd signature must not hide the others
            log.warning("describe: %s has no schema: %s", ref.path, e)
            tool = {"name": ref.path, "description": f"(no schema: {e})"}
        action = tree_actions.get(ref.path)
        tool["action"] = action or call_action
        tool["action_type"] = RUN_TREE if action else CALL_ACTOR
        tools.append(tool)
    doc: Description = {"namespace": namespace or "/", "call_action": call_action, "tools": tools}
    missing = (
        []
        if tools or not name
        else difflib.get_close_matches(name, sorted({r.path for r in refs} | {r.name for r in refs}), n=5, cutoff=0.5)
    )
    return doc, missing


def _matches(ref: ActorRef, name: str) -> bool:
    return ref.path == name or ref.name == name or ref.path.startswith(name + ".")


class DescribeService:
    """The service on the server's node (executor thread).

    Args:
        rt: the runtime whose actors are described.
        name: the resolved service name.
        served: returns the served trees (path -> action), the call action and the
            namespace, now (trees come and go with the watched folder).
    """

    def __init__(self, rt: Runtime, name: str, served: Callable[[], tuple[dict[str, str], str, str]]) -> None:
        self.rt = rt
        self.name = name
        self._served = served
        self._service: Service | None = None
        self._node: Node | None = None

    def create(self, node: Node) -> None:
        from actorbt_interfaces.srv import Describe

        self._node = node
        self._service = node.create_service(Describe, self.name, self._on_request)

    def destroy(self) -> None:
        if self._service is not None and self._node is not None:  # create() sets both
            self._node.destroy_service(self._service)
            self._service = None

    def _on_request(self, request: RosMessage, response: RosMessage) -> RosMessage:
        try:
            trees, call_action, namespace = self._served()
            # the actors, and the trees that have an action
            refs = self.rt.run_on_hub(
                lambda: [r for r in self.rt.root.all_actors() if not r.is_tree or r.path in trees]
            )
            doc, close = describe(refs, trees, call_action, namespace, request.name.strip())
        except Exception as e:
            log.exception("describe failed")
            response.error_code = response.UNKNOWN_NAME
            response.error_msg = f"describe failed: {type(e).__name__}: {e}"
            return response
        if not doc["tools"] and request.name.strip():
            hint = f"; did you mean: {', '.join(close)}?" if close else ""
            response.error_code = response.UNKNOWN_NAME
            response.error_msg = f"no served tree or actor {request.name.strip()!r}{hint}"
        response.tools_json = json.dumps(doc, default=str)
        return response
