"""Opening files a user names, or that a file they opened names (a model's material library, a
scene's texture): every loader reads user files through here.

Only regular files are opened (symbolic links are followed to what they point at): a FIFO or a
device such as /dev/stdin would block the program, /dev/zero would be read without end, and a
directory is no file. Each kind of file has a size limit, checked before reading and again while
reading (a file may grow, and /proc files say they are empty). What is refused is one
UserFileError naming the file, what it is, and who named it; it is an OSError, so loaders that
already turn an unreadable file into their own one-line error handle it as they handle any other.

The file is opened without waiting (O_NONBLOCK) and checked on the open descriptor, so nothing
can be swapped in between the check and the read.
"""

from __future__ import annotations

import os
import stat
from dataclasses import dataclass
from pathlib import Path
from typing import BinaryIO, Final

__all__ = [
    "BINDINGS",
    "IMAGE",
    "INPUT_SCRIPT",
    "MATERIAL_LIBRARY",
    "MODEL",
    "SCENE",
    "FileKind",
    "UserFileError",
    "check_user_file",
    "open_user_file",
    "read_user_file",
]

MiB: Final = 1 << 20


@dataclass(frozen=True)
class FileKind:
    """What a file is to the loader (its name in messages) and the most bytes it may have."""

    name: str
    limit: int


# The limits are far above any real file of the kind, and low enough that reading one whole
# (which the loaders do) costs at most a fraction of the memory of a small machine.
MODEL: Final = FileKind("model file", 1024 * MiB)  # OBJ, glTF and its buffers, GLB, PLY, STL
MATERIAL_LIBRARY: Final = FileKind("material library", 16 * MiB)  # .mtl text
IMAGE: Final = FileKind("image", 512 * MiB)  # textures and environment maps (an 8k .hdr is ~100 MiB)
SCENE: Final = FileKind("scene file", 64 << 30)  # read member by member, each checked (scene_file.py)
INPUT_SCRIPT: Final = FileKind("input script", 16 * MiB)  # hours of recording; parsed, ~20x its size
BINDINGS: Final = FileKind("bindings file", 1 * MiB)


class UserFileError(OSError):
    """A file that is not opened: not a regular file, or over its kind's size limit."""

    def __init__(self, path: str | os.PathLike[str], why: str, named_by: str | None = None) -> None:
        self.path, self.why, self.named_by = str(path), why, named_by
        by = f" (named by {named_by})" if named_by else ""
        super().__init__(f"{self.path}{by}: {why}")

    def __str__(self) -> str:
        return str(self.args[0])


def _what(mode: int) -> str:
    if stat.S_ISDIR(mode):
        return "a directory"
    if stat.S_ISFIFO(mode):
        return "a FIFO (named pipe)"
    if stat.S_ISCHR(mode):
        return "a character device"
    if stat.S_ISBLK(mode):
        return "a block device"
    if stat.S_ISSOCK(mode):
        return "a socket"
    return "not a regular file"


def _a(name: str) -> str:
    return f"{'an' if name[0] in 'aeiou' else 'a'} {name}"


def _size(n: int) -> str:
    return f"{n / MiB:.1f} MiB" if n >= MiB else f"{n} bytes"


def _refuse(path: str | os.PathLike[str], mode: int, kind: FileKind, named_by: str | None) -> UserFileError:
    target = os.path.realpath(path)
    link = f" (a link to {target})" if target != os.path.abspath(path) else ""
    return UserFileError(path, f"is {_what(mode)}{link}, not a regular file; {_a(kind.name)} must be one", named_by)


def _too_large(path: str | os.PathLike[str], size: int, kind: FileKind, named_by: str | None) -> UserFileError:
    why = f"is {_size(size)}, more than the {_size(kind.limit)} {_a(kind.name)} may have"
    return UserFileError(path, why, named_by)


def open_user_file(path: str | os.PathLike[str], kind: FileKind, named_by: str | None = None) -> BinaryIO:
    """The regular file at `path`, open for reading in binary (OSError: missing, unreadable;
    UserFileError: not a regular file, or larger than `kind.limit`). Read it with a bound:
    `read_user_file` does."""
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0) | getattr(os, "O_BINARY", 0)
    fd = os.open(path, flags | getattr(os, "O_CLOEXEC", 0))
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise _refuse(path, info.st_mode, kind, named_by)
        if info.st_size > kind.limit:
            raise _too_large(path, info.st_size, kind, named_by)
        if hasattr(os, "set_blocking"):
            os.set_blocking(fd, True)
        return os.fdopen(fd, "rb")
    except BaseException:
        os.close(fd)
        raise


def read_user_file(path: str | os.PathLike[str], kind: FileKind, named_by: str | None = None) -> bytes:
    """The whole file, as `open_user_file` checks it; a file that grows past the limit while it
    is read (or that said it was smaller) is refused too."""
    with open_user_file(path, kind, named_by) as file:
        data = file.read(kind.limit + 1)
    if len(data) > kind.limit:
        raise _too_large(path, len(data), kind, named_by)
    return data


def check_user_file(path: str | os.PathLike[str], kind: FileKind, named_by: str | None = None) -> Path:
    """`path` after checking that it opens as `open_user_file` opens it (for a file read later,
    or by a library that opens files itself)."""
    with open_user_file(path, kind, named_by):
        pass
    return Path(path)
