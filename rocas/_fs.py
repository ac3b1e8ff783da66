"""Atomic file output: write to a temporary sibling, rename into place on success.

An interrupted command never leaves a half-written file under the final name. A destination
that cannot be written (a directory, a read-only or missing place, a full disk) raises
:class:`~rocas.errors.OutputError`; :func:`check_writable` finds that out before a long job.
"""

from __future__ import annotations

import contextlib
import errno
import os
import re
import tempfile
from collections.abc import Iterator
from pathlib import Path

from rocas.errors import OutputError, UsageError

_FULL = {errno.ENOSPC, getattr(errno, "EDQUOT", errno.ENOSPC)}
#: a write that failed for the place, not for rocas: full, over a size limit, read-only
_WRITE_FAILED = _FULL | {errno.EFBIG, errno.EROFS}


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; on clean exit, rename it onto ``path``.

    On any exception (including KeyboardInterrupt) the temporary file is removed and
    ``path`` is left as it was.

    Raises:
        OutputError: ``path`` is a directory, its folder cannot be made or written, or the
            disk fills up while writing.
    """
    final = Path(path)
    tmp_path = _temporary_beside(final)
    try:
        yield tmp_path
        try:
            os.replace(tmp_path, final)
        except OSError as exc:
            raise _output_error(final, exc) from exc
    except BaseException as exc:
        with contextlib.suppress(OSError):
            tmp_path.unlink()
        if isinstance(exc, OSError) and exc.errno in _WRITE_FAILED:
            raise _output_error(final, exc) from exc
        raise


def check_writable(path: str | os.PathLike[str]) -> None:
    """Fail now, not after a long job, if a file the user named cannot be written atomically.

    The folder must exist (a mistyped ``-o /nonexistent/dir/out`` is refused, not created);
    creates (and removes) the temporary sibling the real write will use.

    Raises:
        OutputError: the folder does not exist, or as :func:`atomic_path`.
    """
    check_parent_exists(path)
    _temporary_beside(Path(path)).unlink()


def check_parent_exists(path: str | os.PathLike[str]) -> None:
    """Refuse an output (file or directory) the user named whose folder does not exist.

    Raises:
        OutputError: the folder of ``path`` is missing or is not a directory.
    """
    parent = Path(path).parent
    if not parent.is_dir():
        what = "is not a directory" if parent.exists() else "does not exist"
        raise OutputError(f"cannot write {path}: the folder {parent} {what}",
                          f"create it first (mkdir -p {parent}) or choose another place")


def refuse_overwriting(source: str | os.PathLike[str], output: str | os.PathLike[str]) -> None:
    """Refuse an output that is the input file itself (by any path or link).

    Raises:
        UsageError: ``output`` names the same file as ``source``.
    """
    src, dst = Path(source), Path(output)
    if src.exists() and dst.exists() and os.path.samefile(src, dst):
        raise UsageError(f"the output {dst} is the input recording {src}",
                         "write the output to another file; the input would be lost")


def is_temporary(path: str | os.PathLike[str]) -> bool:
    """Whether ``path`` is named like the temporary sibling :func:`atomic_path` writes
    (``.NAME.XXXXXXXX.part``): debris of a process killed while writing, never a finished file."""
    name = Path(path).name
    return name.startswith(".") and name.endswith(".part") and len(name) > len("..part")


def _temporary_beside(final: Path) -> Path:
    if final.is_dir():
        raise OutputError(f"cannot write {final}: it is a directory",
                          "give a file name, e.g. " + str(final / "out"))
    try:
        final.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{final.name}.", suffix=".part", dir=final.parent)
    except OSError as exc:
        raise _output_error(final, exc) from exc
    os.close(fd)
    tmp_path = Path(tmp)
    os.chmod(tmp_path, 0o666 & ~_umask())  # mkstemp makes 0600; give the usual mode
    return tmp_path


def _output_error(final: Path, exc: OSError) -> OutputError:
    reason = exc.strerror or type(exc).__name__
    return OutputError(f"cannot write {final}: {reason}",
                       "free some space" if exc.errno in _FULL else "choose a writable place")


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def write_text_atomic(path: str | os.PathLike[str], text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")


#: what a path component made from data may hold: letters, digits, ``.``, ``_``, ``-``
_UNSAFE_IN_NAME = re.compile(r"[^A-Za-z0-9._-]+")
#: the longest path component made from data [characters] (file systems allow 255 bytes)
MAX_NAME_CHARS = 120


def safe_component(name: str, fallback: str = "unnamed") -> str:
    """``name`` (from a scenario, a recording, a campaign) as one harmless path component.

    Every run of characters other than letters, digits, ``.``, ``_`` and ``-`` becomes ``_``
    (so no separator, no drive, nothing a shell or a terminal acts on), as does every run of
    dots (no ``..``); leading dots are dropped (no hidden file) and the length is capped;
    what is left empty becomes ``fallback``. A name that is already safe is returned unchanged.
    """
    s = re.sub(r"_{2,}", "_", re.sub(r"\.{2,}", "_", _UNSAFE_IN_NAME.sub("_", str(name))))
    s = s.lstrip("._")[:MAX_NAME_CHARS].rstrip("_")
    return s or fallback


def is_safe_component(name: object) -> bool:
    """True when ``name`` is a string that :func:`safe_component` leaves as it is."""
    return isinstance(name, str) and bool(name) and safe_component(name, fallback="") == name


def inside(base: str | os.PathLike[str], *parts: str) -> Path:
    """``base / parts...``, checked to resolve inside ``base`` (links followed).

    Raises:
        InputError: the path leaves ``base`` (an absolute part, ``..``, a link out).
    """
    from rocas.errors import InputError

    root = Path(base).resolve()
    target = root.joinpath(*parts).resolve()
    if target != root and root not in target.parents:
        raise InputError(f"{Path(base).joinpath(*parts)} leads outside {base}",
                         "the name comes from a file someone else wrote; it is refused")
    return target
