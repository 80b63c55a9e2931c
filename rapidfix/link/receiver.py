"""The controller side of the protocol in Python: the state machine of RfxRecv.mod.

:class:`ControllerReceiver` takes decoded frames and returns the reply frames,
handling files in a folder exactly as the RAPID receiver handles them on the
controller's disk. It knows nothing of ports; :mod:`rapidfix.link.simulator`
puts it behind a pseudo-terminal.

State machine (the same names and transitions as in RfxRecv.mod)::

    IDLE ──HELLO──▶ RECEIVING ──END, verified──▶ FINISHED
      ▲  (new file: open NAME.rfxpart)  │  (rename to NAME, load)   │
      │                                 │ HELLO, same file:          │ HELLO:
      │                                 │ READY(resume at expected)  │ new transfer
      └──────── END, check failed: remove NAME.rfxpart ◀─────────────┘

- HELLO: another version -> READY(VERSION_REFUSED), nothing changes. The same
  file (name, size, CRC, flags) while RECEIVING -> READY(expected): resume.
  Otherwise drop any unfinished temporary file, create NAME.rfxpart, expected = 0
  (READY(CANNOT_CREATE) if NAME holds '/', '\\' or ':' or cannot be created).
- DATA n while RECEIVING: n = expected -> append, expected += 1, ACK(expected);
  n < expected (a duplicate) -> ACK(expected), nothing written; n > expected (a
  gap) -> NAK(expected), once until expected moves.
- END n: n ≠ expected -> NAK(expected). Otherwise close the temporary file, read
  it back (BUSY every 4096 bytes), compare size and CRC with HELLO and END; on a
  match remove an old NAME, rename NAME.rfxpart to NAME and load it if asked;
  on a mismatch remove NAME.rfxpart. Reply DONE(status) and go to FINISHED, where
  a repeated END gets the same DONE again.

The real name only ever appears by renaming a verified file.
"""

from __future__ import annotations

from collections.abc import Callable
from enum import IntEnum
from pathlib import Path
from typing import BinaryIO

from rapidfix.link.checksum import crc16
from rapidfix.link.protocol import (
    BUSY_EVERY,
    PROTOCOL_VERSION,
    DoneStatus,
    Frame,
    FrameKind,
    Hello,
    ReadyStatus,
    decode_end,
    encode_frame,
)

TEMP_SUFFIX = ".rfxpart"
FORBIDDEN_IN_NAME = "/\\:"  # a name is a file in the receiver's folder, never a path


class ReceiverState(IntEnum):
    """States of the receiver; RfxRecv.mod uses the same numbers."""

    IDLE = 0
    RECEIVING = 1
    FINISHED = 2


def temp_name(name: str) -> str:
    """The temporary name a file is received under."""
    return name + TEMP_SUFFIX


class ControllerReceiver:
    """The receiver's state machine writing into `folder`.

    `loader(path)` plays RAPID's Load: it raises any exception to refuse the file.
    `version` is the protocol version this receiver speaks (tests change it).
    """

    def __init__(
        self,
        folder: str | Path,
        loader: Callable[[Path], None] | None = None,
        version: int = PROTOCOL_VERSION,
    ) -> None:
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        self.loader = loader
        self.version = version
        self.state = ReceiverState.IDLE
        self.expected = 0
        self.nak_sent = False
        self.identity: Hello | None = None
        self.done_status = DoneStatus.NO_TRANSFER
        self.loaded: list[str] = []
        self._temp: BinaryIO | None = None

    # -- dispatch -------------------------------------------------------------

    def handle(self, frame: Frame) -> list[bytes]:
        """Act on one valid frame; return the encoded replies in sending order."""
        if frame.kind == FrameKind.HELLO:
            return self._on_hello(frame)
        if frame.kind == FrameKind.DATA:
            return self._on_data(frame)
        if frame.kind == FrameKind.END:
            return self._on_end(frame)
        return []

    def close(self) -> None:
        """Close an open temporary file (the receiver stopping); it stays on disk."""
        if self._temp is not None:
            self._temp.close()
            self._temp = None

    # -- frames ---------------------------------------------------------------

    def _ready(self, status: ReadyStatus) -> list[bytes]:
        return [encode_frame(FrameKind.READY, self.expected, bytes((self.version, status)))]

    def _on_hello(self, frame: Frame) -> list[bytes]:
        hello = Hello.decode(frame.payload)
        if hello is None:
            return []
        if hello.version != self.version:
            return [
                encode_frame(FrameKind.READY, 0, bytes((self.version, ReadyStatus.VERSION_REFUSED)))
            ]
        self.nak_sent = False
        if self.state == ReceiverState.RECEIVING and hello == self.identity:
            return self._ready(ReadyStatus.ACCEPTED)
        self._drop_temp()
        self.state = ReceiverState.IDLE
        self.expected = 0
        if any(sep in hello.name for sep in FORBIDDEN_IN_NAME):
            return self._ready(ReadyStatus.CANNOT_CREATE)
        try:
            self._temp = open(self.folder / temp_name(hello.name), "wb")
        except (OSError, ValueError):
            return self._ready(ReadyStatus.CANNOT_CREATE)
        self.identity = hello
        self.state = ReceiverState.RECEIVING
        return self._ready(ReadyStatus.ACCEPTED)

    def _on_data(self, frame: Frame) -> list[bytes]:
        if self.state != ReceiverState.RECEIVING or self._temp is None:
            return []
        if frame.seq == self.expected:
            self._temp.write(frame.payload)
            self.expected += 1
            self.nak_sent = False
            return [encode_frame(FrameKind.ACK, self.expected)]
        if frame.seq < self.expected:
            return [encode_frame(FrameKind.ACK, self.expected)]
        if not self.nak_sent:
            self.nak_sent = True
            return [encode_frame(FrameKind.NAK, self.expected)]
        return []

    def _on_end(self, frame: Frame) -> list[bytes]:
        if self.state == ReceiverState.FINISHED and frame.seq == self.expected:
            return [self._done()]
        if self.state != ReceiverState.RECEIVING or self._temp is None:
            self.done_status = DoneStatus.NO_TRANSFER
            return [self._done()]
        if frame.seq != self.expected:
            return [encode_frame(FrameKind.NAK, self.expected)]
        assert self.identity is not None
        announced = decode_end(frame.payload)
        self._temp.close()
        self._temp = None
        replies, size, crc = self._read_back()
        temp = self.folder / temp_name(self.identity.name)
        real = self.folder / self.identity.name
        wanted = (self.identity.size, self.identity.crc)
        if announced != wanted or (size, crc) != wanted:
            temp.unlink(missing_ok=True)
            self.done_status = DoneStatus.CHECK_FAILED
        else:
            self.done_status = self._put_in_place(temp, real)
        self.state = ReceiverState.FINISHED
        replies.append(self._done())
        return replies

    # -- files ----------------------------------------------------------------

    def _done(self) -> bytes:
        return encode_frame(FrameKind.DONE, self.expected, bytes((self.done_status,)))

    def _read_back(self) -> tuple[list[bytes], int, int]:
        """Size and CRC of the temporary file as read from disk, with the BUSY frames."""
        assert self.identity is not None
        busy: list[bytes] = []
        crc = 0xFFFF
        size = 0
        with open(self.folder / temp_name(self.identity.name), "rb") as handle:
            while block := handle.read(BUSY_EVERY):
                crc = crc16(block, crc)
                size += len(block)
                if len(block) == BUSY_EVERY:
                    busy.append(encode_frame(FrameKind.BUSY, 0))
        return busy, size, crc

    def _put_in_place(self, temp: Path, real: Path) -> DoneStatus:
        try:
            real.unlink(missing_ok=True)
            temp.rename(real)
        except OSError:
            return DoneStatus.FILE_ERROR
        if self.identity is not None and self.identity.load:
            try:
                if self.loader is not None:
                    self.loader(real)
            except Exception:
                return DoneStatus.LOAD_FAILED
            self.loaded.append(real.name)
        return DoneStatus.OK

    def _drop_temp(self) -> None:
        """Close and remove the temporary file of an unfinished transfer."""
        if self._temp is not None:
            self._temp.close()
            self._temp = None
            if self.identity is not None:
                (self.folder / temp_name(self.identity.name)).unlink(missing_ok=True)
