"""File output: safe names, atomic writes, all-or-nothing sets of files.

Every file diefab writes goes through :func:`write_files` (or
:func:`atomic_write` for one file):

* each file is written to a temporary file beside it and renamed over the
  target, so a failure or a kill never leaves a half-written output;
* several files are one transaction: all are written first, then renamed,
  and if anything fails the targets that had already been replaced get
  their previous content back;
* a write that would replace one of the command's own inputs is refused;
* temporary files are named ``.NAME.PID.XXXXXXXX.tmp``; those whose process
  is gone (killed mid-write) are removed the next time anything is written
  to their folder.

Output names come from :func:`safe_name`, so a design's name cannot lead a
file out of the output folder.
"""

from __future__ import annotations

import contextlib
import os
import re
import signal
import tempfile
from collections.abc import Iterable, Mapping
from pathlib import Path

from diefab.core.errors import OutputError
from diefab.core.stopping import STOP_SIGNALS, check_stop


class LockError(OutputError):
    """Another process holds the lock of a run folder or of an output file."""


__all__ = [
    "NAME_MAX",
    "ExclusiveLock",
    "LockError",
    "atomic_write",
    "check_outputs",
    "check_size",
    "ensure_dir",
    "hold_lock",
    "hold_outputs",
    "keep_state",
    "output_path",
    "release_locks",
    "safe_name",
    "write_files",
]

#: Longest file name, in bytes, that common file systems accept.
NAME_MAX = 255
#: Characters replaced in output names: path separators, control characters and
#: what Windows forbids in a file name.
_UNSAFE = re.compile(r'[\x00-\x1f\x7f/\\:*?"<>|]')
#: Bytes of a temporary name beyond the target's (".", ".PID", ".XXXXXXXX", ".tmp").
_TMP_EXTRA = 1 + 8 + 9 + 4


def safe_name(name: str) -> str:
    """`name` as one file-name component: no separators, control characters or leading dots.

    Examples
    --------
    >>> safe_name("../../etc/x"), safe_name("gem: v2"), safe_name(".hidden"), safe_name("..")
    ('_.._etc_x', 'gem_ v2', 'hidden', '_')
    """
    if not isinstance(name, str):
        raise OutputError(f"name {name!r} is not a string")
    text = _UNSAFE.sub("_", name).strip().lstrip(".").rstrip(". ")
    return text or "_"


def output_path(folder: str | Path, name: str, suffix: str) -> Path:
    """``folder / (safe_name(name) + suffix)``, refusing a file name longer than :data:`NAME_MAX` bytes."""
    filename = safe_name(name) + suffix
    size = len(filename.encode("utf-8"))
    if size > NAME_MAX:
        raise OutputError(
            f"output file name {filename[:24]}...{filename[-12:]} is {size} bytes, more than the {NAME_MAX} "
            "a file system accepts: give the design a shorter name"
        )
    return Path(folder) / filename


def check_size(path: str | Path, limit: int, what: str, error: type[Exception] = OutputError) -> None:
    """Raise `error` if the file `path` is larger than `limit` bytes (its apparent size: a sparse file counts whole).

    Inputs go through this before they are read, so that memory stays
    bounded whatever the file; a file that cannot be inspected is left to
    the reader's own error.
    """
    try:
        size = os.stat(path).st_size
    except (OSError, ValueError):
        return
    if size > limit:
        raise error(f"{what} {path} is {size:,} bytes, more than the {limit:,} any die needs")


def ensure_dir(path: str | Path) -> Path:
    """Create folder `path` if needed and check that it is writable."""
    path = Path(path)
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        blocking = next((p for p in (path, *path.parents) if p.exists() and not p.is_dir()), None)
        if blocking is not None:  # mkdir's "File exists" or "Not a directory" would not say which
            raise OutputError(f"cannot create output folder {path}: {blocking} is a file, not a folder") from exc
        raise OutputError(f"cannot create output folder {path}: {exc.strerror or exc}") from exc
    if not path.is_dir():
        raise OutputError(f"output path {path} is not a folder")
    if not os.access(path, os.W_OK | os.X_OK):
        raise OutputError(f"output folder {path} is not writable")
    return path


@contextlib.contextmanager
def signals_deferred():
    """Defer Ctrl-C, SIGTERM and SIGHUP to the end of the block, then deliver them as they would have been.

    Python runs signal handlers in the main thread whichever thread the
    signal arrives in (a BLAS thread may take a ``kill``), so the handlers
    are swapped for ones that only note the signal, rather than the signals
    masked.  Signals that are ignored stay ignored; off the main thread
    nothing changes.
    """
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return
    noted: list[int] = []
    previous = {}
    try:
        # inside the try: a stop received before runs its handler in one of these calls, and the handlers
        # already swapped must be put back
        for signum in STOP_SIGNALS:
            handler = signal.getsignal(signum)
            if handler is not signal.SIG_IGN and handler is not None:  # None: set outside Python, left alone
                previous[signum] = signal.signal(signum, lambda s, frame: noted.append(s))
        yield
    finally:
        stopped = None
        for signum, handler in previous.items():
            while True:  # a stop landing on a handler already put back raises here: finish putting them back
                try:
                    signal.signal(signum, handler)
                    break
                except KeyboardInterrupt as exc:
                    stopped = exc
        for signum in dict.fromkeys(noted):
            signal.raise_signal(signum)
        if stopped is not None:
            raise stopped


class ExclusiveLock:
    """An exclusive advisory lock on ``FOLDER/.NAME.lock`` for the file or folder ``FOLDER/NAME``.

    Taken without waiting: when another process holds it, :meth:`acquire`
    raises :class:`LockError` naming that process's id, which the holder
    writes into the lock file.  The lock is the operating system's (``flock``
    on POSIX, through the `filelock` package elsewhere), so it ends with the
    process however the process ends; a lock file left by a killed process
    is taken over.  :meth:`release` removes the lock file while still
    holding it, and :meth:`acquire` checks that the file it locked is still
    the one at the path, so that no two processes can both hold it.

    Parameters
    ----------
    target : path
        The run folder or output file guarded.
    what : str
        Words for the refusal, e.g. ``"run out/r"``.
    """

    def __init__(self, target: str | Path, what: str) -> None:
        target = Path(os.path.realpath(target))  # two paths to one file, through a link, share one lock
        self.path = target.parent / f".{_short(target)}.lock"
        self.what = what
        self._fd: int | None = None
        self._other = None

    @property
    def held(self) -> bool:
        return self._fd is not None or self._other is not None

    def acquire(self) -> ExclusiveLock:
        if self.held:
            return self
        try:
            import fcntl
        except ImportError:  # no flock: filelock's own (without the holder's id)
            return self._acquire_portable()
        while True:
            try:
                fd = os.open(self.path, os.O_RDWR | os.O_CREAT | getattr(os, "O_CLOEXEC", 0), 0o644)
            except OSError as exc:
                raise OutputError(f"cannot lock {self.what} ({self.path}): {exc.strerror or exc}") from exc
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                holder = _read_pid(fd)
                os.close(fd)
                who = f"process {holder}" if holder else "another process"
                raise LockError(f"{self.what} is in use by {who} (lock {self.path})") from None
            try:
                same = os.path.samestat(os.fstat(fd), os.stat(self.path))
            except OSError:
                same = False
            if not same:  # the holder released (and removed) it between our open and our lock: again
                os.close(fd)
                continue
            try:
                os.ftruncate(fd, 0)
                os.write(fd, f"{os.getpid()}\n".encode())
            except OSError:
                pass  # a full disk: the lock holds, only the holder's id is not recorded
            self._fd = fd
            return self

    def _acquire_portable(self) -> ExclusiveLock:
        import filelock

        lock = filelock.FileLock(str(self.path), timeout=0)
        try:
            lock.acquire()
        except filelock.Timeout:
            raise LockError(f"{self.what} is in use by another process (lock {self.path})") from None
        self._other = lock
        return self

    def release(self) -> None:
        if self._other is not None:
            self._other.release()
            self._other = None
        if self._fd is not None:
            with contextlib.suppress(OSError):
                os.unlink(self.path)
            os.close(self._fd)
            self._fd = None

    def __enter__(self) -> ExclusiveLock:
        try:
            with signals_deferred():  # a stop is delivered once the lock is taken, and then releases it
                return self.acquire()
        except BaseException:
            self.release()
            raise

    def __exit__(self, *exc) -> None:
        with signals_deferred():
            self.release()


#: Output locks this process keeps until :func:`release_locks` (taken by :func:`check_outputs`).
_HELD: dict[Path, ExclusiveLock] = {}


def _output_locks(targets: Iterable[str | Path]) -> list[ExclusiveLock]:
    """Locks of the `targets` this process does not hold yet, in a fixed order (no two writers deadlock)."""
    locks = []
    for target in sorted({os.path.abspath(p) for p in targets}):
        lock = ExclusiveLock(target, f"output {target}")
        if lock.path not in _HELD and os.path.isdir(lock.path.parent):  # a missing folder is made later
            locks.append(lock)
    return locks


# A lock is taken and recorded in _HELD, or released and forgotten, with the stop signals deferred: a stop in
# between would leave a lock file that nothing removes.


def hold_outputs(targets: Iterable[str | Path]) -> None:
    """Lock the output files `targets` until :func:`release_locks`: a second writer of them is refused."""
    with signals_deferred():
        for lock in _output_locks(targets):
            _HELD[lock.path] = lock.acquire()


def hold_lock(target: str | Path, what: str) -> None:
    """Lock `target` (a run folder, say) until :func:`release_locks`; refuse it if another process holds it."""
    lock = ExclusiveLock(target, what)
    with signals_deferred():
        if lock.path not in _HELD:
            _HELD[lock.path] = lock.acquire()


def release_locks() -> None:
    """Release the locks taken by :func:`hold_lock` and :func:`hold_outputs` (and :func:`check_outputs`)."""
    with signals_deferred():
        while _HELD:
            _HELD.popitem()[1].release()


def _read_pid(fd: int) -> int | None:
    try:
        text = os.pread(fd, 32, 0).decode("ascii", "replace").strip()
    except (OSError, AttributeError):
        return None
    return int(text) if text.isdigit() else None


def _release_at_exit() -> None:
    import atexit

    atexit.register(release_locks)


_release_at_exit()


def atomic_write(path: str | Path, data: str | bytes, *, inputs: Iterable[str | Path] = ()) -> Path:
    """Write `data` to `path` through a temporary file in the same folder and a rename."""
    return write_files({path: data}, inputs=inputs)[0]


def keep_state(path: str | Path, data: bytes) -> Path:
    """Write the state a command continues from (a stopped validation's drops) atomically, even once stopped.

    :func:`write_files` writes nothing after a stop signal, so that a stopped
    command leaves no new outputs; the state that lets the command continue
    is what a stop must leave, so it is written all the same (the stop signals
    deferred while it is, and delivered after).
    """
    with signals_deferred():
        return _write_files({path: data}, ())[0]


def write_files(files: Mapping[str | Path, str | bytes], *, inputs: Iterable[str | Path] = ()) -> list[Path]:
    """Write several files as one: either all are replaced or none is.

    Parameters
    ----------
    files : mapping path -> str or bytes
        Targets and their contents (str is written as UTF-8).
    inputs : iterable of path
        Files the command read; replacing one of them is refused.

    Returns
    -------
    list of Path
        The targets, in the order given.

    Raises
    ------
    OutputError
        A target is an input, a folder, or cannot be written; no target has
        changed.

    Ctrl-C, SIGTERM and SIGHUP are deferred while the files are written and
    delivered just after, so that an interrupt leaves the targets all old or
    all new and no temporary file behind.
    """
    check_stop()  # a stop received (and swallowed by someone) before: nothing is written
    with signals_deferred():
        taken = _output_locks(files)
        try:
            for lock in taken:
                _HELD[lock.path] = lock.acquire()
            return _write_files(files, inputs)
        finally:
            for lock in taken:
                if _HELD.get(lock.path) is lock:
                    del _HELD[lock.path]
                lock.release()


def _write_files(files: Mapping[str | Path, str | bytes], inputs: Iterable[str | Path]) -> list[Path]:
    targets = [Path(p) for p in files]
    payloads = [d.encode("utf-8") if isinstance(d, str) else bytes(d) for d in files.values()]
    if len(set(map(os.path.abspath, targets))) != len(targets):
        raise OutputError("two outputs of one command have the same file name")
    check_outputs(targets, inputs)
    for path in targets:
        ensure_dir(path.parent)
    for folder in dict.fromkeys(p.parent for p in targets):
        _remove_stale(folder)
    temps: list[str] = []
    backups: dict[Path, str | None] = {}
    done: list[Path] = []
    current = targets[0] if targets else None
    try:
        for current, payload in zip(targets, payloads):
            temps.append(_write_temp(current, payload))
        for path, tmp in zip(targets, temps):
            current = path
            if path.exists():
                backups[path] = _temp_name(path)
                try:
                    os.link(path, backups[path])
                except OSError:  # a file system without hard links: this one cannot be put back
                    backups[path] = None
            os.replace(tmp, path)
            done.append(path)
    except BaseException as exc:
        for path in reversed(done):  # put back what was there before
            with contextlib.suppress(OSError):
                if path not in backups:
                    path.unlink()
                elif backups[path] is not None:
                    os.replace(backups.pop(path), path)
        for leftover in [*temps, *backups.values()]:
            if leftover is not None:
                Path(leftover).unlink(missing_ok=True)
        if isinstance(exc, OSError) and not isinstance(exc, OutputError):
            raise OutputError(f"cannot write {current}: {exc.strerror or exc}") from exc
        raise
    for backup in backups.values():
        if backup is not None:
            Path(backup).unlink(missing_ok=True)
    for folder in {p.parent for p in targets}:
        _fsync_dir(folder)
    return targets


def check_outputs(targets: Iterable[str | Path], inputs: Iterable[str | Path] = ()) -> None:
    """Refuse outputs that would replace an input or something that is not a regular file.

    Commands call this before their long work, so that a refusal comes
    first, not after minutes of computing; :func:`write_files` checks again.
    The targets are locked (:func:`hold_outputs`) until :func:`release_locks`,
    so that two processes cannot write the same set of files.
    """
    targets = [Path(p) for p in targets]
    sources = [Path(p) for p in inputs if p is not None]
    hold_outputs(targets)
    for path in targets:
        if path.is_dir() or (path.exists() and not path.is_file()):
            raise OutputError(f"cannot write {path}: it exists and is not a regular file")
        for source in sources:
            same = path.resolve() == source.resolve()
            if not same and path.exists() and source.exists():
                with contextlib.suppress(OSError):
                    same = os.path.samefile(path, source)
            if same:
                raise OutputError(f"refusing to write {path}: it would replace {source}, an input of this command")


def _short(path: Path) -> str:
    """The target's name cut to leave room for the temporary name's extras."""
    raw = path.name.encode("utf-8")[: NAME_MAX - _TMP_EXTRA]
    return raw.decode("utf-8", errors="ignore")


def _temp_name(path: Path) -> str:
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{_short(path)}.{os.getpid()}.", suffix=".tmp")
    os.close(fd)
    os.unlink(tmp)
    return tmp


def _write_temp(path: Path, payload: bytes) -> str:
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{_short(path)}.{os.getpid()}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(payload)
            fh.flush()
            os.fsync(fh.fileno())
        os.chmod(tmp, 0o644)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return tmp


#: A temporary file of :func:`write_files`: ``.NAME.PID.XXXXXXXX.tmp``.
_TEMP = re.compile(r"\..+\.(\d+)\.[a-z0-9_]{8}\.tmp", re.DOTALL)


def _remove_stale(folder: Path) -> None:
    """Remove the temporary files in `folder` left by writers that no longer run (killed mid-write)."""
    try:
        names = os.listdir(folder)
    except OSError:
        return
    for name in names:
        m = _TEMP.fullmatch(name)
        if m and not _alive(int(m[1])):
            with contextlib.suppress(OSError):
                (folder / name).unlink()


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError):
        return True  # someone else's process, or not a pid we can ask about: leave its files alone
    return True


def _fsync_dir(folder: Path) -> None:
    """Make the renames durable (best effort: not every system can open a folder)."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)
