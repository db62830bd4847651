"""The importer's entry point: choose the dialect, read the files, convert."""

from __future__ import annotations

from pathlib import Path
from typing import Iterable

from ._convert import Importer
from ._errors import BtXmlError, Pos
from ._nodes import NodeModel
from ._pytwb import PytwbImporter

__all__ = ["DIALECTS", "import_files"]

#: importer class by dialect name
DIALECTS: dict[str, type[Importer]] = {"btcpp": Importer, "pytwb": PytwbImporter}


def import_files(
    paths: Iterable[str | Path], model: NodeModel | None = None, dialect: str = "btcpp"
) -> dict[str, dict]:
    """Convert every tree of these XML files; returns mission dicts by name, in file
    order (included files where they are included).

    Raises:
        BtXmlError: the first problem found, located in its XML file.
    """
    if dialect not in DIALECTS:
        raise BtXmlError(
            Pos("<command line>", 1, 1), f"unknown dialect {dialect!r}, expected one of: {', '.join(DIALECTS)}"
        )
    importer = DIALECTS[dialect](model)
    for path in paths:
        importer.load(path)
    return importer.convert_all()
