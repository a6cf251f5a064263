"""Safe file outputs and inputs, and the JSON text of a record (:class:`JsonRecord`).

Writes are atomic (a reader sees the old file or the new one, and the folder is fsynced) and
destroy nothing: a symbolic link is written through and stays; a device or FIFO is refused,
or with ``force=True`` written into; a folder, an input or (without ``force``) a read-only file
is refused.  :func:`check_replace` is the stricter check for a tree a command rewrites whole.
"""

from __future__ import annotations

import json
import os
import stat
import tempfile
from pathlib import Path

__all__ = ["MAX_JSON_BYTES", "JsonRecord", "OutputError", "atomic_write_bytes", "atomic_write_text", "check_input",
           "private_folder", "check_output", "check_replace", "read_json", "refuse_folder_name"]

#: Most bytes of a params, rig or manifest JSON file, checked before it is parsed (the package's
#: largest, a rig of 13 pairs, is about 110 KB; parsing holds some ten times a file's size).
MAX_JSON_BYTES = 4 << 20


class JsonRecord:
    """A record whose :meth:`to_dict` is JSON-ready, written as indented JSON text by :meth:`to_json`."""

    def to_dict(self) -> dict:
        """The record as plain JSON types; each record class defines it."""
        raise NotImplementedError

    def to_json(self) -> str:
        """:meth:`to_dict` as indented JSON text.

        Returns
        -------
        text : str
            The JSON document.
        """
        return json.dumps(self.to_dict(), indent=2)


class OutputError(ValueError):
    """An input or output path that must not be used; the message names the user's path."""


def _mode_for(path: Path) -> int:
    """Keep an existing file's permissions; a new file gets what open() would give it."""
    try:
        return path.stat().st_mode & 0o777
    except FileNotFoundError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask


def _fsync_folder(folder: Path) -> None:
    try:
        fd = os.open(folder, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
    except OSError:   # e.g. a platform that cannot open folders
        return
    try:
        os.fsync(fd)
    except OSError:   # some file systems do not support fsync on folders
        pass
    finally:
        os.close(fd)


def _kind(mode: int) -> str:
    for test, name in ((stat.S_ISDIR, "a folder"), (stat.S_ISCHR, "a character device"),
                       (stat.S_ISBLK, "a block device"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
                       (stat.S_ISSOCK, "a socket")):
        if test(mode):
            return name
    return "not a regular file"


def atomic_write_bytes(path, data: bytes) -> Path:
    """Write `data` to a temporary file beside `path`, flush it to disk, then rename (a link is
    written through; a device or FIFO is written into; a folder raises ``IsADirectoryError``).

    >>> import tempfile, pathlib
    >>> target = pathlib.Path(tempfile.mkdtemp()) / "out.txt"
    >>> atomic_write_bytes(target, b"hello").read_bytes()
    b'hello'
    """
    refuse_folder_name(path)
    path = Path(path)
    final = Path(os.path.realpath(path)) if path.is_symlink() else path
    try:
        mode = path.stat().st_mode   # through any link
    except FileNotFoundError:
        mode = None
    if mode is not None and stat.S_ISDIR(mode):
        raise IsADirectoryError(21, "Is a directory", str(path))
    if mode is not None and not stat.S_ISREG(mode):
        with open(path, "wb") as handle:   # a device or FIFO: write into it, never replace it
            handle.write(data)
        return path
    folder = final.parent
    fd, tmp = tempfile.mkstemp(prefix=f".{final.name}.", suffix=".tmp", dir=folder)
    try:
        os.chmod(tmp, _mode_for(final))
        with os.fdopen(fd, "wb") as handle:
            handle.write(data)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(tmp, final)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    _fsync_folder(folder)
    return path


def atomic_write_text(path, text: str) -> Path:
    """:func:`atomic_write_bytes` for UTF-8 text."""
    return atomic_write_bytes(path, text.encode("utf-8"))


def _same(a: Path, b: Path) -> bool:
    try:
        return os.path.samefile(a, b)
    except OSError:
        return os.path.realpath(a) == os.path.realpath(b)


def read_json(path, *, most_bytes: int = MAX_JSON_BYTES):
    """The JSON value of the file at `path`, refused unparsed above `most_bytes` bytes.

    Raises FileNotFoundError, OSError (unreadable), or ValueError saying why it is not JSON
    within the limits.

    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "a.json"
    >>> _ = path.write_text('{"n": 1}')
    >>> read_json(path)
    {'n': 1}
    >>> _ = path.write_text('{"n": 1' + "0" * 5000 + '}')
    >>> read_json(path)
    Traceback (most recent call last):
    ...
    ValueError: it holds a number of more than 4300 digits
    >>> read_json(path, most_bytes=100)
    Traceback (most recent call last):
    ...
    ValueError: it is larger than 100 bytes
    """
    import json

    check_input(path)   # a FIFO or a device is never opened
    with open(path, "rb") as handle:
        raw = handle.read(most_bytes + 1)
    if len(raw) > most_bytes:
        raise ValueError(f"it is larger than {most_bytes} bytes")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise ValueError("it is not UTF-8 text") from None
    try:
        return json.loads(text)
    except RecursionError:
        raise ValueError("its JSON is nested too deeply") from None
    except json.JSONDecodeError as exc:
        raise ValueError(f"it is not valid JSON: {exc}") from None
    except ValueError as exc:   # int() refuses more than sys.get_int_max_str_digits() digits
        if "digits" in str(exc):
            import sys

            raise ValueError(f"it holds a number of more than {sys.get_int_max_str_digits()} digits") from None
        raise ValueError(f"it is not valid JSON: {exc}") from None


def check_input(path, *, what: str = "input") -> Path:
    """Refuse an input that exists but is not a regular file (a FIFO blocks, ``/dev/zero`` never
    ends) before anything opens it; a missing file is left to the reader.

    >>> check_input("/dev/zero", what="--params-file")
    Traceback (most recent call last):
    ...
    ismb_lab._core.files.OutputError: --params-file '/dev/zero': a character device, not a regular file
    """
    path = Path(path)
    try:
        mode = path.stat().st_mode
    except (OSError, ValueError):   # missing, a loop of links, a NUL in the name: the reader says
        return path
    if not stat.S_ISREG(mode):
        if stat.S_ISDIR(mode):
            raise OutputError(f"{what} {str(path)!r}: a folder, not a file")
        raise OutputError(f"{what} {str(path)!r}: {_kind(mode)}, not a regular file")
    return path


def refuse_folder_name(text, what: str = "output") -> None:
    """Refuse an output name written as a folder's (ending in ``/``, ``/.`` or ``/..``): it needs
    the text, as ``Path("out.json/")`` is ``out.json``.

    >>> refuse_folder_name("out.json/", "--json")
    Traceback (most recent call last):
    ...
    ismb_lab._core.files.OutputError: --json 'out.json/' names a folder (it ends with '/'); give a file name
    """
    if not isinstance(text, (str, bytes)):
        return
    text = os.fsdecode(text)
    last = text.replace(os.altsep or os.sep, os.sep).rsplit(os.sep, 1)[-1]
    if last in ("", ".", ".."):
        end = "/" if last == "" else last
        raise OutputError(f"{what} {text!r} names a folder (it ends with {end!r}); give a file name")


def _stat_or_none(stat_of, shown: str):
    """``stat_of()``, or None where the path does not exist; any other OSError as an OutputError."""
    try:
        return stat_of()
    except FileNotFoundError:
        return None
    except OSError as exc:
        raise OutputError(f"{shown}: {exc.strerror or exc}") from None


def check_output(path, *, inputs=(), force: bool = False, what: str = "output") -> Path:
    """Check, before any work, that `path` may be written by :func:`atomic_write_bytes`.

    It may never be one of `inputs`, whatever the link or spelling, not even with `force`;
    `force` allows replacing a read-only file and writing into a device or FIFO.  `what` names
    the path in the :class:`OutputError`'s one line, e.g. ``"--json"``.

    >>> import tempfile, pathlib
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> check_output(folder / "p.json").name
    'p.json'
    >>> check_output(folder / "nodir" / "p.json", what="--out")
    Traceback (most recent call last):
    ...
    ismb_lab._core.files.OutputError: --out '.../nodir/p.json': the folder '.../nodir' does not exist
    >>> check_output(str(folder) + "/p.json/", what="--json")
    Traceback (most recent call last):
    ...
    ismb_lab._core.files.OutputError: --json '.../p.json/' names a folder (it ends with '/'); give a file name
    """
    refuse_folder_name(path, what)
    path = Path(path)
    shown = f"{what} {str(path)!r}"
    for source in inputs:
        if source is not None and _same(path, Path(source)):
            raise OutputError(f"{shown} is also an input of this command ({str(source)!r}); "
                              "an output never replaces an input: choose another name")
    final = Path(os.path.realpath(path)) if path.is_symlink() else path
    if path.is_symlink() and not final.parent.is_dir():
        raise OutputError(f"{shown} is a symbolic link to {str(final)!r}, whose folder does not exist")
    st = _stat_or_none(path.stat, shown)   # through any link (/dev/stdout -> /proc/self/fd/1 -> a pipe)
    if st is not None and stat.S_ISDIR(st.st_mode):
        raise OutputError(f"{shown} is a folder; give a file name")
    if st is not None and not stat.S_ISREG(st.st_mode):
        if not force:
            raise OutputError(f"{shown} is {_kind(st.st_mode)}, which an output never replaces; "
                              "give --force to write into it")
        if not os.access(path, os.W_OK):
            raise OutputError(f"{shown}: {_kind(st.st_mode)} that cannot be written")
        return path
    if st is not None and not force and (not st.st_mode & 0o222 or not os.access(final, os.W_OK)):
        raise OutputError(f"{shown} is a read-only file; give --force to replace it")
    folder = final.parent
    if not folder.is_dir():
        why = "is not a folder" if folder.exists() else "does not exist"
        raise OutputError(f"{shown}: the folder {str(folder)!r} {why}")
    try:   # the only sure test of a writable folder (read-only mounts, ACLs, root)
        fd, probe = tempfile.mkstemp(prefix=f".{final.name}.", suffix=".probe", dir=folder)
    except OSError as exc:
        raise OutputError(f"{shown}: cannot create a file in {str(folder)!r} "
                          f"({exc.strerror or exc})") from None
    os.close(fd)
    os.unlink(probe)
    return path


def check_replace(path, *, what: str = "output") -> Path:
    """Check that `path` is new, or a regular, writable file that a rename may replace.

    Stricter than :func:`check_output` (no link, device, FIFO or read-only file, no ``force``),
    for a tree a command rewrites whole.  A file whose folder does not exist yet passes.

    >>> import tempfile, pathlib
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> (folder / "link.png").symlink_to(folder / "elsewhere.png")
    >>> check_replace(folder / "link.png", what="render")
    Traceback (most recent call last):
    ...
    ismb_lab._core.files.OutputError: render '.../link.png' is a symbolic link, which is never written through or replaced; remove it first
    """
    path = Path(path)
    shown = f"{what} {str(path)!r}"
    st = _stat_or_none(path.lstat, shown)
    if st is not None and stat.S_ISLNK(st.st_mode):
        raise OutputError(f"{shown} is a symbolic link, which is never written through or replaced; "
                          "remove it first")
    if st is not None and not stat.S_ISREG(st.st_mode):
        raise OutputError(f"{shown} is {_kind(st.st_mode)}, which an output never replaces")
    if st is not None and (not st.st_mode & 0o222 or not os.access(path, os.W_OK)):
        raise OutputError(f"{shown} is a read-only file, which is never replaced; make it writable "
                          "or remove it first")
    return check_output(path, what=what) if path.parent.is_dir() else path


def private_folder(name: str, temp: str | None = None) -> str:
    """``<temp>/<name>-<uid>`` (mode 0700) if it is this account's private folder, else a new
    private folder in `temp` (never someone else's).

    >>> import tempfile
    >>> folder = private_folder("ismb-doc", tempfile.mkdtemp())
    >>> oct(os.stat(folder).st_mode & 0o777), folder == private_folder("ismb-doc", os.path.dirname(folder))
    ('0o700', True)
    """
    temp = temp or tempfile.gettempdir()
    path = os.path.join(temp, f"{name}-{os.getuid()}")
    try:
        os.mkdir(path, 0o700)
    except FileExistsError:
        pass
    try:
        info = os.lstat(path)
        if stat.S_ISDIR(info.st_mode) and info.st_uid == os.getuid() and not info.st_mode & 0o077:
            return path
    except OSError:
        pass
    return tempfile.mkdtemp(prefix=f"{name}-", dir=temp)
