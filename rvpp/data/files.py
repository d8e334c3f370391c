"""Reading the files of a case safely: what a file holds, its text, and paths that stay
inside the case.

A case is a portable folder: ``case.yaml`` names its history CSV by a path relative to
the folder. A path that is absolute, takes a ``..`` step or follows a link out of the
folder (or, for an upload, out of the uploaded files) is refused before anything is
opened. Files must be UTF-8 text (a byte-order mark is fine); anything else is named
(a zip or Excel workbook, a PDF, UTF-16 or Latin-1 text, binary data) rather than parsed
as garbage. Messages quote at most a short, printable excerpt of a file.

An upload is also bounded in what it may cost (:class:`UploadLimits`): the bytes sent,
the bytes unzipped (counted while inflating, never taken from a zip's headers), the rows
and columns of history and the time spent reading it (:class:`UploadBudget`).
"""

from __future__ import annotations

import errno
import io
import os
import re
import stat
import time
import uuid
import zipfile
import zlib
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path, PurePosixPath
from typing import Any, BinaryIO

from ..errors import CaseFileError, CasePathError, UploadError, UploadLimitError

MIB = 1024 ** 2
EXCERPT_CHARS = 40
UTF8_BOM = b"\xef\xbb\xbf"
CHUNK_BYTES = 64 * 1024
SNIFF_BYTES = 8192

# Leading bytes of the files most often sent where a text file belongs.
MAGIC = (
    (b"PK\x03\x04", "a zip archive (an Excel .xlsx workbook is one too)"),
    (b"PK\x05\x06", "an empty zip archive"),
    (b"\x1f\x8b", "a gzip archive"),
    (b"%PDF-", "a PDF document"),
    (b"\x89PNG\r\n\x1a\n", "a PNG image"),
    (b"\xff\xd8\xff", "a JPEG image"),
    (b"\xd0\xcf\x11\xe0\xa1\xb1\x1a\xe1", "an old-style Office file (.xls, .doc)"),
    (b"7z\xbc\xaf\x27\x1c", "a 7-Zip archive"),
    (b"Rar!\x1a\x07", "a RAR archive"),
    (b"\xff\xfe\x00\x00", "UTF-32 text"),
    (b"\x00\x00\xfe\xff", "UTF-32 text"),
    (b"\xff\xfe", "UTF-16 text"),
    (b"\xfe\xff", "UTF-16 text"),
)
# What zipfile.ZipFile raises on data that is not a zip it can read: damaged records, a
# version or size it does not support, a name that is not UTF-8 (a ValueError).
UNREADABLE_ZIP = (zipfile.BadZipFile, zipfile.LargeZipFile, ValueError, EOFError, NotImplementedError)
WINDOWS_DRIVE = re.compile(r"^[A-Za-z]:")
S_IFMT, S_IFLNK = 0o170000, 0o120000


@dataclass(frozen=True)
class UploadLimits:
    """What reading one upload may cost; each limit exceeded raises :class:`UploadLimitError`.

    The defaults let a year of 15-minute history for 100 units through: a 30 MiB CSV, or a
    workbook of about 25 MiB that unzips to 140-180 MiB. Reading a workbook is slow (openpyxl
    parses every cell): a year of quarter-hours for 53 series took 8 s on an idle machine and
    24-35 s on a busy one, hence the generous time limit.
    """

    upload_bytes: int = 64 * MIB        # every file as sent
    unzipped_bytes: int = 256 * MIB     # inflated from zips and workbooks, counted while reading
    zip_members: int = 1000             # entries of one zip or workbook
    history_rows: int = 200_000         # about 22 years of hours, or 5.7 years of quarter-hours
    history_columns: int = 500          # the timestamp, three prices and one column per unit
    parse_s: float = 120.0              # reading and checking the upload [s]


class UploadBudget:
    """What is left of the limits while one upload is read: unzipped bytes and time."""

    def __init__(self, limits: UploadLimits):
        self.limits = limits
        self.unzipped = 0
        self._end = time.monotonic() + limits.parse_s

    def check_time(self, doing: str) -> None:
        """Refuse once reading has taken longer than the limit; ``doing`` says what was under way."""
        if time.monotonic() > self._end:
            raise UploadLimitError(f"the upload took longer than {self.limits.parse_s:g} s to read (stopped while "
                                   f"{doing}); upload a smaller case")

    def count_unzipped(self, n: int, name: str) -> None:
        self.unzipped += n
        if self.unzipped > self.limits.unzipped_bytes:
            raise UploadLimitError(f"{name}: unpacks to more than {_mib(self.limits.unzipped_bytes)}; "
                                   "a case is usually a few MiB")


def excerpt(value: Any, limit: int = EXCERPT_CHARS) -> str:
    """``value`` as short, printable text for a message (control characters as ``?``)."""
    text = "".join(ch if ch.isprintable() else "?" for ch in str(value)[:limit + 1])
    return text if len(text) <= limit else text[:limit - 1] + "…"


# Characters that text shown, stored or exported may not hold: control characters (C0, DEL and C1:
# a terminal obeys them, Excel refuses them in a cell) and the bidirectional embeddings, overrides
# and isolates (U+202A..U+202E, U+2066..U+2069), which reorder the text shown after them.
CONTROL_CHARACTERS = re.compile(r"[\x00-\x1f\x7f-\x9f]")
BIDI_CONTROLS = re.compile(r"[\u202a-\u202e\u2066-\u2069]")


def refused_character(text: str, rules) -> str | None:
    """What ``text`` may not hold, for a message: ``"control characters (found U+001B)"`` for the
    first ``(pattern, what)`` of ``rules`` that it matches; ``None`` if it matches none."""
    for pattern, what in rules:
        if found := pattern.search(text):
            return f"{what} (found U+{ord(found.group()):04X})"
    return None


def excerpt_names(names, shown: int = 8) -> str:
    """Names for a message (e.g. a CSV header): the first ``shown``, each cut short, quoted."""
    names = list(names)
    text = ", ".join(f'"{excerpt(name, 30)}"' for name in names[:shown])
    return (text + (f" and {len(names) - shown} more" if len(names) > shown else "")) if names else "none"


def sniff(data: bytes) -> str | None:
    """What ``data`` seems to be when it is not text, e.g. ``"a PDF document"``; ``None`` for text."""
    for magic, kind in MAGIC:
        if data.startswith(magic):
            return kind
    if b"\x00" in data[:SNIFF_BYTES]:
        return "binary data (it holds NUL bytes)"
    return None


def decode_text(data: bytes, name: str) -> str:
    """The UTF-8 text of file ``name``; a leading byte-order mark is dropped.

    Anything else raises :class:`CaseFileError` saying what the file seems to be, e.g.
    ``history.csv: not UTF-8 text: byte 1234 (line 5, column 17) is 0xE9, which looks
    like Latin-1/Windows-1252; save the file as UTF-8`` (bytes, lines and columns count from 1).
    """
    kind = sniff(data)
    if kind is not None:
        raise CaseFileError(f"{name}: is {kind}, not UTF-8 text")
    if data.startswith(UTF8_BOM):
        data = data[len(UTF8_BOM):]
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        at = exc.start
        line = data.count(b"\n", 0, at) + 1
        column = at - data.rfind(b"\n", 0, at)
        guess = "looks like Latin-1/Windows-1252" if _is_cp1252(data) else "is not valid UTF-8"
        raise CaseFileError(f"{name}: not UTF-8 text: byte {at + 1} (line {line}, column {column}) is "
                            f"0x{data[at]:02X}, which {guess}; save the file as UTF-8") from None


def _is_cp1252(data: bytes) -> bool:
    try:
        data.decode("cp1252")
    except UnicodeDecodeError:
        return False
    return True


def read_file(path: Path, name: str, max_bytes: int | None = None) -> bytes:
    """The bytes of a file on disk; a folder, a named pipe or device, a missing file, no
    permission or more than ``max_bytes`` raise :class:`CaseFileError` naming ``name``."""
    try:
        with open_regular(path, name) as handle:
            data = handle.read() if max_bytes is None else handle.read(max_bytes + 1)
    except OSError as exc:
        raise CaseFileError(f"{name}: cannot be read ({exc.strerror or exc})") from None
    if max_bytes is not None and len(data) > max_bytes:
        raise CaseFileError(f"{name}: is larger than {_mib(max_bytes)}; a case file is usually a few KiB")
    return data


def open_regular(path: Path, name: str, error: type[Exception] = CaseFileError) -> BinaryIO:
    """``path`` opened for reading, only if it is a regular file (links followed).

    A folder, a named pipe, a device or a socket raises ``error`` naming ``name``, e.g.
    ``history.csv: not a regular file (it is a named pipe)``, before it is opened: opening a
    named pipe waits for a writer, and a device such as ``/dev/zero`` never ends. The file
    is opened without waiting and checked again once open, in case it changed in between.
    Other failures (missing, no permission) raise :class:`OSError` for the caller to name.
    """
    def refuse(mode: int) -> None:
        if stat.S_ISDIR(mode):
            raise error(f"{name}: is a folder, not a file")
        if not stat.S_ISREG(mode):
            raise error(f"{name}: not a regular file (it is {_file_kind(mode)}); give a file saved on disk")

    refuse(os.stat(path).st_mode)
    descriptor = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0))
    try:
        refuse(os.fstat(descriptor).st_mode)
        return os.fdopen(descriptor, "rb")
    except BaseException:
        os.close(descriptor)
        raise


def _file_kind(mode: int) -> str:
    """What a file that is not regular is, for a message."""
    if stat.S_ISFIFO(mode):
        return "a named pipe"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    if stat.S_ISSOCK(mode):
        return "a socket"
    return "not a plain file"


# ----------------------------------------------------------------------------- paths


# What makes a written path unsafe (:func:`_path_parts`).
NUL, ABSOLUTE, STEPS_OUT, EMPTY = "nul", "absolute", "steps out", "empty"


def relative_path(text: Any, field: str, file: str) -> PurePosixPath:
    """The path a case writes in ``field`` of ``file``, checked to stay inside its folder.

    Nothing is opened. Backslashes count as separators (a case written on Windows), so
    ``..\\x.csv`` is refused like ``../x.csv``. Raises :class:`CasePathError`.
    """
    example = f"name a file inside the case folder, relative to {file}, e.g. history.csv"
    if not isinstance(text, str) or not text.strip():
        raise CasePathError(f'{file}: "{field}" must {example}')
    fault, parts = _path_parts(text.strip())
    if fault:
        problem = {NUL: "holds a NUL character", ABSOLUTE: "is an absolute path",
                   STEPS_OUT: 'steps out of the case folder with ".."', EMPTY: "names the case folder itself"}[fault]
        raise CasePathError(f'{file}: {field} "{excerpt(text, 80)}" {problem}; {example}')
    return PurePosixPath(*parts)


def inside_folder(folder: Path, relative: PurePosixPath, field: str, file: str) -> Path:
    """``relative`` (from :func:`relative_path`) within ``folder`` on disk, links followed.

    A link that leads out of ``folder`` raises :class:`CasePathError`; nothing is opened.
    """
    root = folder.resolve()
    target = root.joinpath(*relative.parts).resolve()
    if not target.is_relative_to(root):
        raise CasePathError(f'{file}: {field} "{excerpt(relative, 80)}" is a link to a file outside the case '
                            "folder; copy the file into the folder")
    return target


def upload_path(name: str) -> PurePosixPath:
    """The name of an uploaded file or zip member as a clean relative path.

    An absolute name, a ``..`` step or a NUL raises :class:`CasePathError`: an upload may
    only refer to its own files.
    """
    fault, parts = _path_parts(name)
    if fault:
        problem = {NUL: "the name holds a NUL character",
                   ABSOLUTE: "an absolute path; an upload may only hold files inside its own folder",
                   STEPS_OUT: 'the name steps out of the upload with ".."', EMPTY: "the name is empty"}[fault]
        raise CasePathError(f'uploaded file "{excerpt(name, 80)}": {problem}')
    return PurePosixPath(*parts)


def _path_parts(written: str) -> tuple[str | None, list[str]]:
    """The parts of a relative path (backslashes count as separators, ``.`` and empty parts
    dropped), or what makes it unsafe: a NUL, an absolute path, a ``..`` step, no part at all."""
    if "\x00" in written:
        return NUL, []
    written = written.replace("\\", "/")
    if written.startswith("/") or WINDOWS_DRIVE.match(written):
        return ABSOLUTE, []
    parts = [part for part in written.split("/") if part not in ("", ".")]
    if ".." in parts:
        return STEPS_OUT, []
    return (None, parts) if parts else (EMPTY, [])


# ----------------------------------------------------------------------------- zips


def open_zip(data: bytes, name: str, limits: UploadLimits, expected: str = "a zip archive") -> zipfile.ZipFile:
    """An uploaded zip (or workbook: ``expected`` names it) whose every member stays inside the upload.

    A damaged zip, too many members, an absolute or ``..`` member name, a link or an
    encrypted member is refused before any member is inflated.
    """
    try:
        archive = zipfile.ZipFile(io.BytesIO(data))
    except UNREADABLE_ZIP:
        kind = sniff(data) or ("empty" if not data else "text or other data, not a zip archive")
        raise UploadError(f"{name}: cannot be read as {expected} (it seems to be {kind})") from None
    members = archive.infolist()
    if len(members) > limits.zip_members:
        archive.close()
        raise UploadLimitError(f"{name}: holds {len(members):,} entries; an upload may hold at most "
                               f"{limits.zip_members:,}")
    for member in members:
        try:
            upload_path(member.filename)
        except CasePathError as err:
            archive.close()
            raise CasePathError(f"{name}: member {err.problems[0].removeprefix('uploaded file ')}") from None
        if (member.external_attr >> 16) & S_IFMT == S_IFLNK:
            archive.close()
            raise CasePathError(f'{name}: member "{excerpt(member.filename, 80)}" is a symbolic link; an upload '
                                "may only hold plain files")
        if member.flag_bits & 0x1:
            archive.close()
            raise UploadError(f'{name}: member "{excerpt(member.filename, 80)}" is encrypted; upload a zip '
                              "without a password")
    return archive


def unzip(archive: zipfile.ZipFile, member: zipfile.ZipInfo, name: str, budget: UploadBudget,
          keep: bool = True) -> bytes:
    """The inflated bytes of ``member``, counted against the budget while they are read
    (``keep=False``: only counted and checked, nothing kept)."""
    where = member_name(name, member)
    chunks = []
    with unpacking(name, member):
        with archive.open(member) as stream:
            while chunk := stream.read(CHUNK_BYTES):
                budget.count_unzipped(len(chunk), name)
                budget.check_time(f"unpacking {where}")
                if keep:
                    chunks.append(chunk)
    return b"".join(chunks)


def member_name(name: str, member: zipfile.ZipInfo) -> str:
    """A zip member for a message: ``prices.zip, member "marginalpdbc_20180326.1"``."""
    return f'{name}, member "{excerpt(member.filename, 80)}"'


@contextmanager
def unpacking(name: str, member: zipfile.ZipInfo, error: type[Exception] = UploadError) -> Iterator[None]:
    """Turn what reading ``member`` of zip ``name`` raises when it is damaged (a corrupt
    stream, a bad CRC, cut short), encrypted or packed with a method Python cannot read
    into ``error`` naming the zip and the member (:func:`member_name`)."""
    where = member_name(name, member)
    try:
        yield
    except zipfile.BadZipFile:
        raise error(f"{where}: is damaged (its data does not match the zip's records)") from None
    except RuntimeError as exc:
        if member.flag_bits & 0x1:
            raise error(f"{where}: is encrypted; give a zip without a password") from None
        raise error(f"{where}: cannot be unpacked ({excerpt(exc, 80)})") from None
    except (NotImplementedError, EOFError, OSError, ValueError, zlib.error) as exc:
        # ValueError: an offset in the records points before the file; a name that is not UTF-8
        raise error(f"{where}: cannot be unpacked ({excerpt(exc, 80)})") from None


def _mib(n: int) -> str:
    return f"{n / MIB:g} MiB"


@contextmanager
def replacing(path: str | Path) -> Iterator[Path]:
    """A temporary path beside ``path`` (same suffix) to write to; it replaces ``path`` only
    when the block ends without error, so ``path`` is never seen half-written."""
    path = Path(path)
    temporary = sibling(path, "tmp")
    try:
        yield temporary
        os.replace(temporary, path)
    finally:
        temporary.unlink(missing_ok=True)


def check_replaceable(path: str | Path, headers: tuple[bytes, ...], kind: str) -> None:
    """Refuse to write ``path`` over anything but an earlier file of the same ``kind``.

    A missing ``path`` is fine, and so is a file starting with one of ``headers``, as the
    files of that kind that rvpp writes do; a folder, a device, a dangling link or any
    other file raises :class:`OSError` naming ``path`` and the headers expected, so a
    mistyped output path cannot destroy an unrelated file. Only the first bytes are read,
    and they are never shown.
    """
    path = Path(path)
    if not os.path.lexists(path):
        return
    if path.is_dir():
        raise IsADirectoryError(errno.EISDIR, "it is a folder, not a file", str(path))
    if not path.is_file():
        raise FileExistsError(errno.EEXIST, "it exists and is not a regular file", str(path))
    with path.open("rb") as handle:
        start = handle.read(max(len(header) for header in headers))
    if not start.startswith(headers):
        expected = " or ".join(repr(header.decode()) for header in headers)
        raise FileExistsError(errno.EEXIST, f"it exists and is not {kind}, whose first line starts with {expected}; "
                              "remove it first or choose another path", str(path))


def sibling(path: Path, tag: str) -> Path:
    """A hidden, unique name beside ``path`` with the same suffix, e.g. ``.plan.tmp-1a2b3c4d.xlsx``."""
    return path.with_name(f".{path.stem}.{tag}-{uuid.uuid4().hex[:8]}{path.suffix}")
