"""Actions served from the hub over ROS 2 (bt_ros.action_server): one runtime
serves, another is the client, over real DDS on loopback. The same server code as on
the local bus (tests/test_bus_actions.py)."""

from __future__ import annotations

import pytest

pytest.importorskip("rclpy")
from actorbt_interfaces.action import CallActor  # noqa: E402

from bt_engine import ActorError, Runtime, SubSystem  # noqa: E402
from bt_engine.bus.actions import ActionGoalError  # noqa: E402
from bt_ros.transport import RosTransport  # noqa: E402
from tests.test_bus_actions import Echo  # noqa: E402
from tests.test_ros_common import wait_until  # noqa: E402

SERVER = "/ros_actions_test/echo"


class Client(SubSystem):
    def __init__(self) -> None:
        super().__init__()
        self.register_action("echo", CallActor, SERVER)


@pytest.fixture(scope="module")
def pair():
    server = Runtime(clock="wall", bus=RosTransport)
    client = Runtime(clock="wall", bus=RosTransport)
    try:
        server.echo = server.add_subsystem("echo", Echo, SERVER)
        client.add_subsystem("client", Client)
        yield server, client
    finally:
        client.close()
        server.close()


def test_a_goal_over_ros_succeeds_with_the_servers_result(pair):
    server, client = pair
    result = client.call("echo", actor="hello", timeout=20.0)
    assert result.success and result.result_yaml == "hello"


def test_an_abort_over_ros_carries_the_result(pair):
    server, client = pair
    with pytest.raises(ActorError) as failed:
        client.call("echo", actor="fail", timeout=20.0)
    error = failed.value.__cause__
    assert isinstance(error, ActionGoalError) and error.status == 6
    assert error.result.error_msg == "told to fail"


def test_cancelling_the_client_call_reaches_the_server(pair):
    server, client = pair
    client.call("echo", actor="warm-up", timeout=20.0)  # discovered
    txn = client.start("echo", actor="slow")
    assert wait_until(lambda: server.run_on_hub(lambda: server.echo.started), 10.0)
    txn.cancel("enough")
    assert wait_until(lambda: "slow" in server.run_on_hub(lambda: list(server.echo.cancelled)), 10.0)
