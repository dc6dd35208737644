"""Reading what a worker left behind, as hostile data.

The job folder belongs to the sandbox, so any file in it may be a symbolic link
to something only the grader can read, a FIFO that blocks the reader forever, a
device, a hard link, or a zip bomb shaped like an ``.npz``. Files are opened with
``O_NOFOLLOW | O_NONBLOCK`` and taken only when ``fstat`` says they are regular,
singly linked and small enough; an ``.npz`` is read member by member from its
zip directory, each member's ``.npy`` header checked (plain numeric, boolean or
text dtypes, a shape whose size matches the bytes) before any data is decoded,
with bounded reads whatever the directory claims.
"""
from __future__ import annotations

import io
import json
import os
import re
import signal
import stat
import unicodedata
import zipfile
from pathlib import Path

import numpy as np

STATUS_LIMIT = 64 << 10        # status.json
NPZ_LIMIT = 128 << 20          # output.npz on disk
ARRAYS_LIMIT = 256 << 20       # all arrays decoded from it
MAX_MEMBERS = 64
ALLOWED_KINDS = set("biufU")   # bool, int, uint, float, unicode text: never objects, structs or bytes blobs

_FLAGS = os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0)


class UntrustedError(Exception):
    """What the worker left cannot be used; the message says why, for the student."""


def read_regular(path: Path, limit: int) -> bytes:
    """The bytes of ``path`` if it is a regular, singly linked file of at most ``limit`` bytes."""
    try:
        fd = os.open(path, _FLAGS)
    except FileNotFoundError:
        raise UntrustedError(f"{path.name} is missing") from None
    except OSError as err:
        raise UntrustedError(f"{path.name} could not be opened ({err.strerror})") from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise UntrustedError(f"{path.name} is not a regular file")
        if st.st_nlink != 1:
            raise UntrustedError(f"{path.name} is a hard link")
        if st.st_size > limit:
            raise UntrustedError(f"{path.name} is {st.st_size} bytes, more than the {limit} allowed")
        chunks, total = [], 0
        while total <= limit and (chunk := os.read(fd, min(1 << 20, limit + 1 - total))):
            chunks.append(chunk)
            total += len(chunk)
        if total > limit:
            raise UntrustedError(f"{path.name} grew past the {limit} bytes allowed")
        return b"".join(chunks)
    finally:
        os.close(fd)


def read_status(path: Path) -> tuple[bool, str]:
    """``(ok, error)`` from the worker's status.json."""
    try:
        status = json.loads(read_regular(path, STATUS_LIMIT))
    except ValueError:
        raise UntrustedError("status.json is not JSON") from None
    if not isinstance(status, dict) or not isinstance(status.get("ok"), bool):
        raise UntrustedError("status.json is not a status")
    error = status.get("error", "")
    return status["ok"], (error if isinstance(error, str) else repr(error))[:2000]


def _npy_header(fh) -> tuple[np.dtype, tuple[int, ...], bool]:
    version = np.lib.format.read_magic(fh)
    if version not in ((1, 0), (2, 0), (3, 0)):
        raise UntrustedError("an array has an unknown format")
    reader = {(1, 0): np.lib.format.read_array_header_1_0}.get(version, np.lib.format.read_array_header_2_0)
    shape, fortran, dtype = reader(fh, max_header_size=10000)
    return dtype, tuple(int(s) for s in shape), bool(fortran)


def read_arrays(path: Path) -> dict[str, np.ndarray]:
    """The arrays of an ``.npz``, each checked before it is decoded; ``UntrustedError`` at the first problem."""
    data = read_regular(path, NPZ_LIMIT)
    try:
        archive = zipfile.ZipFile(io.BytesIO(data))
    except (zipfile.BadZipFile, ValueError):
        raise UntrustedError("the answer file is not an .npz archive") from None
    members = archive.infolist()
    if len(members) > MAX_MEMBERS:
        raise UntrustedError(f"the answer holds {len(members)} arrays, more than {MAX_MEMBERS}")
    out: dict[str, np.ndarray] = {}
    budget = ARRAYS_LIMIT
    for info in members:
        name = info.filename.removesuffix(".npy")
        if not info.filename.endswith(".npy") or not name.isidentifier() or name in out:
            raise UntrustedError(f"the answer holds an unexpected member {info.filename[:60]!r}")
        try:
            with archive.open(info) as fh:
                dtype, shape, fortran = _npy_header(fh)
                if dtype.kind not in ALLOWED_KINDS or dtype.hasobject or dtype.fields is not None:
                    raise UntrustedError(f"array {name!r} has dtype {dtype}, not plain numbers or text")
                if any(s < 0 for s in shape):
                    raise UntrustedError(f"array {name!r} has a negative dimension")
                count = int(np.prod(shape, dtype=object))
                size = count * dtype.itemsize
                if size > budget:
                    raise UntrustedError(f"array {name!r} would take {size} bytes, over what is allowed")
                budget -= size
                raw = fh.read(size + 1)   # bounded, whatever the zip directory says
        except UntrustedError:
            raise
        except (zipfile.BadZipFile, ValueError, OSError, EOFError, SyntaxError, KeyError) as err:
            raise UntrustedError(f"array {name!r} could not be read ({type(err).__name__})") from None
        if len(raw) != size:
            raise UntrustedError(f"array {name!r} holds {len(raw)} bytes for a shape of {size}")
        array = np.frombuffer(raw, dtype=dtype).reshape(shape, order="F" if fortran else "C")
        out[name] = array.copy()  # writable and owned
    return out


_SUSPECT = re.compile("[^\n\t\x20-\x7e]")
_UNSAFE = {"Cc", "Cf", "Cs", "Zl", "Zp"}   # controls, format (bidi, zero-width), lone surrogates, line separators


def _escape(match: re.Match) -> str:
    c = match.group()
    if unicodedata.category(c) not in _UNSAFE:
        return c
    code = ord(c)
    return f"\\x{code:02x}" if code < 0x100 else f"\\u{code:04x}" if code < 0x10000 else f"\\U{code:08x}"


def printable(text: object, lines: bool = True) -> str:
    """``text`` safe for a terminal, CSV, JSON or HTML: every control, bidi or other invisible format character
    (C0, DEL, C1 and so ESC, U+202E, U+200B, lone surrogates, U+2028) written out as its escape, ``\\x1b``.
    Newlines and tabs stay when ``lines``; else they are escaped too (a one-line cell or name)."""
    text = str(text)
    if not lines:
        text = text.replace("\t", "\\t").replace("\n", "\\n")
    return _SUSPECT.sub(_escape, text)


def signal_name(returncode: int | None) -> str | None:
    """The name of the signal that ended a process (``returncode < 0``), real-time signals too."""
    if returncode is None or returncode >= 0:
        return None
    try:
        return signal.Signals(-returncode).name
    except ValueError:
        return f"signal {-returncode}"
