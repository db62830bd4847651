"""ROS 2 (rclpy) side of the engine, one concept per module. Imports go down this list:

    rostypes     names for the values of no fixed type (an actor's result, a QoS setting)
    names        node, action and service names of ``actorbt serve`` (and namespaces)
    error_codes  why a goal ended -> the ``error_code`` constants of the interface files
    yamlio       values as YAML text (results, and the arguments a client sends)
    goals        a goal's YAML text -> a validated call (the one place goals are decoded)
    host         RosHost: one rclpy Context, its nodes and one executor thread
    qos          rclpy QoS profiles for the named settings of ``bt_engine.bus.qos``
    client       goals and service calls sent from the executor thread
    transport    RosTransport: the bus interface (``bt_engine.bus``) over rclpy
    goal_server  one action server and the goals it runs: accept, cancel, result
    call_server  ``/actorbt/call`` (CallActor)
    tree_server  ``/actorbt/tree/<name>`` (RunTree): one goal at a time, progress, traces
    describe_service  ``/actorbt/describe``: the JSON Schema of served trees and actors
    call_now_service  ``/actorbt/call_now``: a quick actor as a service
    tree_watch   the trees folder polled; a change reloads its trees
    server       ``serve(rt)``: the node, its actions and services, the served trees, shutdown
    remote       Remote: a client of a running ``actorbt serve``; what it serves (ROS graph)
    shell        RemoteShell: ``actorbt rshell``, one warm client for many calls
    command_app  what the commands below use of bt_cli's App (a protocol)
    cli          ``actorbt serve``, ``actorbt goal``, ``actorbt rcall``, ``actorbt rshell``

Recording and viewing (``--bag``, ``--foxglove``; docs/recording.md):

    live_options     the options and their early checks (imported when the parser is built)
    cdr              messages as CDR bytes (rclpy), their definitions and hashes (rosbags)
    tree_status      the tree's status on /actorbt/status (diagnostic_msgs/DiagnosticArray)
    compressed       sensor_msgs/Image -> CompressedImage, as image_transport does
    bag              BagRecorder: the robot's topics, the status and the trace to rosbag2
    bag_replay       ``actorbt replay`` of a bag (its /actorbt/trace)
    foxglove_scene   the robot's body, detections, goals and path as Foxglove messages
    foxglove_view    FoxgloveView: the Foxglove SDK server and its channels
    foxglove_layout  docs/foxglove_layout.json
    live             LiveSession: all of it around one run, demo episode or serve

Layering: ``ros`` sits above ``bus`` (it implements the bus interface) and the trees
layer (it serves trees); nothing below imports ``bt_ros``, and only ``bt_cli``,
the top layer, imports ``bt_ros.cli``.

Nothing here imports rclpy until it is used, so ``actorbt`` starts quickly and
builds without ROS still run the local bus. Discovery stays on this machine unless
``ROS_AUTOMATIC_DISCOVERY_RANGE`` says otherwise (see ``host.py``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:  # what __getattr__ imports when a name is first used
    from .host import RosHost
    from .live import LiveSession
    from .live_options import LiveOptions, add_live_options
    from .remote import Remote
    from .server import Server, serve
    from .transport import RosTransport

__all__ = ["LiveOptions", "LiveSession", "Remote", "RosHost", "RosTransport", "Server", "add_live_options", "serve"]

_HOMES = {
    "Remote": "remote",
    "RosHost": "host",
    "RosTransport": "transport",
    "Server": "server",
    "serve": "server",
    "LiveSession": "live",
    "LiveOptions": "live_options",
    "add_live_options": "live_options",
}


def __getattr__(name: str) -> object:
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(name)
    import importlib

    return getattr(importlib.import_module(f"{__name__}.{home}"), name)
