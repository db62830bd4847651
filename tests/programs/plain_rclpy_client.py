"""A plain rclpy client of `actorbt serve`, as a ROS user would write it: rclpy and the
actorbt_interfaces messages only, none of actorbt's own client code.

    python plain_rclpy_client.py '[{"op": "goal", "action": "/robot1/actorbt/tree/t", "inputs": "{a: 1}"}, ...]'

Runs the steps in order and prints one JSON list, a result per step:

- ``goal``: action, inputs -> accepted, status, the result's fields, and ``events``:
  every feedback (with its arrival time) and the result, in the order they arrived.
- ``describe``: service, name -> error_code, error_msg, tools (the parsed JSON).
- ``call_now``: service, actor, args -> the response's fields.
- ``wait_action``: action, present (bool), timeout -> found (whether the action's
  presence became as asked within timeout).
"""

import json
import sys
import time

import rclpy
from rclpy.action import ActionClient
from rclpy.action.graph import get_action_names_and_types

from actorbt_interfaces.action import RunTree
from actorbt_interfaces.srv import CallActorNow, Describe

WAIT = 15.0  # seconds for discovery (between processes about 2 s)


def spin_until(node, future, timeout):
    end = time.monotonic() + timeout
    while not future.done() and time.monotonic() < end:
        rclpy.spin_once(node, timeout_sec=0.05)
    return future.done()


def goal(node, step):
    client = ActionClient(node, RunTree, step["action"])
    if not client.wait_for_server(timeout_sec=WAIT):
        return {"error": "no server"}
    time.sleep(0.3)  # let the feedback subscription match the server's publisher
    events = []

    def on_feedback(msg):
        fb = msg.feedback
        events.append(
            {
                "type": "feedback",
                "t": time.monotonic(),
                "status": fb.status,
                "active_node": fb.active_node,
                "tick_count": fb.tick_count,
                "elapsed": fb.elapsed,
            }
        )

    sent = client.send_goal_async(RunTree.Goal(inputs_yaml=step.get("inputs", "")), feedback_callback=on_feedback)
    if not spin_until(node, sent, WAIT):
        return {"error": "no goal response"}
    handle = sent.result()
    if not handle.accepted:
        return {"accepted": False}
    result = handle.get_result_async()

    def on_result(fut):
        events.append({"type": "result", "t": time.monotonic()})

    result.add_done_callback(on_result)
    if not spin_until(node, result, step.get("timeout", 30.0)):
        return {"accepted": True, "error": "no result"}
    end = time.monotonic() + 0.3  # feedback that arrives late is recorded too
    while time.monotonic() < end:
        rclpy.spin_once(node, timeout_sec=0.05)
    res = result.result()
    r = res.result
    return {
        "accepted": True,
        "status": res.status,
        "success": r.success,
        "result_status": r.status,
        "outputs_yaml": r.outputs_yaml,
        "error_code": r.error_code,
        "error_msg": r.error_msg,
        "events": events,
    }


def call_service(node, srv_type, name, request):
    client = node.create_client(srv_type, name)
    if not client.wait_for_service(timeout_sec=WAIT):
        return None
    fut = client.call_async(request)
    spin_until(node, fut, WAIT)
    return fut.result()


def describe(node, step):
    resp = call_service(node, Describe, step["service"], Describe.Request(name=step.get("name", "")))
    if resp is None:
        return {"error": "no server"}
    return {
        "error_code": resp.error_code,
        "error_msg": resp.error_msg,
        "doc": json.loads(resp.tools_json) if resp.tools_json else None,
    }


def call_now(node, step):
    req = CallActorNow.Request(
        actor=step["actor"], args_yaml=step.get("args", ""), timeout=float(step.get("timeout", 0.0))
    )
    resp = call_service(node, CallActorNow, step["service"], req)
    if resp is None:
        return {"error": "no server"}
    return {
        "success": resp.success,
        "result_yaml": resp.result_yaml,
        "error_code": resp.error_code,
        "error_msg": resp.error_msg,
    }


def wait_action(node, step):
    end = time.monotonic() + step.get("timeout", WAIT)
    while True:
        names = [n for n, _ in get_action_names_and_types(node)]
        if (step["action"] in names) == step.get("present", True):
            return {"found": True}
        if time.monotonic() >= end:
            return {"found": False, "actions": names}
        rclpy.spin_once(node, timeout_sec=0.1)


OPS = {"goal": goal, "describe": describe, "call_now": call_now, "wait_action": wait_action}


def main():
    steps = json.loads(sys.argv[1])
    rclpy.init()
    node = rclpy.create_node("plain_rclpy_client")
    try:
        print(json.dumps([OPS[s["op"]](node, s) for s in steps]))
    finally:
        node.destroy_node()
        rclpy.shutdown()


if __name__ == "__main__":
    main()
