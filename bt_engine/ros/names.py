"""The names a server and its clients agree on: node, action and topic names of
``actorbt serve``, and how a goal is identified in a rejection message.

    /actorbt/call          CallActor: call any actor
    /actorbt/tree/<name>   RunTree: one action per tree (``nav.patrol`` -> ``nav/patrol``)
    /actorbt/rejections    std_msgs/String, reliable, transient local: why goals were
                           rejected (the action protocol carries no reason)
"""
from __future__ import annotations

import re
from typing import Any

NODE_NAME = "actorbt"
CALL_ACTION = "/actorbt/call"
TREE_PREFIX = "/actorbt/tree/"
REJECTIONS_TOPIC = "/actorbt/rejections"
#: rejections kept for late subscribers on /actorbt/rejections
REJECTIONS_DEPTH = 50

__all__ = ["CALL_ACTION", "NODE_NAME", "REJECTIONS_DEPTH", "REJECTIONS_TOPIC", "TREE_PREFIX",
           "goal_text", "rejections_qos", "tree_action_name", "tree_of_action"]


def tree_action_name(tree: str) -> str:
    """``/actorbt/tree/<name>`` for a tree path (dots become slashes)."""
    parts = []
    for part in tree.replace("/", ".").split("."):
        part = re.sub(r"[^A-Za-z0-9_]", "_", part)
        if part and part[0].isdigit():
            part = "_" + part
        if part:
            parts.append(part)
    return TREE_PREFIX + "/".join(parts)


def tree_of_action(action: str) -> str | None:
    """The tree path an action name serves (``/actorbt/tree/nav/patrol`` -> ``nav.patrol``),
    or None when it is not a tree action."""
    if not action.startswith(TREE_PREFIX) or len(action) == len(TREE_PREFIX):
        return None
    return action[len(TREE_PREFIX):].replace("/", ".")


def goal_text(goal: Any) -> str:
    """What identifies a goal in a rejection message: the inputs of a RunTree goal,
    ``actor`` and ``args_yaml`` of a CallActor goal."""
    if hasattr(goal, "inputs_yaml"):
        return goal.inputs_yaml
    return f"{goal.actor}\n{goal.args_yaml}"


def rejections_qos() -> Any:
    """The QoS of /actorbt/rejections, on both sides (imports rclpy)."""
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    return QoSProfile(depth=REJECTIONS_DEPTH, reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL)
