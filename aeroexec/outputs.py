"""Writing an output file that is never presented whole unless it is whole.

    with whole_file_or_none("fixed.mcap") as temp:
        write(temp)                  # any exception, or a signal, removes `temp`
    # here fixed.mcap is complete (renamed into place)

Commands whose output is only useful complete (`recover`, `import`, `view -o`) write
to a hidden temporary name beside the target and rename it into place at the end. On a
failure (a full disk, a damaged input) or a signal (`Interrupted`), the temporary file is
removed, the target is left as it was, and an `Interrupted` is told so for its one line.
The temporary file is created like any other file (mode 0666 less the umask).

`aeroexec run -o` and `replay -o` do not use this: a recording is useful up to
its last flush, so they write in place and keep what they can (see `Recorder`).
"""

from __future__ import annotations

import contextlib
import os
import shutil
import stat
import tempfile
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from aeroexec.errors import AeroexecError, Mark, RecordingError
from aeroexec.interrupts import Interrupted

#: What a command says when it removed its unfinished output.
NOT_WRITTEN = "the partial output was removed"


def partial_name(target: Path) -> Path:
    return target.with_name(f".{target.name}.partial")


@contextmanager
def whole_file_or_none(
    target: str | os.PathLike[str], error: type[AeroexecError] = RecordingError
) -> Iterator[Path]:
    """A temporary path beside `target`, renamed onto `target` when the block ends
    normally, removed when it does not. `OSError`s of the block (and of the rename)
    become `error` "cannot write: ...; the partial output was removed"."""
    final = Path(target)
    _check_replaceable(final, error)
    temp = partial_name(final)
    try:
        yield temp
        os.replace(temp, final)
    except Interrupted as stop:
        _remove(temp)
        stop.notes.append(f"{NOT_WRITTEN}, {final} not written")
        raise
    except OSError as exc:
        reason = f"cannot write: {exc.strerror or exc}"
        if _remove(temp):
            reason += f"; {NOT_WRITTEN}"
        raise error(reason, Mark(str(final))) from None
    except BaseException:
        _remove(temp)
        raise


class Pipe:
    """A FIFO for a writer that must never see a write error, copied into a file.

    Rerun's file sink deadlocks (in `save`, `flush` or `disconnect`, by chance) when a
    write fails under it. Given this FIFO instead, it always writes successfully: a thread
    copies what arrives into the real file with Python's own I/O, keeps draining after
    a write error (a full disk), and `finish()` raises that `OSError` once the writer has
    closed its end."""

    def __init__(self, target: Path) -> None:
        self._folder = tempfile.mkdtemp(prefix="aeroexec-pipe-")
        self.path = Path(self._folder) / target.name
        os.mkfifo(self.path)
        self._target = target
        self._error: OSError | None = None
        self._opened = threading.Event()
        self._thread = threading.Thread(target=self._pump, name="aeroexec-pipe", daemon=True)
        self._thread.start()

    def _pump(self) -> None:
        with open(self.path, "rb") as source:
            self._opened.set()
            try:
                sink = open(self._target, "wb")  # noqa: SIM115 (closed below)
            except OSError as exc:
                self._error, sink = exc, None
            while block := source.read(1 << 16):
                if sink is None:
                    continue  # keep draining: the writer must not block or fail
                try:
                    sink.write(block)
                except OSError as exc:
                    self._error = exc
                    with contextlib.suppress(OSError):
                        sink.close()
                    sink = None
            if sink is not None:
                try:
                    sink.close()
                except OSError as exc:
                    self._error = exc

    def finish(self) -> None:
        """Wait for the copy to end (the writer closed the FIFO); raise its write error."""
        if not self._opened.is_set():
            # The writer never opened the FIFO: open and close it so the thread returns.
            with contextlib.suppress(OSError):
                os.close(os.open(self.path, os.O_WRONLY | os.O_NONBLOCK))
        self._thread.join()
        shutil.rmtree(self._folder, ignore_errors=True)
        if self._error is not None:
            raise self._error


def _check_replaceable(final: Path, error: type[AeroexecError]) -> None:
    """Renaming onto a device or a FIFO would replace it (as root, `/dev/full` itself)."""
    try:
        mode = os.stat(final).st_mode
    except OSError:
        return  # nothing there yet (or unreachable: the write will say)
    if stat.S_ISDIR(mode):
        raise error("is a directory", Mark(str(final)))
    if not stat.S_ISREG(mode):
        raise error(
            "is not a regular file: this output is only ever written whole, to a file",
            Mark(str(final)),
        )


def _remove(path: Path) -> bool:
    """Remove `path`; whether there was one."""
    try:
        path.unlink()
    except FileNotFoundError:
        return False
    except OSError:
        pass
    return True
