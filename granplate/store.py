"""One run store for every cache: content-addressed entries under the cache directory.

The directory is ``$GRANPLATE_CACHE``, else ``~/.cache/granplate``. An entry is found by
one identity rule, `key(kind, payload, fmt)`: the SHA-256 of the canonical JSON of

    {"kind": kind, "format": fmt, "granplate_version": version, "payload": payload}

so another payload, another per-kind format version or another granplate version is
another entry. Entries live at ``DIR/KIND/[LABEL-]KEY.EXT`` (LABEL: an optional readable
tag, such as a preset name), carry their key inside (an npz array, a JSON field, a netCDF
attribute) and are compared with it when read. Writes are atomic (a temporary file in the
same folder, then os.replace); a read returns None, never raises, for a missing,
truncated, corrupt or mismatched entry, and a failed save only warns (the caller just
computes again next time). `exclusive` makes processes that would compute the same entry
at the same time (the workers of a sweep) take turns, so it is computed once. Reading an
entry marks it used; beyond
``$GRANPLATE_CACHE_MAX_BYTES`` (default 2 GiB) the least recently used entries are
removed after each save.
"""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
import warnings
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Callable, Iterator

#: Environment variable naming the cache directory.
CACHE_ENV = "GRANPLATE_CACHE"
#: Environment variable: the store's size cap in bytes (least recently used entries go first).
MAX_BYTES_ENV = "GRANPLATE_CACHE_MAX_BYTES"
#: Size cap when MAX_BYTES_ENV is not set [bytes].
DEFAULT_MAX_BYTES = 2 * 1024**3
#: Name under which an entry stores its own key (npz array, JSON field, netCDF attribute).
KEY_FIELD = "granplate_store_key"
#: Suffix of the temporary files of an atomic write (never an entry).
TMP_SUFFIX = ".tmp"
#: Suffix of the lock files of `exclusive` (never an entry).
LOCK_SUFFIX = ".lock"


# --------------------------------------------------------------------------------------
# Identity
# --------------------------------------------------------------------------------------
def cache_directory() -> Path:
    """$GRANPLATE_CACHE, else ~/.cache/granplate."""
    env = os.environ.get(CACHE_ENV)
    return Path(env) if env else Path.home() / ".cache" / "granplate"


def canonical_json(obj: Any) -> str:
    """JSON with sorted keys and no spaces (floats exact via repr; other objects via repr)."""
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), default=repr)


def key(kind: str, payload: Any, fmt: int, version: str | None = None) -> str:
    """SHA-256 (hex) of the canonical JSON of kind, format, granplate version and payload.

    version: the granplate version the entry belongs to (None: this one).
    """
    if version is None:
        from granplate.version import __version__ as version
    doc = {"kind": kind, "format": int(fmt), "granplate_version": version, "payload": payload}
    return hashlib.sha256(canonical_json(doc).encode()).hexdigest()


def entry_path(kind: str, entry_key: str, suffix: str, label: str = "") -> Path:
    """DIR/KIND/[LABEL-]KEY.SUFFIX of an entry."""
    return cache_directory() / kind / f"{label + '-' if label else ''}{entry_key}{suffix}"


# --------------------------------------------------------------------------------------
# Writing and reading files
# --------------------------------------------------------------------------------------
def atomic_write(path: str | Path, write: Callable[[Path], Any]) -> Path:
    """Call write(tmp) on a temporary file beside path, then rename it to path.

    Readers see the old file or the complete new one, never a partial file; when write
    raises, the temporary file is removed and the exception propagates.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, name = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=TMP_SUFFIX)
    os.close(fd)
    tmp = Path(name)
    try:
        write(tmp)
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()
    return path


@contextmanager
def exclusive(kind: str, payload: Any, fmt: int) -> Iterator[None]:
    """Hold the entry key(kind, payload, fmt) for this process: another process asking for
    the same entry waits until this one leaves (so that it finds the entry stored instead
    of computing it again). A lock on DIR/KIND/.KEY.lock, released by the system when the
    process dies; where locking is not available (no fcntl, an unwritable folder) it
    does not wait."""
    path = cache_directory() / kind / f".{key(kind, payload, fmt)}{LOCK_SUFFIX}"
    try:
        import fcntl

        path.parent.mkdir(parents=True, exist_ok=True)
        fh = open(path, "a")
    except (ImportError, OSError):
        yield
        return
    try:
        try:
            fcntl.flock(fh.fileno(), fcntl.LOCK_EX)
        except OSError:
            pass
        yield
    finally:
        fh.close()  # releases the lock


def _save(kind: str, entry_key: str, suffix: str, label: str, write: Callable[[Path], Any]) -> Path | None:
    """Atomically write an entry, then enforce the size cap; an OSError only warns."""
    path = entry_path(kind, entry_key, suffix, label)
    try:
        atomic_write(path, write)
    except OSError as exc:
        warnings.warn(f"granplate: could not write the {kind} cache entry {path}: {exc}", stacklevel=3)
        return None
    prune()
    return path


#: An entry read again within this many seconds of its last mark is not marked again [s].
TOUCH_INTERVAL_S = 600.0


def _touch(path: Path) -> None:
    """Mark an entry as used now (its modification time orders the size cap's removals),
    unless it was marked in the last TOUCH_INTERVAL_S: then the file is left as it is, so
    that the copies other processes keep in memory (`load_arrays`, which a changed file
    voids) stay valid while they read the same entry."""
    import time

    try:
        if time.time() - path.stat().st_mtime > TOUCH_INTERVAL_S:
            os.utime(path)
    except OSError:
        pass


def save_arrays(kind: str, payload: Any, fmt: int, arrays: dict[str, Any], label: str = "") -> Path | None:
    """Store named numpy arrays (.npz) under key(kind, payload, fmt); the path, or None on failure."""
    import numpy as np

    k = key(kind, payload, fmt)

    def write(tmp: Path) -> None:
        with open(tmp, "wb") as fh:
            np.savez(fh, **{KEY_FIELD: np.array(k)}, **arrays)

    return _save(kind, k, ".npz", label, write)


#: The entry `load_arrays` read last in this process: path -> (file signature, arrays).
_LAST_ARRAYS: dict[Path, tuple[tuple, dict]] = {}


def _signature(path: Path) -> tuple | None:
    """What identifies a file's content here: device, inode, size, modification time."""
    try:
        st = path.stat()
    except OSError:
        return None
    return (st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns)


def load_arrays(kind: str, payload: Any, fmt: int, label: str = "") -> dict[str, Any] | None:
    """The arrays stored under key(kind, payload, fmt), or None (missing, unreadable, other key).

    The entry read last is kept in memory while its file is unchanged (the designs of a
    study that share a plate read it once per process): callers must not modify the arrays."""
    import numpy as np

    k = key(kind, payload, fmt)
    path = entry_path(kind, k, ".npz", label)
    last = _LAST_ARRAYS.get(path)
    if last is not None and last[0] == _signature(path):
        return dict(last[1])
    try:
        with np.load(path, allow_pickle=False) as data:
            if str(data[KEY_FIELD]) != k:
                return None
            arrays = {name: np.array(data[name]) for name in data.files if name != KEY_FIELD}
    except Exception:  # noqa: BLE001 - any unreadable entry just means "compute again"
        return None
    _touch(path)
    sig = _signature(path)
    _LAST_ARRAYS.clear()
    if sig is not None:
        _LAST_ARRAYS[path] = (sig, arrays)
    return dict(arrays)


def save_json(kind: str, payload: Any, fmt: int, doc: Any, label: str = "") -> Path | None:
    """Store a JSON document under key(kind, payload, fmt); the path, or None on failure."""
    k = key(kind, payload, fmt)
    text = json.dumps({KEY_FIELD: k, "doc": doc}, indent=1, sort_keys=True) + "\n"
    return _save(kind, k, ".json", label, lambda tmp: tmp.write_text(text))


def load_json(kind: str, payload: Any, fmt: int, label: str = "") -> Any | None:
    """The JSON document stored under key(kind, payload, fmt), or None."""
    k = key(kind, payload, fmt)
    path = entry_path(kind, k, ".json", label)
    try:
        entry = json.loads(path.read_text())
        if not isinstance(entry, dict) or entry.get(KEY_FIELD) != k or "doc" not in entry:
            return None
    except Exception:  # noqa: BLE001
        return None
    _touch(path)
    return entry["doc"]


def save_netcdf(kind: str, payload: Any, fmt: int, ds: Any, label: str = "") -> Path | None:
    """Store an xarray Dataset (.nc, the key as attribute KEY_FIELD); the path, or None on failure."""
    k = key(kind, payload, fmt)
    stored = ds.copy(deep=False)
    stored.attrs = {**ds.attrs, KEY_FIELD: k}
    return _save(kind, k, ".nc", label, lambda tmp: stored.to_netcdf(tmp))


def load_netcdf(kind: str, payload: Any, fmt: int, label: str = "") -> Any | None:
    """The Dataset stored under key(kind, payload, fmt), loaded into memory (without the key
    attribute), or None."""
    import xarray as xr

    k = key(kind, payload, fmt)
    path = entry_path(kind, k, ".nc", label)
    try:
        with xr.open_dataset(path) as opened:
            if opened.attrs.get(KEY_FIELD) != k:
                return None
            ds = opened.load()
    except Exception:  # noqa: BLE001
        return None
    ds.attrs.pop(KEY_FIELD, None)
    _touch(path)
    return ds


# --------------------------------------------------------------------------------------
# Housekeeping
# --------------------------------------------------------------------------------------
def _entries(kind: str | None = None) -> list[tuple[str, Path]]:
    """(kind, path) of every entry (temporary files of writes in progress excluded)."""
    root = cache_directory()
    kinds = (
        [root / kind]
        if kind is not None
        else (sorted(p for p in root.iterdir() if p.is_dir()) if root.is_dir() else [])
    )
    out = []
    for folder in kinds:
        if folder.is_dir():
            out += [
                (folder.name, p)
                for p in sorted(folder.iterdir())
                if p.is_file() and not p.name.endswith((TMP_SUFFIX, LOCK_SUFFIX))
            ]
    return out


def info() -> dict[str, dict[str, int]]:
    """{kind: {"entries": count, "bytes": total size}} of the store."""
    out: dict[str, dict[str, int]] = {}
    for kind, path in _entries():
        try:
            size = path.stat().st_size
        except OSError:
            continue
        row = out.setdefault(kind, {"entries": 0, "bytes": 0})
        row["entries"] += 1
        row["bytes"] += size
    return out


def clear(kind: str | None = None) -> int:
    """Remove every entry (of one kind when given); the number removed."""
    n = 0
    for _, path in _entries(kind):
        try:
            path.unlink()
            n += 1
        except OSError:
            pass
    return n


def max_bytes() -> int:
    """The size cap [bytes]: $GRANPLATE_CACHE_MAX_BYTES, else DEFAULT_MAX_BYTES."""
    env = os.environ.get(MAX_BYTES_ENV)
    if not env:
        return DEFAULT_MAX_BYTES
    try:
        return int(float(env))
    except ValueError:
        warnings.warn(
            f"granplate: {MAX_BYTES_ENV}={env!r} is not a number of bytes; using {DEFAULT_MAX_BYTES}", stacklevel=2
        )
        return DEFAULT_MAX_BYTES


def prune(limit: int | None = None) -> int:
    """Remove the least recently used entries until the store holds at most limit bytes
    (None: max_bytes()); the number removed."""
    limit = max_bytes() if limit is None else limit
    sized = []
    for _, path in _entries():
        try:
            st = path.stat()
        except OSError:
            continue
        sized.append((st.st_mtime_ns, path.name, path, st.st_size))
    total = sum(s[3] for s in sized)
    n = 0
    for _, _, path, size in sorted(sized):
        if total <= limit:
            break
        try:
            path.unlink()
        except OSError:
            continue
        total -= size
        n += 1
    return n
