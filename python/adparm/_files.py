"""Writing files so that nothing is ever left half-written, and knowing which files are adparm's.

Every file adparm writes goes first to a temporary file in the same folder (a hidden name ending
in ``.tmp`` and the real suffix, holding the writer's pid), is flushed to disk, then renamed over
its final name with ``os.replace``, which is atomic: a reader, a crash, a full disk or a signal
sees either the old file or the new one, never a truncated one; on any failure the temporary file
is removed, and the error names the final file, not the temporary.

A folder written by the command line holds ``.adparm-outputs.json``, the manifest of the files
adparm wrote there (size and modification time of each), and ``.adparm-lock``, locked
(``fcntl.flock``) by the command writing there: one command at a time per folder. Before a run,
:class:`OutputFolder` takes the lock, removes the temporary files and figure folders that a killed
adparm (a pid no longer running) left, and refuses to overwrite a file that is not in the manifest
or was changed since (a user's file). After the run, before writing the first file, it removes the
files of the earlier run it replaces (all of them, not only those it writes again), so the folder
never mixes two runs' files. Each file is recorded in the manifest before it is renamed into place,
so the manifest always covers the files on disk.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import secrets
import shutil
import tempfile
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import TYPE_CHECKING, Any

try:
    import fcntl
except ImportError:  # pragma: no cover - not POSIX: no folder lock
    fcntl = None  # type: ignore[assignment]

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

__all__ = ["LOCK", "MANIFEST", "OutputError", "OutputFolder", "atomic_write", "write_text"]

MANIFEST = ".adparm-outputs.json"
LOCK = ".adparm-lock"
FIGURE_STAGING = ".adparm-figures-"

# What adparm leaves behind only when it is killed (SIGKILL, power loss): a temporary file
# (.<stem>.<pid>-<8 hex>.tmp<suffix>) or a figure folder (.adparm-figures-<pid>-<random>).
_LEFTOVER = re.compile(r"\..*\.(\d+)-[0-9a-f]{8}\.tmp(\.[^.]*)?|\.adparm-figures-(\d+)-[^/]*")


def _temporary(path: Path) -> Path:
    return path.with_name(f".{path.stem}.{os.getpid()}-{secrets.token_hex(4)}.tmp{path.suffix}")


def _named(error: OSError, path: Path, temporary: Path) -> OSError:
    """``error`` naming ``path`` where it named the temporary file (or nothing)."""
    if error.filename not in (None, str(temporary), temporary):
        return error
    return OSError(error.errno, error.strerror or str(error), str(path))


def atomic_write(
    path: str | Path,
    write: Callable[[Path], Any],
    before_rename: Callable[[Path], Any] | None = None,
) -> Path:
    """Call ``write(temporary)`` to write a file in ``path``'s folder, flush it to disk, call
    ``before_rename(temporary)`` if given, and rename it to ``path`` (atomic); on any failure or
    interrupt, remove the temporary file and leave ``path`` as it was. An OSError names
    ``path``, not the temporary file. Returns ``path``."""
    path = Path(path)
    temporary = _temporary(path)
    try:
        write(temporary)
        with open(temporary, "rb+") as stream:
            os.fsync(stream.fileno())
        if before_rename is not None:
            before_rename(temporary)
        os.replace(temporary, path)
    except BaseException as error:
        with contextlib.suppress(OSError):
            temporary.unlink()
        named = _named(error, path, temporary) if isinstance(error, OSError) else error
        if named is not error:
            raise named from error
        raise
    return path


def write_text(path: str | Path, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    return atomic_write(path, lambda temporary: temporary.write_text(text, encoding="utf-8"))


class OutputError(ValueError):
    """An output path that cannot or must not be written (found before anything runs)."""


def _stamp(path: Path) -> list[int]:
    stat = path.stat()
    return [stat.st_size, stat.st_mtime_ns]


class OutputFolder:
    """A folder a command writes ``names`` into, as the group ``group`` of the manifest.

    ``check()`` (before any computation) creates the folder, proves it writable, takes its lock
    (released by ``close()``, or by leaving ``with folder:``), removes what a killed adparm left
    and refuses files in ``names`` that adparm did not write; ``remove_previous()`` (before the
    first write) removes the files of the earlier run this one replaces; ``write``/
    ``write_figures`` write atomically and record each file in the manifest. ``written`` lists
    the files written so far, ``removed`` those of the earlier run that were removed."""

    def __init__(self, folder: str | Path, names: Iterable[str], group: str, option: str = "--out"):
        self.folder = Path(folder)
        self.names = list(names)
        self.group = group
        self.option = option
        self.written: list[Path] = []
        self.removed: list[Path] = []
        self._manifest: dict[str, dict[str, Any]] = {}
        self._lock: int | None = None

    def __enter__(self) -> OutputFolder:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Release the folder's lock (the lock file stays, for the next command)."""
        if self._lock is not None:
            os.close(self._lock)
            self._lock = None

    # -- before the run -------------------------------------------------------------------------

    def check(self) -> None:
        folder = self.folder
        if folder.exists() and not folder.is_dir():
            raise OutputError(f"{self.option}: {folder} exists and is not a folder")
        try:
            folder.mkdir(parents=True, exist_ok=True)
            with tempfile.NamedTemporaryFile(dir=folder, prefix=".adparm-probe-"):
                pass
        except OSError as error:
            raise OutputError(f"{self.option}: cannot write in {folder}: {error}") from None
        self._take_lock()
        try:
            self._check_files()
        except BaseException:
            self.close()
            raise

    def _take_lock(self) -> None:
        """Lock the folder (fcntl.flock on LOCK, its holder's pid written in it); another
        command holding it is an OutputError naming its pid."""
        if fcntl is None or self._lock is not None:  # not POSIX, or taken already
            return
        path = self.folder / LOCK
        try:
            lock = os.open(path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW, 0o644)
        except OSError as error:
            raise OutputError(
                f"{self.option}: cannot open the lock file {path}: {error.strerror or error}; "
                "move it away"
            ) from None
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            holder = os.read(lock, 32).decode("ascii", "replace").strip() or "unknown"
            os.close(lock)
            raise OutputError(
                f"{self.option}: {self.folder} is being written by another adparm command (pid "
                f"{holder}); wait for it to end or choose another folder"
            ) from None
        with contextlib.suppress(OSError):  # the pid only informs: a full disk keeps the lock
            os.ftruncate(lock, 0)
            os.write(lock, f"{os.getpid()}\n".encode("ascii"))
        self._lock = lock

    def _check_files(self) -> None:
        folder = self.folder
        manifest = folder / MANIFEST
        if manifest.is_symlink() or (manifest.exists() and not manifest.is_file()):
            raise OutputError(
                f"{self.option}: {manifest} exists and is not a regular file; adparm keeps the "
                "list of the files it wrote there: move it away"
            )
        self.remove_leftovers()
        self._manifest = self._read_manifest()
        for name in self.names:
            path = folder / name
            if not (path.exists() or path.is_symlink()):
                continue
            if path.is_symlink() or not path.is_file():
                raise OutputError(
                    f"{self.option}: {path} exists and is not a regular file; adparm does not "
                    "replace it (choose another folder or move it away)"
                )
            if not self._owned(name):
                raise OutputError(
                    f"{self.option}: {path} exists and was not written by adparm (or was changed "
                    "since); adparm does not overwrite it: choose another folder or move the "
                    "file away"
                )

    def remove_leftovers(self) -> list[Path]:
        """Remove the temporary files and figure folders that an adparm process no longer
        running left here (killed while writing); returns them."""
        removed = []
        with os.scandir(self.folder) as entries:
            for entry in entries:
                match = _LEFTOVER.fullmatch(entry.name)
                if match is None or _running(int(match.group(1) or match.group(3))):
                    continue
                if entry.is_dir(follow_symlinks=False):
                    shutil.rmtree(entry.path, ignore_errors=True)
                else:
                    with contextlib.suppress(OSError):
                        os.unlink(entry.path)
                removed.append(Path(entry.path))
        return removed

    def _read_manifest(self) -> dict[str, dict[str, Any]]:
        try:
            data = json.loads((self.folder / MANIFEST).read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return {}
        files = data.get("files") if isinstance(data, dict) else None
        if not isinstance(files, dict):
            return {}
        return {k: v for k, v in files.items() if isinstance(v, dict) and isinstance(k, str)}

    def _owned(self, name: str) -> bool:
        """Whether ``name`` is as adparm wrote it: its stamp is the manifest's (or, while a
        file was being replaced, the one it replaced)."""
        entry = self._manifest.get(name)
        path = self.folder / name
        try:
            return entry is not None and _stamp(path) in (entry.get("stamp"), entry.get("replaces"))
        except OSError:
            return False

    # -- writing --------------------------------------------------------------------------------

    def remove_previous(self, keep: Iterable[str] = ()) -> list[Path]:
        """Before this run's first file: remove the files of the earlier runs it replaces (its
        own group's, and every group of which it overwrites a file), so the folder never holds
        two runs' files; only files unchanged since adparm wrote them, and not those in ``keep``
        (a one-file output, replaced atomically). Returns them."""
        written = {path.name for path in self.written} | set(keep)
        groups = {self.group} | {
            entry.get("group") for name, entry in self._manifest.items() if name in self.names
        }
        removed = []
        for name, entry in list(self._manifest.items()):
            if entry.get("group") not in groups or name in written or Path(name).name != name:
                continue
            path = self.folder / name
            if self._owned(name):
                with contextlib.suppress(OSError):
                    path.unlink()
                    removed.append(path)
            if not (path.exists() or path.is_symlink()):
                del self._manifest[name]
        if removed:
            self.removed += removed
            self._save_manifest()
        return removed

    def write(self, name: str, write: Callable[[Path], Any]) -> Path:
        """Write ``name`` atomically with ``write(temporary_path)``, recorded in the manifest
        before it is renamed into place."""
        path = atomic_write(
            self.folder / name, write, lambda temporary: self._record(name, temporary)
        )
        self.written.append(path)
        return path

    def write_text(self, name: str, text: str) -> Path:
        return self.write(name, lambda temporary: temporary.write_text(text, encoding="utf-8"))

    def write_figures(self, figures: dict[str, Figure], formats: Iterable[str]) -> list[Path]:
        """Each figure as ``<name>.<format>`` (adparm.plotting.save_figures into a temporary
        folder beside, then each file recorded and renamed into place)."""
        formats = list(formats)
        prefix = f"{FIGURE_STAGING}{os.getpid()}-"
        staging = Path(tempfile.mkdtemp(dir=self.folder, prefix=prefix))
        paths: list[Path] = []
        try:
            self._write_figures(figures, formats, staging, paths)
        except OSError as error:
            if error.filename is not None and str(staging) not in str(error.filename):
                raise  # the manifest, named by _record
            names = ", ".join(f"{name}.{fmt}" for name in figures for fmt in formats)
            raise OSError(
                error.errno, error.strerror or str(error), f"{self.folder}/ ({names})"
            ) from error
        finally:
            shutil.rmtree(staging, ignore_errors=True)
        return paths

    def _write_figures(
        self, figures: dict[str, Figure], formats: Iterable[str], staging: Path, paths: list[Path]
    ) -> None:
        for path in save_figures(figures, staging, formats):
            with open(path, "rb+") as stream:
                os.fsync(stream.fileno())
            self._record(path.name, path)
            final = self.folder / path.name
            os.replace(path, final)
            self.written.append(final)
            paths.append(final)

    def _record(self, name: str, temporary: Path) -> None:
        """Record ``name`` with the stamp of ``temporary`` (a rename keeps size and mtime),
        before it is renamed into place; if the manifest cannot be written, the error names it
        (and the file is not renamed into place)."""
        previous = self._manifest.get(name)
        entry: dict[str, Any] = {"group": self.group, "stamp": _stamp(temporary)}
        if self._owned(name):  # replaced: the old file stays adparm's until the rename
            entry["replaces"] = _stamp(self.folder / name)
        self._manifest[name] = entry
        try:
            self._save_manifest()
        except OSError as error:
            if previous is None:
                del self._manifest[name]
            else:
                self._manifest[name] = previous
            raise OSError(
                error.errno,
                error.strerror or str(error),
                f"{self.folder / MANIFEST} (the manifest, recording {name})",
            ) from error

    def _save_manifest(self) -> None:
        text = json.dumps({"written_by": "adparm", "files": self._manifest}, indent=1) + "\n"
        atomic_write(self.folder / MANIFEST, lambda t: t.write_text(text, encoding="utf-8"))

    # -- after the run --------------------------------------------------------------------------

    def describe_written(self) -> str:
        """``folder/ (a, b, c)`` of the files written so far, or a sentence saying none was."""
        if not self.written:
            return f"nothing was written in {self.folder}/"
        names = dict.fromkeys(path.name for path in self.written)  # once each, if rewritten
        return f"{self.folder}/ ({', '.join(names)})"


def _running(pid: int) -> bool:
    """Whether a process ``pid`` exists (this one included)."""
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (OSError, OverflowError):  # another user's process (EPERM), or not a pid
        return pid > 0
    return pid > 0


def save_figures(
    figures: dict[str, Figure], directory: str | Path, formats: Iterable[str] = ("png", "svg")
) -> list[Path]:
    """Write each figure as ``<directory>/<name>.<format>``.

    Parameters
    ----------
    figures : dict of str to Figure
        As :meth:`adparm.SimulationResult.plot` returns.
    directory : str or Path
        Created if missing.
    formats : iterable of str
        Any format matplotlib writes (png, svg, pdf, ...). PNGs at 200 dpi; no creation dates,
        so the same run writes the same files.

    Returns
    -------
    list of Path
        The paths written.
    """
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    written = []
    for name, figure in figures.items():
        for fmt in formats:
            path = directory / f"{name}.{fmt}"
            figure.savefig(path, dpi=200, metadata=_figure_metadata(fmt))
            written.append(path)
    return written


def _figure_metadata(fmt: str) -> dict[str, Any] | None:
    # Leave out creation dates so that the same run writes the same files.
    if fmt == "svg":
        return {"Date": None}
    if fmt == "pdf":
        return {"CreationDate": None}
    return None
