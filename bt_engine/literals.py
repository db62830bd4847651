"""Terminal arguments to Python values: literals via ``ast.literal_eval``, never ``eval``."""

from __future__ import annotations

import ast
import shlex
from typing import Any

from .errors import ActorbtError


class ArgumentSyntaxError(ActorbtError, ValueError):
    """A terminal argument line could not be split."""


def parse_value(token: str) -> Any:
    """A Python literal (``1``, ``2.5``, ``[1, 2]``, ``'x'``, ``True``), else the raw string."""
    try:
        return ast.literal_eval(token)
    except (ValueError, SyntaxError, MemoryError, RecursionError):
        return token


def parse_args(tokens: list[str]) -> tuple[list[Any], dict[str, Any]]:
    """Positional literals, and ``key=value`` pairs as keyword arguments."""
    args: list[Any] = []
    kwargs: dict[str, Any] = {}
    for tok in tokens:
        key, eq, val = tok.partition("=")
        if eq and key.isidentifier():
            kwargs[key] = parse_value(val)
        else:
            args.append(parse_value(tok))
    return args, kwargs


def split_line(line: str) -> list[str]:
    try:
        return shlex.split(line)
    except ValueError as e:
        raise ArgumentSyntaxError(f"cannot split {line!r}: {e}") from None
