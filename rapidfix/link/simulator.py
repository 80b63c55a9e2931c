"""A simulated controller running the receiver behind a real pseudo-terminal.

:class:`SimulatedController` opens a pty pair (``os.openpty``); the host opens
the slave side (``.port``, e.g. ``/dev/pts/7``) with pyserial like any serial
port, and a thread serves the master side: it decodes frames with
:class:`~rapidfix.link.protocol.FrameReader` (abandoning a partial frame after the
inter-byte time-out, as RfxRecv.mod does), hands them to
:class:`~rapidfix.link.receiver.ControllerReceiver` and writes the replies back.

With ``paced=True`` the thread takes bytes in no faster than the line rate,
10 bit times per byte (8N1): a byte every ``10 / baud`` seconds. Replies are
not paced (they are a few bytes on the other wire of a full-duplex line).
Optional :class:`~rapidfix.link.faults.LinkFaults` spoil the line.
"""

from __future__ import annotations

import contextlib
import os
import select
import threading
import time
from collections.abc import Callable
from pathlib import Path
from types import TracebackType

from rapidfix.exceptions import LinkError
from rapidfix.link.faults import FaultInjector, LinkFaults
from rapidfix.link.protocol import PROTOCOL_VERSION, FrameReader
from rapidfix.link.receiver import ControllerReceiver

BITS_PER_BYTE = 10  # start bit, 8 data bits, stop bit
READ_CHUNK = 64  # bytes taken from the pty at once; small so that pacing stays smooth


def check_loadable(path: Path) -> None:
    """The simulated Load: refuse a module the project's RAPID grammar rejects."""
    from rapidfix.rapid import parse_program  # the link layer needs the parser only here

    parse_program(path.read_bytes(), str(path))


class SimulatedController:
    """RfxRecv on a simulated controller whose disk is `folder`; use as a context manager."""

    def __init__(
        self,
        folder: str | Path,
        baud: int = 115200,
        paced: bool = False,
        faults: LinkFaults | None = None,
        byte_timeout: float = 0.5,
        loader: Callable[[Path], None] | None = check_loadable,
        version: int = PROTOCOL_VERSION,
    ) -> None:
        self.receiver = ControllerReceiver(folder, loader=loader, version=version)
        self.byte_time = BITS_PER_BYTE / baud
        self.paced = paced
        self.injector = FaultInjector(faults) if faults is not None else None
        self.byte_timeout = byte_timeout
        self.bytes_received = 0
        self.port = ""
        self._master = -1
        self._slave = -1
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._rx_clock = 0.0
        self.error: BaseException | None = None

    @property
    def folder(self) -> Path:
        """The simulated controller's disk."""
        return self.receiver.folder

    def start(self) -> SimulatedController:
        """Open the pty pair and start serving; `.port` is then the device to open."""
        try:
            import tty  # POSIX only, like pseudo-terminals themselves

            self._master, self._slave = os.openpty()
        except (ImportError, AttributeError, OSError) as err:
            raise LinkError(
                f"cannot simulate a controller here: no pseudo-terminal ({err})",
                hint="--simulate needs Linux or macOS",
            ) from None
        tty.setraw(self._slave)
        os.set_blocking(self._master, False)
        self.port = os.ttyname(self._slave)
        self._thread = threading.Thread(target=self._serve, name="rfx-controller", daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        """Stop serving and close the pty pair (an open temporary file stays on disk)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
            self._thread = None
        for fd in (self._master, self._slave):
            if fd >= 0:
                os.close(fd)
        self._master = self._slave = -1
        self.receiver.close()

    def __enter__(self) -> SimulatedController:
        return self.start()

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.stop()

    # -- the serving thread -----------------------------------------------------

    def _serve(self) -> None:
        reader = FrameReader()
        last_byte = time.monotonic()
        try:
            while not self._stop.is_set():
                ready_at_once = bool(select.select([self._master], [], [], 0)[0])
                if not ready_at_once:
                    wait = self.byte_timeout if reader.in_frame else 0.05
                    if not select.select([self._master], [], [], wait)[0]:
                        if reader.in_frame and time.monotonic() - last_byte >= self.byte_timeout:
                            reader.abandon()
                        continue
                try:
                    data = os.read(self._master, READ_CHUNK)
                except (BlockingIOError, InterruptedError):
                    continue
                except OSError:  # the host side went away for good
                    self._stop.wait(0.05)
                    continue
                self._pace(len(data), ready_at_once)
                self.bytes_received += len(data)
                last_byte = time.monotonic()
                pieces = self.injector.from_host(data) if self.injector else [(0.0, data)]
                for stall, piece in pieces:
                    if stall and self._stop.wait(stall):
                        return
                    for frame in reader.feed(piece):
                        for reply in self.receiver.handle(frame):
                            self._send(reply)
        except BaseException as err:  # surfaced to tests through .error
            self.error = err
            raise

    def _pace(self, nbytes: int, continuing: bool) -> None:
        """Hold the bytes until the line could have carried them."""
        if not self.paced:
            return
        now = time.monotonic()
        start = self._rx_clock if continuing and self._rx_clock > now - 0.01 else now
        self._rx_clock = max(start, self._rx_clock) + nbytes * self.byte_time
        delay = self._rx_clock - time.monotonic()
        if delay > 0:
            time.sleep(delay)

    def _send(self, frame: bytes) -> None:
        pieces = self.injector.to_host(frame) if self.injector else [(0.0, frame)]
        for stall, piece in pieces:
            if stall:
                self._stop.wait(stall)
            with contextlib.suppress(BlockingIOError, OSError):  # nobody listening: bytes lost
                os.write(self._master, piece)
