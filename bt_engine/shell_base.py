"""What the two actor shells (``actorbt shell`` and ``actorbt rshell``) share: their
history, ``~/.actorbt_history`` or the file ``$ACTORBT_HISTORY`` names (through readline
where Python has it), and the ways out."""

from __future__ import annotations

import cmd
import os
import pathlib

HISTORY = pathlib.Path(os.environ.get("ACTORBT_HISTORY", pathlib.Path.home() / ".actorbt_history"))
#: the lines the file keeps
HISTORY_LENGTH = 1000


class ShellBase(cmd.Cmd):
    """A ``cmd.Cmd`` that reads the history as its loop starts and writes it as the loop
    ends, only at a terminal (``use_rawinput``): lines from a file or a pipe are no
    history; without readline, or with an unreadable file, the shell runs without it.
    ``quit``, ``exit`` and end of input leave; an empty line does nothing."""

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

                readline.set_history_length(HISTORY_LENGTH)
                readline.write_history_file(HISTORY)
            except (ImportError, OSError):
                pass

    def emptyline(self) -> bool:
        return False  # cmd.Cmd would repeat the last line: a second robot motion

    def do_quit(self, arg: str) -> bool:
        """Leave the shell."""
        return True

    do_exit = do_quit
    do_EOF = do_quit
