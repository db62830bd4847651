"""Errors: chaining, call-site errors, bad modes, raising callbacks."""

from __future__ import annotations

import logging

import pytest

from bt_engine import (
    ActorError,
    ActorbtError,
    BadArgumentsError,
    BadModeError,
    Failure,
    SubSystem,
    UnknownActorError,
    actor,
)
from tests.conftest import run_in_actor


class Faulty(SubSystem):
    @actor
    def divide(self, a: float, b: float) -> float:
        """Divide a by b."""
        return a / b

    @actor
    def calls_divide(self) -> float:
        return self.run_actor("divide", 1, 0)

    @actor("fails_later", "async", hub_only=True)
    def fails_later(self, done):
        self.runtime.call_later(0.1, done.fail, RuntimeError("sensor lost"))


@pytest.fixture
def faulty(rt):
    return rt.add_subsystem("f", Faulty)


def test_actor_error_names_the_path_and_chains(rt, faulty):
    with pytest.raises(ActorError) as e:
        rt.call("divide", 1, 0)
    assert e.value.path == "f.divide"
    assert isinstance(e.value.__cause__, ZeroDivisionError)
    assert isinstance(e.value, ActorbtError)


def test_nested_errors_chain_through_each_actor(rt, faulty):
    with pytest.raises(ActorError) as e:
        rt.call("calls_divide")
    assert e.value.path == "f.calls_divide"
    inner = e.value.__cause__
    assert isinstance(inner, ActorError) and inner.path == "f.divide"
    assert isinstance(inner.__cause__, ZeroDivisionError)


def test_async_failure_reaches_sync_caller_and_callback(rt, faulty):
    with pytest.raises(ActorError) as e:
        rt.call("fails_later")
    assert "sensor lost" in str(e.value)
    got = []
    run_in_actor(rt, lambda: (rt.start("fails_later", on_done=got.append), rt.sleep(1)))
    assert isinstance(got[0], Failure) and not got[0]
    assert "sensor lost" in str(got[0].exception)


def test_unknown_actor_lists_close_matches(rt, faulty):
    with pytest.raises(UnknownActorError) as e:
        rt.call("divid", 1, 2)
    assert "divide" in e.value.suggestions
    assert "did you mean" in str(e.value)


def test_wrong_arity_shows_the_signature(rt, faulty):
    with pytest.raises(BadArgumentsError) as e:
        rt.call("divide", 1)
    assert "f.divide(a: float, b: float) -> float" in str(e.value)
    assert "missing a required argument" in str(e.value)


def test_type_error_inside_actor_is_an_actor_error_not_bad_arguments(rt):
    class S(SubSystem):
        @actor
        def adds(self, a):
            return a + "x"

    rt.add_subsystem("s", S)
    with pytest.raises(ActorError) as e:
        rt.call("adds", 1)
    assert not isinstance(e.value, BadArgumentsError)


def test_unknown_mode_string(rt, faulty):
    with pytest.raises(BadModeError) as e:
        rt.run_actor_mode("divide", "iterater", 1, 2)
    assert "iterator" in str(e.value)


def test_mode_needs_its_leading_argument(rt, faulty):
    with pytest.raises(BadModeError):
        rt.run_actor_mode("divide", "timed")
    with pytest.raises(BadModeError):
        rt.run_actor_mode("divide", "async", 1, 2)


def test_unknown_kind_in_decorator():
    with pytest.raises(BadModeError):

        @actor("x", "asynchronous")
        def x(self, done):
            pass


def test_a_raising_callback_is_logged_and_the_runtime_goes_on(rt, faulty, caplog):
    def bad_callback(result):
        raise KeyError("callback bug")

    with caplog.at_level(logging.ERROR, logger="actorbt"):
        run_in_actor(rt, lambda: (rt.start("divide", 4, 2, on_done=bad_callback), rt.sleep(1)))
    assert any(
        "callback bug" in r.getMessage() or (r.exc_info and "callback bug" in str(r.exc_info[1]))
        for r in caplog.records
    )
    assert rt.call("divide", 4, 2) == 2.0
    assert rt.stats() == {"transactions": 0, "tasks": 0}


def test_blocking_from_a_hub_callback_is_a_clear_error(rt, faulty):
    errors = []

    def in_callback():
        try:
            rt.call("divide", 1, 1)
        except ActorbtError as e:
            errors.append(e)

    rt.run_on_hub(in_callback)
    assert "must not block" in str(errors[0])


class Oddity(BaseException):
    """A custom BaseException subclass, as some libraries raise."""


class Unusual(SubSystem):
    @actor
    def raises_base(self) -> None:
        raise Oddity("the driver gave up")

    @actor("async_base", "async")
    def async_base(self, done):
        raise Oddity("at start")

    @actor
    def gen_base(self):
        yield 1
        raise Oddity("mid-stream")

    @actor
    def recurse(self, n: int) -> int:
        if n == 0:
            raise ValueError("x" * 5000)
        return self.run_actor("recurse", n - 1)


@pytest.fixture
def unusual(rt):
    return rt.add_subsystem("u", Unusual)


@pytest.mark.parametrize("name", ["raises_base", "async_base"])
def test_a_custom_base_exception_fails_the_actor_like_any_other(rt, unusual, name):
    with pytest.raises(ActorError) as e:
        rt.call(name)
    assert e.value.path == f"u.{name}"
    assert isinstance(e.value.__cause__, Oddity) or isinstance(e.value.root_cause, Oddity)
    assert "Oddity" in str(e.value)
    got = []
    run_in_actor(rt, lambda: (unusual.run_actor_mode(name, "async", got.append), rt.sleep(0.1)))
    assert isinstance(got[0], Failure) and isinstance(got[0].exception, ActorError)


def test_a_custom_base_exception_in_a_stream_ends_it_with_an_actor_error(rt, unusual):
    def body():
        with unusual.run_actor_mode("gen_base", "iterator") as it:
            assert next(it) == 1
            next(it)

    with pytest.raises(ActorError) as e:
        run_in_actor(rt, body)
    assert "Oddity: mid-stream" in str(e.value)


def test_keyboard_interrupt_and_system_exit_are_not_failures(rt):
    class Quits(SubSystem):
        @actor
        def quits(self) -> None:
            raise SystemExit(3)

    rt.add_subsystem("q", Quits)
    with pytest.raises(SystemExit):
        rt.call("quits")


def test_a_chain_of_failures_gives_one_short_message(rt, unusual):
    with pytest.raises(ActorError) as e:
        rt.call("recurse", 60)
    message = str(e.value)
    assert len(message) < 700, message
    assert message.startswith("actor u.recurse -> u.recurse")
    assert "... 57 more ..." in message and "ValueError: xxx" in message
    assert isinstance(e.value.root_cause, ValueError)
    assert len(e.value.call_chain) == 61


def test_a_long_cause_is_elided_in_the_middle():
    from bt_engine.errors import shorten

    text = "head " + "m" * 1000 + " tail"
    short = shorten(text, 100)
    assert len(short) <= 100 and short.startswith("head ") and short.endswith(" tail") and " ... " in short
