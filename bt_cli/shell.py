"""``actorbt shell``: type an actor name and its arguments, and it runs.

History (~/.actorbt_history), tab completion of actor names, ``help NAME`` for the
docstring and signature, ``stream NAME ARGS`` for every value of a stream. Errors print
a message; the shell carries on.

:func:`print_stream` is also what ``actorbt call NAME ARGS --stream`` prints with.
"""

from __future__ import annotations

import argparse
import json
import pprint
from typing import IO, Any, Iterable, NoReturn

from bt_engine.catalog import text_lines, tool_schema
from bt_engine.errors import ActorbtError
from bt_engine.runtime import Runtime
from bt_engine.shell_base import ShellBase
from bt_engine.literals import parse_args, split_line

#: exit status of a stream ended by Ctrl-C (128 + SIGINT, as a shell reports it)
INTERRUPTED = 130


def format_value(value: Any, as_json: bool = False) -> str:
    """One value as the terminal shows it: ``pprint`` (Python syntax), or one JSON line."""
    return json.dumps(value, default=str) if as_json else pprint.pformat(value)


def print_stream(values: Iterable[Any], out: IO[str], *, as_json: bool = False, count: int | None = None) -> int:
    """Print each of ``values`` on its own line as it arrives (flushed), until the
    iterator ends or ``count`` values were printed (no further value is asked for).

    Returns the exit status: 0, or :data:`INTERRUPTED` when Ctrl-C (KeyboardInterrupt)
    stopped it; the caller's ``with rt.stream(...)`` block then closes the source.
    """
    if count is not None and count <= 0:
        return 0
    printed = 0
    try:
        for value in values:
            out.write(format_value(value, as_json) + "\n")
            out.flush()
            printed += 1
            if count is not None and printed >= count:
                break
    except KeyboardInterrupt:
        return INTERRUPTED
    return 0


def stream_actor(
    rt: Runtime,
    name: str,
    args: list[Any],
    kwargs: dict[str, Any],
    out: IO[str],
    *,
    as_json: bool = False,
    count: int | None = None,
    timeout: float | None = None,
) -> int:
    """Iterate actor ``name`` from the calling thread and print its values
    (:func:`print_stream`); ``timeout`` [s, runtime clock] ends the stream. Leaving
    returns only once the source is closed. A sync or async actor is invoked again for
    every value (the iterator mode)."""
    try:
        with rt.stream(name, *args, timeout=timeout, **kwargs) as values:
            return print_stream(values, out, as_json=as_json, count=count)
    except KeyboardInterrupt:  # while the stream was being started or closed
        return INTERRUPTED


class _OptionError(argparse.ArgumentParser):
    """An argparse parser that raises (the shell goes on) instead of exiting."""

    def error(self, message: str) -> NoReturn:
        option, _, problem = message.removeprefix("argument ").partition(": ")
        if problem == "expected one argument":
            message = f"{option} needs a value"
        raise ActorbtError(message)


_STREAM_OPTIONS = _OptionError(prog="stream", add_help=False)
_STREAM_OPTIONS.add_argument("--count", type=int)
_STREAM_OPTIONS.add_argument("--timeout", type=float)
_STREAM_OPTIONS.add_argument("--json", dest="as_json", action="store_true")


def _stream_options(tokens: list[str]) -> tuple[list[str], dict[str, Any]]:
    """Split ``--count N``, ``--timeout S`` and ``--json`` (``--opt=V`` too) from the
    other tokens of a shell ``stream`` line (the actor and its arguments, in order)."""
    opts, rest = _STREAM_OPTIONS.parse_known_args(tokens)
    return rest, vars(opts)


class ActorShell(ShellBase):
    intro = (
        "actorbt shell: type an actor and its arguments (Python literals), e.g. "
        "`sleep 1.5`.\n`list` shows actors, `help NAME` describes one, `stream NAME ARGS` "
        "prints every value of a stream, `quit` leaves."
    )
    #: the shell's own commands (the rest of a line is an actor call)
    commands = ["help", "list", "quit", "stream", "transactions"]
    stream_options = ["--count", "--json", "--timeout"]
    prompt = "actorbt> "

    def __init__(self, rt: Runtime, stdin: IO[str] | None = None, stdout: IO[str] | None = None) -> None:
        super().__init__(stdin=stdin, stdout=stdout)
        if stdin is not None:
            self.use_rawinput = False
        self.rt = rt

    # -- commands ----------------------------------------------------------------------
    def _names(self) -> list[str]:
        refs = self.rt.root.all_actors()
        return sorted({r.path for r in refs} | {r.name for r in refs})

    def do_list(self, arg: str) -> None:
        """List actors (optionally those containing TEXT)."""
        for r in sorted(self.rt.root.all_actors(), key=lambda r: r.path):
            if arg and arg not in r.path:
                continue
            first = r.doc.splitlines()[0] if r.doc else ""
            tag = "tree" if r.is_tree else r.kind.value
            self.stdout.write(f"  {r.path}{r.signature}  [{tag}]  {first}\n")

    def do_transactions(self, arg: str) -> None:
        """List live transactions."""
        for t in self.rt.transactions():
            self.stdout.write(f"  {t.id:>6} {t.path} {t.mode.value} since {t.started:.3f}s\n")

    def do_stream(self, arg: str) -> None:
        """stream NAME ARG... [--count N] [--timeout S] [--json]: print every value of
        actor NAME, one per line, as it arrives, until the stream ends, N values were
        printed, S seconds of runtime-clock time passed, or Ctrl-C. A sync or async actor
        is called again for every value (the iterator mode): give it --count or --timeout."""
        try:
            tokens, opts = _stream_options(split_line(arg))
            if not tokens:
                self.stdout.write("usage: stream NAME ARG... [--count N] [--timeout S] [--json]\n")
                return
            args, kwargs = parse_args(tokens[1:])
            status = stream_actor(self.rt, tokens[0], args, kwargs, self.stdout, **opts)
        except ActorbtError as e:
            self.stdout.write(f"error: {e}\n")
            return
        if status == INTERRUPTED:
            self.stdout.write("interrupted\n")

    def do_help(self, arg: str) -> None:
        """help NAME: the actor's signature and docstring."""
        if not arg:
            self.stdout.write(
                "Commands: list [TEXT], help NAME, stream NAME ARG... [--count N], "
                "transactions, quit.\n"
                "Anything else: ACTOR ARG... (key=value for keywords).\n"
            )
            return
        if arg in self.commands and not self.rt.check_actor(arg):
            doc = getattr(self, f"do_{arg}").__doc__ or ""
            self.stdout.write(" ".join(doc.split()) + "\n")
            return
        try:
            ref = self.rt.resolve(arg)
        except ActorbtError as e:
            self.stdout.write(f"error: {e}\n")
            return
        self.stdout.write(f"{ref.path}{ref.signature}  [{'tree' if ref.is_tree else ref.kind.value}]\n")
        self.stdout.write("".join(f"{line}\n" for line in text_lines(ref.doc, tool_schema(ref))))

    def default(self, line: str) -> None:
        try:
            tokens = split_line(line)
            if not tokens:
                return
            args, kwargs = parse_args(tokens[1:])
            result = self.rt.call(tokens[0], *args, **kwargs)
        except ActorbtError as e:
            self.stdout.write(f"error: {e}\n")
            return
        except KeyboardInterrupt:
            self.stdout.write("interrupted\n")
            return
        if result is not None:
            self.stdout.write(format_value(result) + "\n")

    def completenames(self, text: str, *ignored: Any) -> list[str]:
        return [n for n in self._names() + self.commands if n.startswith(text)]

    def complete_help(self, text: str, *ignored: Any) -> list[str]:
        return [n for n in self._names() + self.commands if n.startswith(text)]

    def complete_stream(self, text: str, line: str, begidx: int, endidx: int) -> list[str]:
        """The actor name first, then the options."""
        if text.startswith("-"):
            return [o for o in self.stream_options if o.startswith(text)]
        if len(line[:begidx].split()) <= 1:  # completing the word after `stream`
            return [n for n in self._names() if n.startswith(text)]
        return []

    def cmdloop(self, intro: Any = None) -> None:
        while True:
            try:
                super().cmdloop(intro)
                return
            except KeyboardInterrupt:
                self.stdout.write("\n")
                intro = ""
