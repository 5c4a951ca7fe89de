"""Read an untrusted marker file in a child process with a memory and a time limit.

A C3D reader is native code: a hostile or damaged file can crash it (SIGSEGV) or make it
allocate gigabytes. So an upload is read in a child forked from a ``forkserver`` (started
once, with numpy and the readers imported; never a fork of the threaded server), whose
address space is capped with ``RLIMIT_AS``; the parent waits at most ``seconds``. The
bytes go in; the recording comes back as ``.npz`` bytes read without pickle, so nothing
the child sends can run code in the parent. A crash, an overrun or a timeout becomes an
``InputError`` saying what happened.
"""

from __future__ import annotations

import io
import json
import multiprocessing
import resource
import signal
import tempfile
from dataclasses import dataclass
from multiprocessing.connection import Connection
from pathlib import Path

import numpy as np

from service.errors import InputError
from service.io.formats.c3d import read_c3d
from service.io.formats.csv import read_csv
from service.io.formats.trc import read_trc
from service.io.recording import Recording

_CONTEXT = multiprocessing.get_context("forkserver")
_CONTEXT.set_forkserver_preload([__name__])


def _read_csv(path: Path, max_markers: int | None = None, max_frames: int | None = None) -> Recording:
    """markerflow's own table: text parsed whole (no native code), then held to the same counts."""
    table = read_csv(path)
    for count, what, limit in ((len(table.names), "markers", max_markers), (table.n_frames, "frames", max_frames)):
        if limit is not None and count > limit:
            raise InputError(f"{path}: {count} {what} exceeds the limit of {limit} (limits.max_{what})")
    return table


_READERS = {".c3d": read_c3d, ".trc": read_trc, ".csv": _read_csv}
_RECORDING, _ERROR, _MEMORY = b"R", b"E", b"M"  # the first byte of the child's one message


@dataclass(frozen=True)
class ReaderBounds:
    """What one read may take: address space beyond the interpreter's own, and wall time."""

    memory_bytes: int
    seconds: float
    max_markers: int | None = None
    max_frames: int | None = None


def read_isolated(data: bytes, suffix: str, bounds: ReaderBounds) -> Recording:
    """The recording in ``data`` (a ``.c3d``, ``.trc`` or markerflow ``.csv`` file's bytes), read in a bounded child.

    Raises:
        InputError: The file is malformed or over a limit, or the reader crashed, ran out of
            memory or time; the message does not name any temporary path.
    """
    receive, send = _CONTEXT.Pipe(duplex=False)
    child = _CONTEXT.Process(target=_child, args=(data, suffix, bounds, send), daemon=True)
    child.start()
    send.close()  # the child's end: EOF here once the child is gone
    try:
        if not receive.poll(bounds.seconds):
            raise InputError(f"reading took longer than the limit of {bounds.seconds:g} s (limits.reader_seconds)")
        reply = receive.recv_bytes()
    except EOFError:
        reply = b""
    finally:
        if child.is_alive():
            child.kill()
        child.join()
        receive.close()
    return _answer(reply, child.exitcode, bounds)


def _answer(reply: bytes, exitcode: int | None, bounds: ReaderBounds) -> Recording:
    tag, body = reply[:1], reply[1:]
    if tag == _RECORDING:
        return recording_from_bytes(body)
    if tag == _ERROR:
        raise InputError(body.decode(errors="replace"))
    if tag == _MEMORY:
        raise InputError(f"reading needs more than the limit of {bounds.memory_bytes // 2**20} MiB of memory "
                         "(limits.reader_memory_bytes)")
    if exitcode is not None and exitcode < 0:
        raise InputError(f"the reader crashed ({signal.Signals(-exitcode).name}) on this file")
    raise InputError(f"the reader stopped (exit status {exitcode}) without an answer")


def _child(data: bytes, suffix: str, bounds: ReaderBounds, send: Connection) -> None:
    """In the child: cap the address space, read, send one tagged message."""
    pages = int(Path("/proc/self/statm").read_text().split()[0])
    cap = pages * resource.getpagesize() + bounds.memory_bytes
    resource.setrlimit(resource.RLIMIT_AS, (cap, cap))
    try:
        send.send_bytes(_RECORDING + recording_to_bytes(_read(data, suffix, bounds)))
    except InputError as error:
        send.send_bytes(_ERROR + str(error).encode())
    except MemoryError:
        send.send_bytes(_MEMORY)


def _read(data: bytes, suffix: str, bounds: ReaderBounds) -> Recording:
    """The readers take a path: a temp file, whose name is cut from their messages."""
    with tempfile.TemporaryDirectory(prefix="markerflow-upload-") as folder:
        path = Path(folder) / f"upload{suffix}"
        path.write_bytes(data)
        try:
            return _READERS[suffix](path, bounds.max_markers, bounds.max_frames)
        except InputError as error:
            raise InputError(str(error).replace(f"{path}: ", "").replace(str(path), "the file")) from None
        except MemoryError:
            raise
        except Exception as error:  # the reader's own bug, on this file: say so, in one line
            raise InputError(f"the reader failed on this file ({type(error).__name__})") from None


def recording_to_bytes(recording: Recording) -> bytes:
    """Pickle-free ``.npz`` bytes of a recording (names and rate in a JSON header)."""
    buffer = io.BytesIO()
    header = json.dumps({"names": list(recording.names), "rate": float(recording.rate)})
    np.savez(buffer, header=np.array(header), positions=np.asarray(recording.positions, dtype=float))
    return buffer.getvalue()


def recording_from_bytes(data: bytes) -> Recording:
    with np.load(io.BytesIO(data), allow_pickle=False) as stored:
        header = json.loads(str(stored["header"]))
        return Recording([str(name) for name in header["names"]], stored["positions"], float(header["rate"]))
