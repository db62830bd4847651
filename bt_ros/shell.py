"""``actorbt rshell``: an actor shell on a running ``actorbt serve``, over ROS.

    rshell> get_pose
    [1.0, 1.0, 0.0]
    rshell> robot.navigation.goto 2.0 1.0 0.0
    rshell> help goto
    rshell> list nav
    rshell> trees

A line is ``ACTOR ARG... [k=v]`` as for ``actorbt rcall`` (Python literals). The shell
keeps one node (a :class:`~bt_ros.remote.Remote`) for the whole session, so a call
after the first costs one round trip to the serve (tens of milliseconds) instead of a
process start, a node and a discovery (about a second for each ``actorbt rcall``).

Tab completion and ``help NAME`` read the actor index of the local actorbt.yaml (what
``actorbt list`` shows, loaded on first use) and the trees the serve offers; a name the
index does not know is still sent, and the serve says whether it knows it. Ctrl-C
during a call cancels the call; the shell carries on. History is shared with
``actorbt shell`` (``~/.actorbt_history``, or ``$ACTORBT_HISTORY``).

This module does not import the ``actorbt`` command line (the layer above): the actor
index comes in as a function.
"""

from __future__ import annotations

import pprint
from typing import IO, TYPE_CHECKING, Callable, Sequence

from bt_engine.errors import ActorbtError
from bt_engine.literals import parse_args, split_line
from bt_engine.shell_base import ShellBase
from .client import GoalRejectedError, ServerUnavailableError
from .remote import GoalRefusedError, NoServeError, Remote, close_matches

if TYPE_CHECKING:
    from .command_app import IndexEntry

__all__ = ["RemoteShell"]


class RemoteShell(ShellBase):
    """The shell (see the module docstring).

    Args:
        remote: the client of the serve, kept for the session.
        index: returns the local actor index entries (``path``, ``name``, ``kind``,
            ``is_tree``, ``doc``, ``shown``), called once, on first use; None: no index.
        timeout: cancel a call after this many seconds (None: wait for it).
    """

    intro = (
        "actorbt rshell: calls actors of the running `actorbt serve`. Type an actor and "
        "its arguments (Python literals), e.g. `get_pose`.\n`list [TEXT]` shows actors, "
        "`trees` the served trees, `help NAME` describes one, `quit` leaves."
    )
    prompt = "rshell> "
    #: the shell's own commands (the rest of a line is an actor call)
    commands = ["help", "list", "quit", "trees"]

    def __init__(
        self,
        remote: Remote,
        index: Callable[[], Sequence[IndexEntry]] | None = None,
        *,
        timeout: float | None = None,
        stdin: IO[str] | None = None,
        stdout: IO[str] | None = None,
    ) -> None:
        super().__init__(stdin=stdin, stdout=stdout)
        if stdin is not None:  # lines from a file or a pipe: no prompt, no banner
            self.use_rawinput = False
            self.prompt = ""
            self.intro = ""
        self.remote = remote
        self.timeout = timeout
        self._index_source = index
        self._index: list[IndexEntry] | None = None

    # -- names ---------------------------------------------------------------------------
    def entries(self) -> list[IndexEntry]:
        """The local actor index (loaded once)."""
        if self._index is None:
            self._index = []
            if self._index_source is not None:
                try:
                    self._index = sorted(self._index_source(), key=lambda e: e.path)
                except Exception as e:  # a broken actorbt.yaml: calls still work
                    self.stdout.write(f"(no actor index: {e})\n")
        return self._index

    def _served_trees(self) -> list[str]:
        try:
            return self.remote.served_trees()
        except ActorbtError:
            return []

    def _names(self) -> list[str]:
        names = {e.path for e in self.entries()} | {e.name for e in self.entries()}
        return sorted(names | set(self._served_trees()))

    def completenames(self, text: str, *ignored: object) -> list[str]:
        return [n for n in self._names() + self.commands if n.startswith(text)]

    def complete_help(self, text: str, *ignored: object) -> list[str]:
        return self.completenames(text)

    # -- commands --------------------------------------------------------------------------
    def do_list(self, arg: str) -> None:
        """list [TEXT]: the actors of the local actor index (those containing TEXT)."""
        for e in self.entries():
            if arg and arg not in e.path:
                continue
            first = e.doc.splitlines()[0] if e.doc else ""
            tag = "tree" if e.is_tree else e.kind
            self.stdout.write(f"  {e.path}{e.shown}  [{tag}]  {first}\n")

    def do_trees(self, arg: str) -> None:
        """trees: the trees the serve offers (its /actorbt/tree/<name> actions)."""
        for t in self._served_trees():
            self.stdout.write(f"  {t}\n")

    def do_help(self, arg: str) -> None:
        """help NAME: the actor's signature and docstring."""
        arg = arg.strip()
        if not arg:
            self.stdout.write(
                "Commands: list [TEXT], trees, help NAME, quit.\n"
                "Anything else: ACTOR ARG... (key=value for keywords), called "
                "in the serve; Ctrl-C cancels it.\n"
            )
            return
        entries = self.entries()
        found = [e for e in entries if e.path == arg] or [e for e in entries if e.name == arg]
        if not found and arg in self.commands:
            doc = getattr(self, f"do_{arg}").__doc__ or ""
            self.stdout.write(" ".join(doc.split()) + "\n")
            return
        if not found:
            if arg in self._served_trees():
                self.stdout.write(f"{arg}  [tree]  (served; not in the local actor index)\n")
                return
            hint = close_matches(arg, self._names())
            self.stdout.write(
                f"error: unknown actor {arg!r}" + (f"; did you mean: {', '.join(hint)}?" if hint else "") + "\n"
            )
            return
        if len(found) > 1:
            self.stdout.write(f"{arg} is ambiguous: {', '.join(e.path for e in found)}\n")
            return
        e = found[0]
        self.stdout.write(f"{e.path}{e.shown}  [{'tree' if e.is_tree else e.kind}]\n")
        self.stdout.write((e.doc or "(no docstring)") + "\n")

    def default(self, line: str) -> None:
        try:
            tokens = split_line(line)
            if not tokens:
                return
            args, kwargs = parse_args(tokens[1:])
            goal = self.remote.call_goal(tokens[0], *args, **kwargs)
            value = self.remote.finish(goal, self.timeout, f"actor {tokens[0]}")
        except KeyboardInterrupt:
            self.stdout.write("interrupted (the call was canceled)\n")
            return
        except GoalRejectedError as e:  # an invalid call: GoalRefusedError, with its code
            word = f"refused ({e.code})" if isinstance(e, GoalRefusedError) else "rejected"
            self.stdout.write(f"error: {word}: {e.reason or e}\n")
            return
        except ServerUnavailableError as e:
            self.stdout.write(f"error: {NoServeError(e.seconds)}\n")
            return
        except ActorbtError as e:  # a failure, a timeout, bad arguments
            self.stdout.write(f"error: {e}\n")
            return
        if value is not None:
            self.stdout.write(pprint.pformat(value) + "\n")

    def cmdloop(self, intro: object = None) -> None:
        while True:
            try:
                super().cmdloop(intro)
                return
            except KeyboardInterrupt:
                self.stdout.write("\n")
                intro = ""
