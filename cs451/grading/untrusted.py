"""Reading what a worker left behind, as hostile data.

The job folder belongs to the sandbox, so any file in it may be a symbolic link
to something only the grader can read, a FIFO that blocks the reader forever, a
device, a hard link, or a zip bomb shaped like an ``.npz``. Files are opened with
``O_NOFOLLOW | O_NONBLOCK`` and taken only when ``fstat`` says they are regular,
singly linked and small enough; an ``.npz`` is read in place, never whole: every
member's ``.npy`` header is checked first (plain numeric, boolean or text dtypes,
sizes that add up to at most ``ARRAYS_LIMIT``), and only then is each member
decoded straight into its own array in bounded chunks, whatever the directory
claims, so an answer costs the grader no more than its arrays' declared size.
"""
from __future__ import annotations

import json
import os
import re
import signal
import stat
import struct
import unicodedata
import zipfile
from zlib import error as zlib_error
from pathlib import Path

import numpy as np

STATUS_LIMIT = 64 << 10        # status.json
NPZ_LIMIT = 128 << 20          # output.npz on disk (read in place, never whole)
ARRAYS_LIMIT = 80 << 20        # all arrays decoded from it (an honest answer: at most 6 MB; a million-node hierarchy: 69 MiB)
CHUNK = 1 << 20                # bytes decoded at a time
MAX_MEMBERS = 64
DIRECTORY_ENTRY = 1024     # bytes of zip directory allowed per member (np.savez writes about 100)
ALLOWED_KINDS = set("biufU")   # bool, int, uint, float, unicode text: never objects, structs or bytes blobs

_FLAGS = os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0)


class UntrustedError(Exception):
    """What the worker left cannot be used; the message says why, for the student."""


def _open_regular(path: Path, limit: int) -> int:
    """A descriptor of ``path`` if it is a regular, singly linked file of at most ``limit`` bytes."""
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
    except BaseException:
        os.close(fd)
        raise
    return fd


def read_regular(path: Path, limit: int) -> bytes:
    """The bytes of ``path`` if it is a regular, singly linked file of at most ``limit`` bytes."""
    fd = _open_regular(path, limit)
    try:
        data = bytearray()
        while len(data) <= limit and (chunk := os.read(fd, min(CHUNK, limit + 1 - len(data)))):
            data += chunk
        if len(data) > limit:
            raise UntrustedError(f"{path.name} grew past the {limit} bytes allowed")
        return bytes(data)
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
    try:
        version = np.lib.format.read_magic(fh)
        if version not in ((1, 0), (2, 0), (3, 0)):
            raise UntrustedError("an array has an unknown format")
        reader = {(1, 0): np.lib.format.read_array_header_1_0}.get(version, np.lib.format.read_array_header_2_0)
        shape, fortran, dtype = reader(fh, max_header_size=10000)
    except UntrustedError:
        raise
    except (ValueError, OSError, EOFError, SyntaxError, TypeError) as err:
        raise UntrustedError(f"array {getattr(fh, 'name', '')!r} could not be read ({type(err).__name__})") from None
    return dtype, tuple(int(s) for s in shape), bool(fortran)


def _fill(fh, array: np.ndarray) -> int:
    """Decode a member's data straight into ``array``, a chunk at a time; the bytes it held (one more if it has more)."""
    view = memoryview(array.reshape(-1).view(np.uint8)) if array.size else memoryview(bytearray())
    done = 0
    while done < len(view):
        chunk = fh.read(min(CHUNK, len(view) - done))
        if not chunk:
            return done
        view[done:done + len(chunk)] = chunk
        done += len(chunk)
    return done + len(fh.read(1))


def read_arrays(path: Path, limit: int = ARRAYS_LIMIT) -> dict[str, np.ndarray]:
    """The arrays of an ``.npz``, every header checked before any is decoded; ``UntrustedError`` at the first problem.

    At most ``limit`` bytes of arrays in all, judged from the headers: a larger answer is refused unread."""
    fd = _open_regular(path, NPZ_LIMIT)
    with os.fdopen(fd, "rb") as file:
        _small_directory(file)
        try:
            archive = zipfile.ZipFile(file)
        except (zipfile.BadZipFile, ValueError, OSError):
            raise UntrustedError("the answer file is not an .npz archive") from None
        with archive:
            members = archive.infolist()
            if len(members) > MAX_MEMBERS:
                raise UntrustedError(f"the answer holds {len(members)} arrays, more than {MAX_MEMBERS}")
            headers, total = [], 0
            for info in members:   # every header first: nothing is decoded from an answer that is too large
                name = info.filename.removesuffix(".npy")
                if not info.filename.endswith(".npy") or not name.isidentifier() or name in {h[1] for h in headers}:
                    raise UntrustedError(f"the answer holds an unexpected member {info.filename[:60]!r}")
                with _member(archive, info, name) as fh:
                    dtype, shape, fortran = _npy_header(fh)
                _check_header(name, dtype, shape)
                size = int(np.prod(shape, dtype=object)) * dtype.itemsize
                total += size
                if total > limit:
                    raise UntrustedError(f"array {name!r} would take {size} bytes, over what is allowed "
                                         f"({limit >> 20} MiB for the whole answer)")
                headers.append((info, name, dtype, shape, fortran, size))
            out: dict[str, np.ndarray] = {}
            for info, name, dtype, shape, fortran, size in headers:
                array = np.empty(shape, dtype=dtype, order="F" if fortran else "C")
                with _member(archive, info, name) as fh:
                    _npy_header(fh)
                    got = _fill(fh, array.T if fortran else array)
                if got != size:
                    raise UntrustedError(f"array {name!r} holds {got} bytes for a shape of {size}")
                out[name] = array
            return out


def _small_directory(file) -> None:
    """Refuse an archive whose directory (read whole by ``zipfile``) could hold more than ``MAX_MEMBERS`` entries,
    from its end record, before the directory is parsed: a 128 MiB directory is millions of entries in memory."""
    end = file.seek(0, os.SEEK_END)
    file.seek(max(0, end - (22 + 0xFFFF)))
    tail = file.read()
    at = tail.rfind(b"PK\x05\x06")
    if at < 0 or len(tail) - at < 22:
        raise UntrustedError("the answer file is not an .npz archive")
    entries, size = struct.unpack("<HL", tail[at + 10:at + 16])
    if entries > MAX_MEMBERS or size > MAX_MEMBERS * DIRECTORY_ENTRY or tail[max(0, at - 20):at].startswith(b"PK\x06\x07"):
        raise UntrustedError(f"the answer's directory is larger than {MAX_MEMBERS} arrays need")


class _member:
    """One member of the archive, open; a read error is the answer's, named."""

    def __init__(self, archive: zipfile.ZipFile, info: zipfile.ZipInfo, name: str):
        self.archive, self.info, self.name = archive, info, name

    def __enter__(self):
        try:
            self.fh = self.archive.open(self.info)
        except (zipfile.BadZipFile, ValueError, OSError, EOFError, KeyError, NotImplementedError) as err:
            raise UntrustedError(f"array {self.name!r} could not be read ({type(err).__name__})") from None
        return self

    def read(self, n: int) -> bytes:
        try:
            return self.fh.read(n)
        except (zipfile.BadZipFile, ValueError, OSError, EOFError, zlib_error) as err:
            raise UntrustedError(f"array {self.name!r} could not be read ({type(err).__name__})") from None

    def __exit__(self, *exc) -> None:
        self.fh.close()


def _check_header(name: str, dtype: np.dtype, shape: tuple[int, ...]) -> None:
    if dtype.kind not in ALLOWED_KINDS or dtype.hasobject or dtype.fields is not None:
        raise UntrustedError(f"array {name!r} has dtype {dtype}, not plain numbers or text")
    if any(s < 0 for s in shape):
        raise UntrustedError(f"array {name!r} has a negative dimension")


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
