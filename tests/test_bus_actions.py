"""Actions on the local bus (bt_engine.bus.actions): a server ends goals from the hub
when it likes; the client actor gets the result, fails with the result on an abort,
and its cancellation reaches the server."""

from __future__ import annotations

import pytest

from actorbt_interfaces.action import CallActor
from bt_engine import ActorbtError, ActorError, Runtime, SubSystem
from bt_engine.bus.actions import ActionGoalError, ServerUnavailableError


class Echo(SubSystem):
    """Serves /echo: succeeds after 1 s with the goal's text, aborts on 'fail', and
    stops when cancelled."""

    def __init__(self, name: str = "/echo") -> None:
        super().__init__()
        self.cancelled: list[str] = []
        self.started = 0
        self.server = self._rt.bus.action_server(name, CallActor, self.on_goal)
        self.register_action("echo", CallActor, name)

    def on_goal(self, goal) -> None:
        self.started += 1
        if goal.request.actor == "fail":
            goal.abort(CallActor.Result(success=False, error_msg="told to fail"))
            return
        timer = self._rt.call_later(
            1.0, lambda: goal.succeed(CallActor.Result(success=True, result_yaml=goal.request.actor))
        )

        def stop() -> None:
            timer.cancel()
            self.cancelled.append(goal.request.actor)
            goal.canceled()

        goal.on_cancel(stop)


@pytest.fixture
def rt():
    with Runtime(clock="virtual") as runtime:
        runtime.echo = runtime.add_subsystem("echo", Echo)
        yield runtime


def test_a_goal_succeeds_with_the_servers_result(rt):
    t0 = rt.now()
    result = rt.call("echo", actor="hello")
    assert result.success and result.result_yaml == "hello"
    assert rt.now() - t0 == pytest.approx(1.0)


def test_an_aborted_goal_fails_with_its_result(rt):
    with pytest.raises(ActorError) as failed:
        rt.call("echo", {"actor": "fail"})
    error = failed.value.__cause__
    assert isinstance(error, ActionGoalError)
    assert error.status == 6 and error.result.error_msg == "told to fail"
    assert "ended aborted: told to fail" in str(failed.value)


def test_cancelling_the_call_cancels_the_goal(rt):
    def begin():  # on the hub, so the clock cannot pass the goal's end in between
        txn = rt.start("echo", actor="slow")
        rt.call_later(0.5, txn.cancel, "enough")
        return txn

    txn = rt.run_on_hub(begin)
    rt.call("sleep", 2.0)
    assert txn.state.name == "CANCELLED"
    assert rt.run_on_hub(lambda: list(rt.echo.cancelled)) == ["slow"]


def test_timed_calls_stop_the_goal(rt):
    from bt_engine import ActorTimeout

    with pytest.raises(ActorTimeout):
        rt.call("echo", actor="late", timeout=0.5)
    rt.call("sleep", 1.0)
    assert rt.run_on_hub(lambda: list(rt.echo.cancelled)) == ["late"]


def test_no_server_is_a_clear_error():
    class Lonely(SubSystem):
        def __init__(self) -> None:
            super().__init__()
            self.register_action("go", CallActor, "/nobody")

    with Runtime(clock="virtual") as rt:
        rt.add_subsystem("lonely", Lonely)
        with pytest.raises(ActorError, match="/nobody.*nothing serves it on the local bus") as failed:
            rt.call("go", actor="x")
        assert isinstance(failed.value.__cause__, ServerUnavailableError)


def test_one_server_per_name(rt):
    with pytest.raises(ActorbtError, match="already served"):
        rt.run_on_hub(lambda: rt.bus.action_server("/echo", CallActor, lambda goal: None))


def test_nested_message_fields_can_be_given_as_mappings():
    from control_msgs.action import GripperCommand

    from bt_engine.bus.actions import build_message

    goal = build_message(GripperCommand.Goal, None, {"command": {"position": 0.01, "max_effort": 2.0}})
    assert goal.command.position == 0.01 and goal.command.max_effort == 2.0
    with pytest.raises(TypeError, match="has no field 'positon'"):
        build_message(GripperCommand.Goal, {"command": {"positon": 0.01}}, {})
