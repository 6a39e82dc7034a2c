"""Run folders: one folder per run with its config, command line and results.

As in rl-baselines3-zoo: ``runs/<kind>/<name>/`` holds ``config.yaml`` (the resolved
configuration), ``command.txt`` (the command line that made it) and whatever the run
writes. Files are written atomically (temporary file, then rename), so an interrupted run
never leaves a half-written result behind.
"""

from __future__ import annotations

import errno
import os
import re
import shlex
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import yaml


def new_run_dir(root: str | Path, kind: str, name: str | None = None) -> Path:
    """Create (or reuse, when ``name`` is given) ``root/kind/name``."""
    base = Path(root) / kind
    if name is None:
        name = time.strftime("%Y%m%d-%H%M%S")
        candidate = base / name
        i = 1
        while candidate.exists():
            candidate = base / f"{name}-{i}"
            i += 1
        name = candidate.name
    path = base / name
    path.mkdir(parents=True, exist_ok=True)
    return path


def write_atomically(path: str | Path, write: Callable[[Path], Any], suffix: str = ".tmp") -> Path:
    """Write ``path`` through a temporary file beside it, then rename it into place, so
    an interrupted write leaves no half-written file.

    Parameters
    ----------
    path : str or Path
        The file to write (its folder is made if missing).
    write : callable
        Writes the content to the temporary path it is given.
    suffix : str
        The temporary file's ending (a writer may choose its format by it: ``.png``).

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    OSError
        Naming ``path`` (never the temporary file), if the file cannot be written.
    """
    path = Path(path)
    tmp: str | None = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=suffix)
        os.close(fd)
        write(Path(tmp))
        os.chmod(tmp, 0o666 & ~_UMASK)  # mkstemp makes 0600; give the usual file mode
        os.replace(tmp, path)
    except OSError as exc:
        _discard(tmp)
        code = exc.errno
        if code == errno.ENOENT and path.parent.is_dir():  # a folder that takes no new file
            code = errno.EPERM  # (/proc, /sys): "no such file" would mislead
        raise OSError(code, os.strerror(code) if code else str(exc), str(path)) from None
    except BaseException:
        _discard(tmp)
        raise
    return path


def _discard(tmp: str | None) -> None:
    if tmp is not None and os.path.exists(tmp):
        os.unlink(tmp)


def write_text(path: str | Path, text: str) -> Path:
    """Write ``text`` atomically (:func:`write_atomically`)."""
    return write_atomically(path, lambda tmp: tmp.write_text(text, encoding="utf-8"))


def write_yaml(path: str | Path, data: Any) -> Path:
    """Write ``data`` as YAML atomically (keys in the given order)."""
    return write_text(path, yaml.safe_dump(_plain(data), sort_keys=False))


class YamlLoader(yaml.SafeLoader):
    """PyYAML's safe loader that also reads ``1e3``, ``1E-5`` and ``+2e4`` as numbers.

    YAML 1.1 (PyYAML) takes a float only with a dot (``1.0e3``), so ``n_timesteps: 1e3``
    would arrive as the string ``'1e3'``; YAML 1.2 and every other reader take it as a
    number, and so does vfgym."""


YamlLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9][0-9_]*)(?:\.[0-9_]*)?[eE][-+]?[0-9]+$"),
    list("-+0123456789"),
)


def parse_yaml(text: str, source: str = "<text>") -> Any:
    """YAML text as Python data (numbers in any notation); bad YAML raises ``ValueError``
    naming ``source`` and the line.

    Parameters
    ----------
    text
        The YAML document.
    source
        Names the text in messages (a file, ``--hyperparams 'k=v'``).

    Returns
    -------
    Any
        The data (``None`` for an empty document).
    """
    try:
        return yaml.load(text, Loader=YamlLoader)  # YamlLoader is a SafeLoader
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        problem = getattr(exc, "problem", None) or exc.__class__.__name__
        if isinstance(exc, yaml.reader.ReaderError):  # a control character: binary data
            ch = exc.character if isinstance(exc.character, int) else ord(exc.character)
            problem = f"character 0x{ch:02x} at offset {exc.position} is not text"
        raise ValueError(f"{source}: not valid YAML ({problem}{where})") from None


def read_yaml(path: str | Path) -> Any:
    """Read a YAML file; a missing, unreadable, binary or malformed file raises
    ``ValueError`` naming it."""
    p = Path(path)
    if p.is_dir():
        raise ValueError(f"{p}: is a folder; give a YAML file")
    if not p.is_file():
        raise ValueError(
            f"{p}: not a regular file; give a YAML file" if p.exists() else f"{p}: no such file"
        )
    try:
        raw = p.read_bytes()
    except OSError as exc:
        raise ValueError(f"{p}: cannot be read ({exc.strerror or exc})") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ValueError(
            f"{p}: not a text file (byte 0x{raw[exc.start]:02x} at offset {exc.start} is not "
            "UTF-8); give a YAML text file"
        ) from None
    return parse_yaml(text, str(p))


_UMASK = os.umask(0o022)
os.umask(_UMASK)
_COMMAND_LINE: list[str] | None = None


def set_command_line(args: list[str] | None) -> None:
    """The arguments of the running ``vfgym`` command (set by :func:`vfgym.cli.main`, so a
    command called as ``main([...])`` records those, not the caller's ``sys.argv``)."""
    global _COMMAND_LINE
    _COMMAND_LINE = None if args is None else list(args)


def command_args() -> list[str] | None:
    """The arguments of the running ``vfgym`` command (after ``vfgym``), or None when no
    command runs through :func:`vfgym.cli.main`."""
    return None if _COMMAND_LINE is None else list(_COMMAND_LINE)


def record_command(run_dir: str | Path, argv: list[str] | None = None) -> None:
    """Write the command line that made this run to ``command.txt``."""
    if argv is None:
        argv = ["vfgym", *_COMMAND_LINE] if _COMMAND_LINE is not None else sys.argv
    cmd = " ".join(shlex.quote(a) for a in ["vfgym", *argv[1:]]) if argv else "vfgym"
    write_text(Path(run_dir) / "command.txt", cmd + "\n")


def _plain(x: Any) -> Any:
    """Numpy scalars and tuples as plain YAML types."""
    if isinstance(x, dict):
        return {str(k): _plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_plain(v) for v in x]
    if hasattr(x, "item") and callable(x.item):
        return x.item()
    if isinstance(x, Path):
        return str(x)
    return x
