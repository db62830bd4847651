"""The ``@actor`` decorator and the description of one actor."""

from __future__ import annotations

import inspect
import math
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping

from .errors import ActorbtError, BadArgumentsError
from .modes import Kind

#: Default depth of a stream's buffer; the oldest value is dropped when it is full.
DEFAULT_STREAM_BUFFER = 16
#: the attribute @actor sets on the function it marks, holding its ActorSpec
SPEC_ATTR = "_actor_spec"


@dataclass(frozen=True)
class ActorSpec:
    """What ``@actor`` records on a function: name, kind, stream buffer depth, and
    whether its ``done``/``emit`` are only ever called by hub code (see ``hub_only``)."""

    name: str | None
    kind: Kind
    fn: Callable
    buffer: int = DEFAULT_STREAM_BUFFER
    hub_only: bool = False
    safety: "Safety | None" = None


#: ``{parameter: (lowest, highest)}``; ``None`` for no bound on that side
Limits = Mapping[str, "tuple[float | None, float | None]"]


@dataclass(frozen=True)
class Safety:
    """What an actor declares about its effect on the world, for callers that must be
    careful (a language model through ``actorbt mcp``).

    Attributes:
        moves: it commands motion of the robot (base, arm or gripper), itself or
            through the actors it calls.
        read_only: it changes nothing: no motion, no state, no files (a query).
        limits: the allowed range of numeric parameters, ``{name: (low, high)}``
            (inclusive; ``None`` leaves a side open). The catalog gives them as
            JSON-Schema ``minimum`` / ``maximum``; for ``*args`` each value is bound.
    """

    moves: bool = False
    read_only: bool = False
    limits: Mapping[str, tuple[float | None, float | None]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.moves and self.read_only:
            raise TypeError("an actor that moves the robot is not read-only")


#: an actor that declares nothing
NO_SAFETY = Safety()


def actor(
    *args: Any,
    kind: "str | Kind | None" = None,
    buffer: int = DEFAULT_STREAM_BUFFER,
    hub_only: bool = False,
    moves: bool = False,
    read_only: bool = False,
    limits: Limits | None = None,
):
    """Declare a method of a SubSystem or SubNet as an actor.

    Forms, as in ros_actor::

        @actor                        # name = function name, kind = sync
        @actor('name')                # explicit name
        @actor('name', 'async')       # impl(done, *args): call done(result) later
        @actor('name', 'multi')       # impl(emit, *args): emit values, return a closer
        @actor(kind='multi', buffer=1)

    A generator function is a stream actor whatever kind is given.

    ``hub_only=True`` promises that an async or stream implementation calls ``done`` /
    ``emit`` only from hub code (runtime timers, local-bus callbacks), never from
    another thread. The virtual clock may then jump while it runs; otherwise it paces
    itself to wall time until the work completes (see :class:`~bt_engine.VirtualClock`).

    Safety (see :class:`Safety`), read by the catalog and by ``actorbt mcp``::

        @actor(moves=True, limits={"speed": (0.0, 0.26)})   # drives the base, at most 0.26 m/s
        @actor(read_only=True)                               # a query: changes nothing
    """
    safety = Safety(moves, read_only, dict(limits or {}))
    if len(args) == 1 and callable(args[0]) and kind is None:
        return _mark(args[0], None, None, buffer, hub_only, safety)
    if len(args) > 2:
        raise TypeError("@actor takes at most a name and a kind")
    name = args[0] if args else None
    k = args[1] if len(args) > 1 else kind
    if name is not None and not isinstance(name, str):
        raise TypeError(f"@actor name must be a string, not {type(name).__name__}")

    def deco(fn: Callable) -> Callable:
        return _mark(fn, name, k, buffer, hub_only, safety)

    return deco


def _mark(
    fn: Callable, name: str | None, kind: "str | Kind | None", buffer: int, hub_only: bool, safety: Safety
) -> Callable:
    if inspect.isgeneratorfunction(fn):
        k = Kind.STREAM
    else:
        k = Kind.parse(kind) if kind is not None else Kind.SYNC
    _check_limits(fn, safety.limits)
    setattr(fn, SPEC_ATTR, ActorSpec(name or fn.__name__, k, fn, buffer, hub_only, safety))
    return fn


def _check_limits(fn: Callable, limits: Mapping[str, tuple[float | None, float | None]]) -> None:
    """A limit names a parameter and is (low, high) with low <= high: a typo would
    otherwise leave the parameter unbounded without a word."""
    try:
        names = set(inspect.signature(fn).parameters)
    except (TypeError, ValueError):
        names = set(limits)
    for pname, bounds in limits.items():
        if pname not in names:
            raise TypeError(f"@actor limits: {fn.__qualname__} has no parameter {pname!r}")
        low, high = bounds
        if low is not None and high is not None and low > high:
            raise TypeError(f"@actor limits: {pname!r} has low {low} above high {high}")


@dataclass
class ActorRef:
    """A bound, callable actor as the runtime sees it.

    ``signature`` describes what a caller passes (no ``self``, and no ``done``/``emit``
    for async and stream implementations). ``hub_only``: see :func:`actor`.

    ``wait`` (an emit-style stream only): the longest a caller waits for its next value
    [s, runtime clock] before the call fails with ActorTimeout, whose message is
    ``wait_detail(seconds)``; None waits forever. It bounds each wait (the first value,
    or the gap before the next one while iterating), not the stream's life, and a
    deadline the caller gives (``timeout=``, the timed modes) replaces it.
    """

    path: str
    name: str
    fn: Callable
    kind: Kind
    signature: inspect.Signature
    doc: str
    owner: Any = None
    is_tree: bool = False
    is_generator: bool = False
    buffer: int = DEFAULT_STREAM_BUFFER
    hub_only: bool = False
    safety: Safety = NO_SAFETY
    wait: float | None = None
    wait_detail: Callable[[float], str] | None = None

    @property
    def moves(self) -> bool:
        return self.safety.moves

    @property
    def read_only(self) -> bool:
        return self.safety.read_only

    @classmethod
    def build(
        cls,
        path: str,
        name: str,
        fn: Callable,
        kind: Kind,
        owner: Any = None,
        doc: str | None = None,
        signature: inspect.Signature | None = None,
        is_tree: bool = False,
        buffer: int = DEFAULT_STREAM_BUFFER,
        hub_only: bool = False,
        safety: Safety | None = None,
        wait: float | None = None,
        wait_detail: Callable[[float], str] | None = None,
    ) -> "ActorRef":
        is_gen = inspect.isgeneratorfunction(fn)
        if signature is None:
            signature = _caller_signature(fn, kind, is_gen)
        if wait is not None:
            if kind is not Kind.STREAM or is_gen:
                raise ActorbtError(
                    f"{path}: wait= bounds the wait for a value of an emit-style "
                    f"stream, and it is {'a generator' if is_gen else kind.value}"
                )
            if isinstance(wait, bool) or not isinstance(wait, (int, float)) or not 0 < wait < math.inf:
                raise ActorbtError(f"{path}: wait must be a positive number of seconds or None, got {wait!r}")
        return cls(
            path=path,
            name=name,
            fn=fn,
            kind=kind,
            signature=signature,
            doc=inspect.cleandoc(doc if doc is not None else (fn.__doc__ or "")),
            owner=owner,
            is_tree=is_tree,
            is_generator=is_gen,
            buffer=buffer,
            hub_only=hub_only,
            safety=safety or NO_SAFETY,
            wait=wait,
            wait_detail=wait_detail,
        )

    def check_args(self, args: tuple, kwargs: dict) -> None:
        """Raise BadArgumentsError when the arguments do not fit the signature."""
        try:
            self.signature.bind(*args, **kwargs)
        except TypeError as e:
            raise BadArgumentsError(self.path, self.signature, str(e)) from None


def _caller_signature(fn: Callable, kind: Kind, is_gen: bool) -> inspect.Signature:
    try:
        # Bound methods already drop self. eval_str resolves the actor module's own
        # postponed annotations (source code, never user input) for the catalog.
        try:
            sig = inspect.signature(fn, eval_str=True)
        except Exception:
            sig = inspect.signature(fn)
    except (TypeError, ValueError):
        return inspect.Signature([inspect.Parameter("args", inspect.Parameter.VAR_POSITIONAL)])
    params = list(sig.parameters.values())
    if kind in (Kind.ASYNC, Kind.STREAM) and not is_gen and params:
        params = params[1:]  # done / emit is supplied by the runtime
    return sig.replace(parameters=params)
