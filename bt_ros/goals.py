"""A goal's YAML text in, a validated call out: the one place that decodes what a
client asks ``actorbt serve`` to run.

- RunTree ``inputs_yaml`` -> :func:`decode_tree_goal`: a mapping of input names to
  values, bound to the tree's inputs (missions of the trees layer also check types).
- CallActor ``actor`` and ``args_yaml`` -> :func:`decode_call_goal`: the actor is
  resolved and the arguments bound to its signature.

Text is parsed with ``yaml.safe_load`` only. Anything wrong raises :class:`GoalError`,
whose message is the reason the goal is refused: the server accepts it and aborts it at
once with that reason in ``error_msg`` and ``INVALID_GOAL`` in ``error_code``, as Nav2
does, so a stock client sees why. The server decodes each goal once, when it arrives,
and runs exactly what was decoded.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import yaml

from bt_engine.errors import ActorbtError
from bt_engine.yaml_hints import syntax_mark, syntax_message
from .error_codes import Ending
from .rostypes import Value

if TYPE_CHECKING:
    from bt_engine import ActorRef, Runtime
    from bt_engine.trees import Mission

__all__ = ["GoalError", "Invocation", "decode_call_goal", "decode_tree_goal", "parse_call_args", "parse_inputs"]


class GoalError(ActorbtError, ValueError):
    """A goal that cannot be run: bad YAML, bad arguments, unknown actor, busy tree.

    ``ending`` is the result's error code for it (``INVALID_GOAL`` unless told)."""

    def __init__(self, message: str, ending: Ending = Ending.INVALID_GOAL) -> None:
        super().__init__(message)
        self.ending = ending


@dataclass(frozen=True)
class Invocation:
    """What an accepted goal runs: ``rt.start(path, *args, **kwargs)``."""

    path: str
    args: tuple[Value, ...]
    kwargs: dict[str, Value]


def decode_tree_goal(rt: Runtime, ref: ActorRef, inputs_yaml: str) -> Invocation:
    """The run of tree actor ``ref`` that a RunTree goal asks for.

    Raises:
        GoalError: invalid YAML, not a mapping, unknown or missing inputs, wrong types.
    """
    inputs = parse_inputs(inputs_yaml)
    mission = _mission(rt, ref)
    try:
        if mission is not None:
            mission.bind_inputs(**inputs)
        else:
            ref.check_args((), inputs)
    except (ActorbtError, TypeError, ValueError) as e:
        raise GoalError(str(e)) from None
    return Invocation(ref.path, (), inputs)


def decode_call_goal(rt: Runtime, actor: str, args_yaml: str) -> Invocation:
    """The call a CallActor goal asks for. Not on the hub (it waits for the hub).

    Raises:
        GoalError: no or unknown actor, invalid YAML, arguments that do not fit.
    """
    name = actor.strip()
    if not name:
        raise GoalError("no actor named in the goal")
    args, kwargs = parse_call_args(args_yaml)
    try:
        ref = rt.run_on_hub(rt.root.resolve, name)
        ref.check_args(tuple(args), kwargs)
    except ActorbtError as e:  # unknown actor, bad arguments
        raise GoalError(str(e)) from None
    return Invocation(ref.path, tuple(args), kwargs)


def _mission(rt: Runtime, ref: ActorRef) -> Mission | None:
    """The trees layer's Mission behind a tree actor, when it has one (it checks types)."""
    try:
        from bt_engine.trees import tree_host

        host = tree_host(rt)
        if host is None or ref.path != ref.name:
            return None
        mission = host.library[ref.name]
        return mission if hasattr(mission, "bind_inputs") else None
    except Exception:
        return None


# -- YAML text -> data -------------------------------------------------------------------
def _load(text: str, what: str) -> Value:
    if not text or not text.strip():
        return None
    try:
        return yaml.safe_load(text)
    except yaml.MarkedYAMLError as e:
        mark = syntax_mark(e)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        raise GoalError(f"{what} is not valid YAML{where}: {syntax_message(e)}") from None
    except yaml.YAMLError as e:
        raise GoalError(f"{what} is not valid YAML: {e}") from None


def _check_keys(mapping: dict, what: str) -> None:
    bad = [k for k in mapping if not isinstance(k, str) or not k.isidentifier()]
    if bad:
        raise GoalError(f"{what}: keys must be argument names, not {', '.join(map(repr, bad))}")


def parse_inputs(text: str) -> dict[str, Value]:
    """RunTree ``inputs_yaml``: a mapping of input names to values (empty: none)."""
    data = _load(text, "inputs_yaml")
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise GoalError(f"inputs_yaml must be a mapping of input names to values, not a {type(data).__name__}")
    _check_keys(data, "inputs_yaml")
    return data


def parse_call_args(text: str) -> tuple[list[Value], dict[str, Value]]:
    """CallActor ``args_yaml`` -> (positional, keyword) arguments.

    - empty: no arguments;
    - a list: positional arguments;
    - a mapping with only ``args`` (a list) and/or ``kwargs`` (a mapping): both;
    - any other mapping: keyword arguments;
    - a single scalar: one positional argument.
    """
    data = _load(text, "args_yaml")
    if data is None:
        return [], {}
    if isinstance(data, list):
        return data, {}
    if isinstance(data, dict):
        if data and set(data) <= {"args", "kwargs"}:
            args = data.get("args") if data.get("args") is not None else []
            kwargs = data.get("kwargs") if data.get("kwargs") is not None else {}
            if not isinstance(args, list):
                raise GoalError(f"args_yaml: 'args' must be a list, not a {type(args).__name__}")
            if not isinstance(kwargs, dict):
                raise GoalError(f"args_yaml: 'kwargs' must be a mapping, not a {type(kwargs).__name__}")
            _check_keys(kwargs, "args_yaml kwargs")
            return args, kwargs
        _check_keys(data, "args_yaml")
        return [], data
    return [data], {}
