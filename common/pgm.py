"""PGM images, the format map_server's maps come in: binary (P5) or ASCII (P2), 8 or 16
bit, ``#`` comments in the header."""

from __future__ import annotations

import numpy as np


def is_pgm(raw: bytes) -> bool:
    return raw[:2] in (b"P5", b"P2")


def read_pgm(raw: bytes, where: str, error: type[Exception] = ValueError) -> np.ndarray:
    """The lightness (0..1, float) of the image ``raw`` [rows, cols], top row first. A
    file that is no PGM, or a broken one, raises ``error`` with a message that starts
    with ``where`` (the file, as the caller names it)."""
    magic = raw[:2]
    if not is_pgm(raw):
        raise error(f"{where}: not a PGM image (magic {magic!r}; expected P5 or P2)")
    fields: list[bytes] = []
    pos = 2
    while len(fields) < 3:  # width, height, maxval; '#' comments between them
        while pos < len(raw) and raw[pos : pos + 1].isspace():
            pos += 1
        if raw[pos : pos + 1] == b"#":
            pos = raw.find(b"\n", pos) + 1 or len(raw)
            continue
        end = pos
        while end < len(raw) and not raw[end : end + 1].isspace():
            end += 1
        if end == pos:
            raise error(f"{where}: truncated PGM header")
        fields.append(raw[pos:end])
        pos = end
    try:
        w, h, maxval = (int(f) for f in fields)
    except ValueError:
        raise error(f"{where}: bad PGM header {fields!r}") from None
    if w <= 0 or h <= 0 or not 0 < maxval < 65536:
        raise error(f"{where}: bad PGM size {w}x{h} or maxval {maxval}")
    if magic == b"P2":
        vals = np.array(raw[pos:].split()[: w * h], dtype=np.int64)
    else:
        pos += 1  # exactly one whitespace after maxval
        dtype = np.dtype(">u2") if maxval > 255 else np.dtype(np.uint8)
        vals = np.frombuffer(raw[pos : pos + w * h * dtype.itemsize], dtype=dtype)
    if vals.size != w * h:
        raise error(f"{where}: PGM data too short ({vals.size} of {w * h} pixels)")
    return vals.reshape(h, w).astype(np.float64) / maxval
