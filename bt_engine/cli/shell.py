"""``actorbt shell``: type an actor name and its arguments, and it runs.

History (~/.actorbt_history), tab completion of actor names, ``help NAME`` for the
docstring and signature. Errors print a message; the shell carries on.
"""
from __future__ import annotations

import cmd
import os
import pathlib
import pprint
from typing import Any

from ..errors import ActorbtError
from ..runtime import Runtime
from ..literals import parse_args, split_line

HISTORY = pathlib.Path(os.environ.get("ACTORBT_HISTORY", pathlib.Path.home() / ".actorbt_history"))


class ActorShell(cmd.Cmd):
    intro = ("actorbt shell: type an actor and its arguments (Python literals), e.g. "
             "`sleep 1.5`.\n`list` shows actors, `help NAME` describes one, `quit` leaves.")
    prompt = "actorbt> "

    def __init__(self, rt: Runtime, stdin: Any = None, stdout: Any = None) -> None:
        super().__init__(stdin=stdin, stdout=stdout)
        if stdin is not None:
            self.use_rawinput = False
        self.rt = rt

    # -- history -----------------------------------------------------------------------
    def preloop(self) -> None:
        if self.use_rawinput:
            try:
                import readline
                readline.set_completer_delims(" \t\n")
                if HISTORY.exists():
                    readline.read_history_file(HISTORY)
            except (ImportError, OSError):
                pass

    def postloop(self) -> None:
        if self.use_rawinput:
            try:
                import readline
                readline.set_history_length(1000)
                readline.write_history_file(HISTORY)
            except (ImportError, OSError):
                pass

    # -- commands ----------------------------------------------------------------------
    def _names(self) -> list[str]:
        refs = self.rt.root.all_actors()
        return sorted({r.path for r in refs} | {r.name for r in refs})

    def emptyline(self) -> bool:
        return False

    def do_quit(self, arg: str) -> bool:
        """Leave the shell."""
        return True

    do_exit = do_quit
    do_EOF = do_quit

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

    def do_help(self, arg: str) -> None:
        """help NAME: the actor's signature and docstring."""
        if not arg:
            self.stdout.write("Commands: list [TEXT], help NAME, transactions, quit.\n"
                              "Anything else: ACTOR ARG... (key=value for keywords).\n")
            return
        try:
            ref = self.rt.resolve(arg)
        except ActorbtError as e:
            self.stdout.write(f"error: {e}\n")
            return
        self.stdout.write(f"{ref.path}{ref.signature}  [{'tree' if ref.is_tree else ref.kind.value}]\n")
        self.stdout.write((ref.doc or "(no docstring)") + "\n")

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
            self.stdout.write(pprint.pformat(result) + "\n")

    def completenames(self, text: str, *ignored: Any) -> list[str]:
        return [n for n in self._names() + ["list", "help", "quit", "transactions"] if n.startswith(text)]

    def complete_help(self, text: str, *ignored: Any) -> list[str]:
        return [n for n in self._names() if n.startswith(text)]

    def cmdloop(self, intro: Any = None) -> None:
        while True:
            try:
                super().cmdloop(intro)
                return
            except KeyboardInterrupt:
                self.stdout.write("\n")
                intro = ""
