"""The frame layout of the upload protocol, shared by the host and the controller.

Every message in both directions is one frame::

    offset  size  field
    0       1     SOH, the start byte 0x01
    1       1     kind, an ASCII letter (see FrameKind)
    2       2     seq, big-endian: a frame number, or a count of frames
    4       1     len, the payload length, 0..80
    5       len   payload
    5+len   2     CRC-16/CCITT-FALSE of bytes 1..4+len (kind, seq, len, payload), big-endian

Seven bytes of overhead per frame; a payload of at most 80 bytes, the length of
a RAPID string, so that a frame fits the receiver's 80-element buffers. Frame
numbers are absolute (0..65534), which bounds a file to 65 535 frames
(5 242 800 bytes) and makes a duplicate recognisable by its number alone.

Payloads of the frames that carry more than a number:

- HELLO (host): version (1), flags (1, bit 0 = load after rename), file size
  (4, big-endian), file CRC (2), file name (ASCII, 1..40 characters).
- READY (controller): its protocol version (1), status (1, see ReadyStatus);
  seq is the frame to resume from.
- END (host): seq = number of data frames; file size (4) and file CRC (2).
- DONE (controller): seq = number of frames; status (1, see DoneStatus).

:class:`FrameReader` decodes a byte stream exactly as the RAPID receiver reads
it: hunt for SOH, read the header, give up on a length above 80, read payload
and CRC, and drop the frame if the CRC differs. Bytes of a dropped frame are
consumed, not rescanned, as the receiver cannot push bytes back.
"""

from __future__ import annotations

import re
import struct
from dataclasses import dataclass
from enum import IntEnum

from rapidfix.link.checksum import crc16

SOH = 0x01
PROTOCOL_VERSION = 1
MAX_PAYLOAD = 80
HEADER_SIZE = 5
OVERHEAD = HEADER_SIZE + 2
MAX_FRAMES = 0xFFFF
MAX_FILE_SIZE = MAX_FRAMES * MAX_PAYLOAD
FLAG_LOAD = 0x01
NAME_PATTERN = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.\-]{0,39}$")
BUSY_EVERY = 4096  # the controller sends BUSY after verifying this many bytes


class FrameKind(IntEnum):
    """Frame kinds; the value is the ASCII code sent in the kind byte."""

    HELLO = ord("H")  # host: start or resume a transfer
    DATA = ord("D")  # host: one chunk of the file
    END = ord("E")  # host: all chunks sent, verify and rename
    READY = ord("R")  # controller: answer to HELLO, with the frame to resume from
    ACK = ord("K")  # controller: every frame before seq is written
    NAK = ord("N")  # controller: a gap, send again from seq
    BUSY = ord("B")  # controller: still verifying, keep waiting
    DONE = ord("F")  # controller: transfer finished, with a status


class ReadyStatus(IntEnum):
    """Status byte of READY."""

    ACCEPTED = 0
    VERSION_REFUSED = 1
    CANNOT_CREATE = 2


class DoneStatus(IntEnum):
    """Status byte of DONE."""

    OK = 0
    CHECK_FAILED = 1  # size or whole-file CRC differs; the temporary file is removed
    FILE_ERROR = 2  # the file could not be written or renamed
    LOAD_FAILED = 3  # the file is in place but Load refused it
    NO_TRANSFER = 4  # END without a transfer in progress


@dataclass(frozen=True)
class Frame:
    """One decoded frame."""

    kind: int
    seq: int
    payload: bytes = b""


def encode_frame(kind: int, seq: int, payload: bytes = b"") -> bytes:
    """The bytes of one frame on the wire."""
    if not 0 <= seq <= MAX_FRAMES:
        raise ValueError(f"frame number {seq} outside 0..{MAX_FRAMES}")
    if len(payload) > MAX_PAYLOAD:
        raise ValueError(f"payload of {len(payload)} bytes exceeds {MAX_PAYLOAD}")
    body = struct.pack(">BHB", kind, seq, len(payload)) + payload
    return bytes((SOH,)) + body + struct.pack(">H", crc16(body))


class FrameReader:
    """Incremental decoder: feed bytes as they arrive, get complete valid frames."""

    def __init__(self) -> None:
        self._buf = bytearray()
        self.bad_frames = 0

    @property
    def in_frame(self) -> bool:
        """True while part of a frame has been read (the inter-byte time-out runs)."""
        return bool(self._buf)

    def abandon(self) -> None:
        """Drop a partial frame, as the receiver does when a byte does not come in time."""
        if self._buf:
            self.bad_frames += 1
        self._buf.clear()

    def feed(self, data: bytes) -> list[Frame]:
        """Consume `data`; return the frames it completed, in order."""
        buf = self._buf
        buf += data
        frames: list[Frame] = []
        while buf:
            if buf[0] != SOH:
                start = buf.find(SOH)
                if start < 0:
                    buf.clear()
                    break
                del buf[:start]
            if len(buf) < HEADER_SIZE:
                break
            length = buf[4]
            if length > MAX_PAYLOAD:
                self.bad_frames += 1
                del buf[:HEADER_SIZE]
                continue
            end = HEADER_SIZE + length + 2
            if len(buf) < end:
                break
            body = bytes(buf[1 : HEADER_SIZE + length])
            (received,) = struct.unpack(">H", buf[end - 2 : end])
            del buf[:end]
            if crc16(body) != received:
                self.bad_frames += 1
                continue
            kind, seq, _ = struct.unpack(">BHB", body[:4])
            frames.append(Frame(kind, seq, body[4:]))
        return frames


@dataclass(frozen=True)
class Hello:
    """What the host announces: which file, how big, its CRC, and whether to load it."""

    name: str
    size: int
    crc: int
    load: bool = False
    version: int = PROTOCOL_VERSION

    def encode(self) -> bytes:
        """HELLO payload bytes."""
        flags = FLAG_LOAD if self.load else 0
        return struct.pack(">BBIH", self.version, flags, self.size, self.crc) + self.name.encode(
            "ascii"
        )

    @classmethod
    def decode(cls, payload: bytes) -> Hello | None:
        """Parse a HELLO payload; None if it is too short or its name is not ASCII."""
        if len(payload) < 9:
            return None
        version, flags, size, crc = struct.unpack(">BBIH", payload[:8])
        try:
            name = payload[8:].decode("ascii")
        except UnicodeDecodeError:
            return None
        return cls(name=name, size=size, crc=crc, load=bool(flags & FLAG_LOAD), version=version)


def encode_end(size: int, crc: int) -> bytes:
    """END payload: file size and whole-file CRC."""
    return struct.pack(">IH", size, crc)


def decode_end(payload: bytes) -> tuple[int, int] | None:
    """(size, crc) of an END payload, or None if malformed."""
    if len(payload) != 6:
        return None
    size, crc = struct.unpack(">IH", payload)
    return size, crc


def frame_count(size: int) -> int:
    """Number of DATA frames for a file of `size` bytes."""
    return -(-size // MAX_PAYLOAD)
