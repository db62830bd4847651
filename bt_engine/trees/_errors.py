"""Errors of the mission front end, and the source positions they point at.

Every error about a mission file is a :class:`MissionError`: its text is one line,
``file:line:column: what is wrong, what was expected``, the shape compilers and
PyYAML's marks use. Lines and columns are 1-based.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ..errors import ActorbtError


__all__ = [
    "ActorbtError",
    "ArgumentMismatchError",
    "CheckEvaluationError",
    "CheckExpressionError",
    "DuplicateKeyError",
    "DuplicateTreeError",
    "InputError",
    "InvalidValueError",
    "LimitError",
    "MissionError",
    "MissionSyntaxError",
    "Pos",
    "SubtreeCycleError",
    "TreeFailure",
    "UnknownBehaviourError",
    "UnknownBlackboardKeyError",
    "UnknownFieldError",
    "UnknownNodeError",
    "UnresolvedActorError",
    "shorten",
]

#: Longest message a MissionError prints; longer ones lose their middle. Values quoted
#: in messages are shortened where they are quoted (:func:`shorten`); this is the net.
MAX_MESSAGE_LENGTH = 1000


def shorten(value: object, limit: int = 60) -> str:
    """``repr(value)``, cut to about ``limit`` characters with ``...`` for error messages
    that quote what the user wrote (a value may be thousands of characters long)."""
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 4] + "..." + text[-1]


def out_of_range(what: str, value: Any, limit: tuple) -> str | None:
    """Why ``value`` breaks an actor's declared range ``limit`` (low, high; None: open),
    None when it is inside it or no number (a reference, a string)."""
    low, high = limit
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    if (low is None or value >= low) and (high is None or value <= high):
        return None
    span = f"{'-inf' if low is None else low}..{'inf' if high is None else high}"
    return f"{what} is {shorten(value)}, expected a value within {span} (the actor's declared range)"


def _printable(text: str) -> str:
    # A file name with a newline (or an undecodable byte) must not break the one line.
    return text if text.isprintable() else "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)


@dataclass(frozen=True, order=True)
class Pos:
    """A place in a mission file: 1-based line and column."""

    file: str
    line: int
    column: int

    def __str__(self) -> str:
        return f"{_printable(self.file)}:{self.line}:{self.column}"

    def shifted(self, columns: int) -> Pos:
        """The position ``columns`` characters further along the same line."""
        return Pos(self.file, self.line, self.column + columns)


class MissionError(ActorbtError):
    """A mission file is malformed or does not fit the actors it calls.

    Attributes:
        pos: where the problem is.
        message: what is wrong and what was expected, without the position.
    """

    def __init__(self, pos: Pos, message: str) -> None:
        # One line, always: tools grep for ``file:line:col:`` and editors jump to it.
        self.pos = pos
        message = " ".join(message.split())
        if len(message) > MAX_MESSAGE_LENGTH:
            keep = MAX_MESSAGE_LENGTH // 2
            message = f"{message[:keep]} ... {message[-keep:]}"  # keep what is wrong and what was expected
        self.message = message
        super().__init__(f"{pos}: {self.message}")


class MissionSyntaxError(MissionError):
    """The file is not valid YAML, or uses YAML features missions do not allow."""


class LimitError(MissionSyntaxError):
    """The file goes past a loader limit: its size, its nesting depth, the length of a
    value or number. The message names the limit; each is a module constant
    (``_yaml.MAX_YAML_DEPTH``, ``_parse.MAX_MISSION_SIZE``...)."""


class DuplicateKeyError(MissionError):
    """A mapping repeats a key (plain YAML would silently keep the last one)."""


class UnknownNodeError(MissionError):
    """A node has no known type, or more than one type."""


class UnknownFieldError(MissionError):
    """A mission or node carries a field its kind does not have."""


class InvalidValueError(MissionError):
    """A field has a value of the wrong type or out of range."""


class UnresolvedActorError(MissionError):
    """A ``do:`` names an actor that the resolver does not know."""


class ArgumentMismatchError(MissionError):
    """The ``with:`` arguments of a ``do:`` do not fit the actor's signature."""


class UnknownBlackboardKeyError(MissionError):
    """A reference reads a blackboard key that no input, ``out:`` or ``set:`` writes."""


class SubtreeCycleError(MissionError):
    """Trees call each other in a cycle through ``do:``."""


class CheckExpressionError(MissionError):
    """A ``check:`` expression does not parse."""


class UnknownBehaviourError(MissionError):
    """A ``behaviour:`` names a py_trees behaviour that is not registered."""


class DuplicateTreeError(MissionError):
    """Two mission files in one library declare the same tree name."""


class CheckEvaluationError(ActorbtError):
    """A ``check:`` expression could not be evaluated on the blackboard at run time
    (a key not written yet, or values that do not compare)."""


class InputError(ActorbtError, TypeError):
    """Values given for a tree's inputs do not fit its declared inputs (unknown name,
    missing required input, wrong type). Raised where the tree is called."""


class TreeFailure(ActorbtError):
    """A tree run ended in FAILURE (what a caller of the tree as an actor receives,
    wrapped in an ActorError).

    Attributes:
        tree: the tree's name.
        node_path: the deepest failed node, e.g. ``sequence/retry x3/pick``.
        reason: that node's feedback message.
    """

    def __init__(self, tree: str, node_path: str, reason: str) -> None:
        self.tree = tree
        self.node_path = node_path
        self.reason = reason
        detail = f": {reason}" if reason else ""
        super().__init__(f"tree {tree} failed at {node_path}{detail}")
