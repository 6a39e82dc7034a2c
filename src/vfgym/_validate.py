"""Input checks shared by every public entry point.

Each check raises ``ValueError`` naming the parameter, the value given and the allowed
range, so a bad setting is caught where it is made, not deep inside a simulation.
"""

from __future__ import annotations

import contextlib
import errno
import math
import os
import re
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np

NAME_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,99}$")
"""A name that becomes a folder or file name: no separators, no leading dot."""


def _what(name: str, value: Any) -> str:
    return f"{name}={value!r}" if name else repr(value)


def _interval(lo: float | None, hi: float | None, lo_open: bool, hi_open: bool) -> str:
    left = "(" if (lo_open or lo is None) else "["
    right = ")" if (hi_open or hi is None) else "]"
    lo_s = "-inf" if lo is None else f"{lo:g}"
    hi_s = "inf" if hi is None else f"{hi:g}"
    return f"{left}{lo_s}, {hi_s}{right}"


def check_real(
    name: str,
    value: Any,
    lo: float | None = None,
    hi: float | None = None,
    *,
    lo_open: bool = False,
    hi_open: bool = False,
    text: bool = False,
) -> float:
    """Return ``value`` as a finite float inside the interval, else raise ``ValueError``.

    A bool is not a number, nor is a string unless ``text`` (the command line's text,
    read as a number: ``1e3``); every config file and dataclass is held to this. An empty
    ``name`` leaves the name out of the message (argparse adds the option's)."""
    # the messages are formatted only when one is raised: the envs check ~40 numbers a move
    if isinstance(value, bool) or (not text and isinstance(value, (str, bytes))):
        raise ValueError(
            f"{_what(name, value)} must be a real number in "
            f"{_interval(lo, hi, lo_open, hi_open)}{_not_text(value)}"
        )
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ValueError(
            f"{_what(name, value)} must be a real number in {_interval(lo, hi, lo_open, hi_open)}"
        ) from None
    bad = (
        not math.isfinite(x)
        or (lo is not None and (x <= lo if lo_open else x < lo))
        or (hi is not None and (x >= hi if hi_open else x > hi))
    )
    if bad:
        raise ValueError(
            f"{_what(name, value)} is out of range: allowed {_interval(lo, hi, lo_open, hi_open)}"
        )
    return x


def _whole_numbers(lo: int | None, hi: int | None) -> str:
    return f"whole numbers in {_interval(lo, hi, False, False)}"


def _not_text(value: Any) -> str:
    return ", not a string" if isinstance(value, (str, bytes)) else ""


def check_int(
    name: str, value: Any, lo: int | None = None, hi: int | None = None, *, text: bool = False
) -> int:
    """Return ``value`` as an int inside ``[lo, hi]``; a float must be whole. A bool is not
    a number, nor is a string unless ``text`` (as :func:`check_real`)."""
    if isinstance(value, bool) or (not text and isinstance(value, (str, bytes))):
        raise ValueError(
            f"{_what(name, value)} must be one of the {_whole_numbers(lo, hi)}{_not_text(value)}"
        )
    if isinstance(value, (int, np.integer)):
        n = int(value)
    else:
        try:
            x = float(value)
        except (TypeError, ValueError):
            raise ValueError(
                f"{_what(name, value)} must be one of the {_whole_numbers(lo, hi)}"
            ) from None
        if not math.isfinite(x) or x != round(x):
            raise ValueError(f"{_what(name, value)} is not allowed: {_whole_numbers(lo, hi)}")
        n = round(x)
    if (lo is not None and n < lo) or (hi is not None and n > hi):
        raise ValueError(f"{_what(name, value)} is out of range: allowed {_whole_numbers(lo, hi)}")
    return n


def set_checked(obj: object, name: str, value: Any) -> None:
    """Store a checked (normalised) value on a frozen dataclass in its ``__post_init__``."""
    object.__setattr__(obj, name, value)


def check_bool(name: str, value: Any) -> bool:
    """Return ``value`` if it is a bool (``True`` / ``False``; no 0, 1 or strings)."""
    if not isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{name}={value!r} must be true or false")
    return bool(value)


def number_from_text(text: Any) -> Any:
    """A command-line value read as a number where it is one (``'70'``: 70, ``'1e3'``:
    1000.0, ``'nan'``: nan), else as it is, so the check that follows names it.

    Parameters
    ----------
    text
        The option's text (anything else is returned as it is).

    Returns
    -------
    Any
        An int, a float, or ``text``.
    """
    if not isinstance(text, str):
        return text
    for kind in (int, float):
        try:
            return kind(text.strip())
        except ValueError:
            pass
    return text


def check_choice(name: str, value: Any, choices: Iterable[str]) -> str:
    """Return ``value`` if it is one of ``choices``."""
    options = tuple(choices)
    if value not in options:
        raise ValueError(f"{name}={value!r} is not allowed: choose one of {', '.join(options)}")
    return value


def check_finite_array(name: str, values: Any, dtype: Any = np.float64) -> np.ndarray:
    """Return a 1-D contiguous array of finite values (no NaN, no inf)."""
    arr = np.ascontiguousarray(np.asarray(values, dtype=dtype))
    if arr.ndim != 1:
        raise ValueError(f"{name} must be a 1-D array of per-tick values, got shape {arr.shape}")
    if arr.size == 0:
        raise ValueError(f"{name} must hold at least one tick, got an empty array")
    if np.issubdtype(arr.dtype, np.floating) and not np.all(np.isfinite(arr)):
        i = int(np.flatnonzero(~np.isfinite(arr))[0])
        raise ValueError(
            f"{name}[{i}]={arr[i]!r} is out of range: allowed finite values (no NaN or inf)"
        )
    return arr


def check_name(option: str, name: Any) -> str:
    """A name that becomes a folder or file name (a study, a run): letters, digits, '.',
    '_' and '-', so that it cannot leave the folder it is made in (no ``/``, no ``..``).

    Parameters
    ----------
    option
        The option or key the name came from, for the message (``--name``, ``study``).
    name
        The name given.

    Returns
    -------
    str
        ``name``, if allowed.

    Raises
    ------
    ValueError
        If the name is not a string of those characters (starting with a letter or digit,
        at most 100), naming the option and what is allowed.
    """
    if not isinstance(name, str) or not NAME_RE.match(name):
        raise ValueError(
            f"{option}={name!r} is not allowed: letters, digits, '.', '_' and '-' "
            "(starting with a letter or digit, at most 100)"
        )
    return name


def check_output_path(
    option: str,
    path: str | os.PathLike,
    *,
    folder: bool = False,
    shown: Any = None,
    root: str | os.PathLike | None = None,
) -> Path:
    """Return ``path`` if vfgym can write it: a file in an existing folder (or, with
    ``folder``, a folder made under ``root``, whose own folder exists), in a folder this
    process may write into.

    Refused with a ``ValueError`` naming ``option`` and ``shown`` (the value given, if the
    path is made from it; default ``path``): an empty path, a folder where a file is wanted
    (or the reverse), a file where a folder must be made, a missing folder (a typo must not
    make folders), a folder without write permission or on a read-only file system.
    Nothing is created.

    Parameters
    ----------
    option
        The option the path came from, for the message (``--out``, ``runs_dir``).
    path
        The file or folder to be written.
    folder
        True if ``path`` is a folder to be made (or reused), False for a file.
    shown
        The value to quote in the message, when ``path`` was made from it.
    root
        With ``folder``: the folder the user named (``--runs-dir``), under which ``path``
        is made; it may be missing, the folder it is in may not.

    Returns
    -------
    Path
        ``path``, if it can be written; else ``ValueError``.
    """
    text = os.fspath(path)
    want = "folder" if folder else "file"
    head = f"{option}={str(text if shown is None else shown)!r} is not allowed"
    if not str(text).strip():
        raise ValueError(f"{head}: give a {want}")
    p = Path(text)
    if p.is_dir() and not folder:
        raise ValueError(f"{head}: {p} is a folder; give a file name")
    if p.exists() and not p.is_dir() and folder:
        raise ValueError(f"{head}: {p} is a file; give a folder")
    anc = p if (folder and p.is_dir()) else p.parent
    while not anc.exists() and not anc.is_symlink() and anc != anc.parent:
        anc = anc.parent
    if not anc.is_dir():
        raise ValueError(f"{head}: {anc} is a file, so no {want} can be made in it")
    must = p.parent if not folder else (None if root is None else Path(root).parent)
    if must is not None and not must.is_dir():
        raise ValueError(f"{head}: folder {must} does not exist; create it first")
    if not os.access(anc, os.W_OK | os.X_OK):
        read_only = False
        with contextlib.suppress(OSError):
            read_only = bool(os.statvfs(anc).f_flag & os.ST_RDONLY)
        why = (
            "is on a read-only file system" if read_only else "is not writable (permission denied)"
        )
        raise ValueError(f"{head}: folder {anc} {why}; give a {want} in a folder you can write")
    return p


def describe_os_error(exc: OSError) -> str:
    """One line for a failed file operation: the path(s) and what went wrong, in words.

    Parameters
    ----------
    exc
        The error (its ``errno``, ``filename`` and ``filename2``).

    Returns
    -------
    str
        ``PATH: reason`` (``reason`` alone if no path is known).
    """
    reasons = {
        errno.ENOENT: "no such file or folder",
        errno.ENOTDIR: "a part of the path is a file, not a folder",
        errno.EEXIST: "a file is in the way where a folder is needed",
        errno.EISDIR: "is a folder, not a file",
        errno.EACCES: "permission denied",
        errno.EPERM: "operation not permitted",
        errno.EROFS: "read-only file system",
        errno.ENOSPC: "no space left on the device",
        errno.EDQUOT: "disk quota exceeded",
        errno.ENAMETOOLONG: "file name too long",
    }
    reason = reasons.get(exc.errno or -1) or exc.strerror or type(exc).__name__
    paths = [str(f) for f in (exc.filename, exc.filename2) if f is not None]
    return f"{' -> '.join(paths)}: {reason}" if paths else reason
