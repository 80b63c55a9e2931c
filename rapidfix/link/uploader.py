"""The host side: send a file to the controller's receiver through pyserial.

The host runs go-back-N with a sliding window, so the line never idles while
acknowledgements travel back:

1. HELLO (name, size, CRC, load flag) until READY arrives or the retries run
   out ("no answer"); READY carries the receiver's protocol version (checked)
   and the frame to resume from (0 for a new transfer).
2. DATA frames from there, at most `window` unacknowledged. ACK n (cumulative)
   slides the window; NAK n sends again from n; no progress for `timeout`
   seconds (plus the time a full window takes on the line) sends again from
   the oldest unacknowledged frame. `retries`
   time-outs in a row end the upload with a LinkError; the receiver keeps what
   it has, and running the same upload again resumes there.
3. END with the whole-file size and CRC until DONE arrives (BUSY, sent while
   the controller reads the file back, restarts the wait). DONE's status says
   whether the file was verified, renamed into place and loaded.
"""

from __future__ import annotations

import errno
import os
import time
from dataclasses import dataclass
from pathlib import Path

import serial
from tqdm import tqdm

from rapidfix.exceptions import LinkError
from rapidfix.link.checksum import crc16
from rapidfix.link.protocol import (
    MAX_FILE_SIZE,
    MAX_PAYLOAD,
    NAME_PATTERN,
    OVERHEAD,
    PROTOCOL_VERSION,
    DoneStatus,
    Frame,
    FrameKind,
    FrameReader,
    Hello,
    ReadyStatus,
    encode_end,
    encode_frame,
    frame_count,
)

POLL_S = 0.02  # longest single wait on the port; deadlines are checked between waits
BACKOFF_LIMIT = 4  # HELLO and END wait at most this many times their first wait


@dataclass(frozen=True)
class LinkSettings:
    """Time-outs and window of the host; the defaults suit a real controller."""

    timeout: float = 1.0  # seconds without progress before sending again
    retries: int = 8  # time-outs in a row before giving up
    window: int = 8  # frames in flight (8 × 87 bytes: fits a small UART buffer)


@dataclass(frozen=True)
class UploadPlan:
    """What an upload sends, computed without a port (``--dry-run``)."""

    name: str
    size: int
    crc: int
    frames: int
    load: bool

    @property
    def hello(self) -> Hello:
        """The HELLO announcing this file."""
        return Hello(name=self.name, size=self.size, crc=self.crc, load=self.load)

    @property
    def wire_bytes(self) -> int:
        """Bytes on the line without errors: HELLO, every DATA frame, END."""
        return (
            (OVERHEAD + len(self.hello.encode()))
            + self.size
            + self.frames * OVERHEAD
            + (OVERHEAD + 6)
        )

    def line_seconds(self, baud: int) -> float:
        """Time the wire bytes take at `baud` (8N1: 10 bits per byte)."""
        return self.wire_bytes * 10 / baud


@dataclass(frozen=True)
class UploadResult:
    """What happened during an upload."""

    name: str
    size: int
    frames: int
    resumed_from: int
    frames_sent: int
    resent: int
    elapsed_s: float
    loaded: bool


def plan_upload(data: bytes, name: str, load: bool = False) -> UploadPlan:
    """Check that `data` can be sent under `name`; raise LinkError if not."""
    if not NAME_PATTERN.match(name):
        raise LinkError(
            f"cannot send under the name {name!r}",
            hint="use 1-40 ASCII letters, digits, '_', '.' or '-'",
        )
    if len(data) > MAX_FILE_SIZE:
        raise LinkError(
            f"{name} has {len(data)} bytes; the protocol carries at most {MAX_FILE_SIZE}"
        )
    return UploadPlan(name, len(data), crc16(data), frame_count(len(data)), load)


def open_port(port: str, baud: int = 115200) -> serial.Serial:
    """Open `port` exclusively; a LinkError says clearly why it could not be opened."""
    try:
        return serial.Serial(port=port, baudrate=baud, timeout=POLL_S, exclusive=True)
    except (serial.SerialException, ValueError, OSError) as err:
        text = str(err)
        code = getattr(err, "errno", None)
        if code == errno.ENOENT or "FileNotFoundError" in text or not _may_exist(port):
            raise LinkError(
                f"serial port {port} does not exist",
                hint="list the ports with: python -m serial.tools.list_ports",
            ) from None
        if code in (errno.EAGAIN, errno.EWOULDBLOCK, errno.EBUSY) or any(
            word in text for word in ("lock", "Access is denied", "PermissionError")
        ):
            raise LinkError(
                f"serial port {port} is in use by another program",
                hint="close the other program (terminal, another upload) and try again",
            ) from None
        raise LinkError(f"cannot open serial port {port}: {text}") from None


def _may_exist(port: str) -> bool:
    """False for a device path that is certainly missing (POSIX); Windows names pass."""
    return not port.startswith("/") or os.path.exists(port)


class Uploader:
    """Runs the protocol over an open port (anything with pyserial's read/write)."""

    def __init__(
        self,
        port: serial.Serial,
        settings: LinkSettings | None = None,
        progress: bool = False,
    ) -> None:
        self.port = port
        self.settings = settings or LinkSettings()
        self.progress = progress
        self._reader = FrameReader()

    def upload(self, data: bytes, name: str, load: bool = False) -> UploadResult:
        """Send `data` as `name` (resuming an unfinished transfer of the same file)."""
        plan = plan_upload(data, name, load)
        started = time.monotonic()
        resume = self._hello(plan)
        bar = tqdm(
            total=plan.size,
            initial=min(resume * MAX_PAYLOAD, plan.size),
            unit="B",
            unit_scale=True,
            desc=f"upload {name}",
            disable=not self.progress,
            leave=False,
        )
        try:
            sent, resent = self._send_data(data, plan, resume, bar)
        finally:
            bar.close()
        self._finish(plan)
        return UploadResult(
            name=name,
            size=plan.size,
            frames=plan.frames,
            resumed_from=resume,
            frames_sent=sent,
            resent=resent,
            elapsed_s=time.monotonic() - started,
            loaded=load,
        )

    # -- phases ---------------------------------------------------------------

    def _hello(self, plan: UploadPlan) -> int:
        """Announce the file; return the frame the receiver wants next."""
        frame = encode_frame(FrameKind.HELLO, 0, plan.hello.encode())
        self.port.reset_input_buffer()
        for wait in self._answer_waits():
            self.port.write(frame)
            reply = self._wait_for({FrameKind.READY}, wait)
            if reply is None:
                continue
            if len(reply.payload) < 2:
                raise LinkError("the receiver sent a malformed READY")
            version, status = reply.payload[0], reply.payload[1]
            if version != PROTOCOL_VERSION or status == ReadyStatus.VERSION_REFUSED:
                raise LinkError(
                    f"the receiver speaks protocol version {version}, "
                    f"this rapidfix speaks version {PROTOCOL_VERSION}",
                    hint="load the RfxRecv.mod shipped with this rapidfix on the controller",
                )
            if status == ReadyStatus.CANNOT_CREATE:
                raise LinkError(f"the controller cannot create the file {plan.name}")
            if status != ReadyStatus.ACCEPTED or reply.seq > plan.frames:
                raise LinkError(f"the receiver answered READY with status {status}")
            return reply.seq
        raise LinkError(
            f"no answer from the receiver on {self.port.port}",
            hint=(
                "is RfxRecv running on the controller, on that channel, "
                f"at {self.port.baudrate} baud?"
            ),
        )

    def _send_data(self, data: bytes, plan: UploadPlan, base: int, bar: tqdm) -> tuple[int, int]:
        """Go-back-N from frame `base` until every frame is acknowledged; (sent, sent again)."""
        timeout, window = self._patience(), self.settings.window
        next_seq = highest = base
        sent = resent = 0
        misses = 0
        deadline = time.monotonic() + timeout
        while base < plan.frames:
            if next_seq < plan.frames and next_seq < base + window:
                stop = min(plan.frames, base + window)
                burst = b"".join(
                    encode_frame(FrameKind.DATA, n, data[n * MAX_PAYLOAD : (n + 1) * MAX_PAYLOAD])
                    for n in range(next_seq, stop)
                )
                self.port.write(burst)
                sent += stop - next_seq
                resent += max(0, min(stop, highest) - next_seq)
                highest = max(highest, stop)
                next_seq = stop
            for frame in self._read_frames():
                if frame.kind == FrameKind.ACK and base < frame.seq <= plan.frames:
                    base = frame.seq  # every frame before it is written
                    next_seq = max(next_seq, base)
                    misses = 0
                elif frame.kind == FrameKind.NAK and base <= frame.seq < next_seq:
                    base = next_seq = frame.seq  # a gap at seq: send again from there
                else:
                    continue
                bar.update(min(base * MAX_PAYLOAD, plan.size) - bar.n)
                deadline = time.monotonic() + timeout
            if base < plan.frames and time.monotonic() >= deadline:
                misses += 1
                if misses > self.settings.retries:
                    raise LinkError(
                        f"link lost: no acknowledgement of frame {base} of {plan.frames} "
                        f"after {self.settings.retries} retries {timeout:.2g} s apart",
                        hint=(
                            f"the controller keeps the first {base} frames; "
                            "run the same upload again to resume"
                        ),
                    )
                next_seq = base
                deadline = time.monotonic() + timeout
        return sent, resent

    def _finish(self, plan: UploadPlan) -> None:
        """Send END until DONE arrives, and check its status.

        Every frame is acknowledged by now, so a NAK here is a stale one and ignored.
        """
        frame = encode_frame(FrameKind.END, plan.frames, encode_end(plan.size, plan.crc))
        for wait in self._answer_waits():
            self.port.write(frame)
            reply = self._wait_for({FrameKind.DONE}, wait, keepalive=FrameKind.BUSY)
            if reply is None or reply.seq != plan.frames or not reply.payload:
                continue
            self._check_done(plan, reply.payload[0])
            return
        raise LinkError(
            f"no answer from the receiver after sending all of {plan.name}",
            hint="check on the controller whether the file arrived; upload again otherwise",
        )

    @staticmethod
    def _check_done(plan: UploadPlan, status: int) -> None:
        if status == DoneStatus.OK:
            return
        if status == DoneStatus.CHECK_FAILED:
            raise LinkError(
                f"{plan.name} failed the whole-file check on the controller; "
                "the damaged copy was removed",
                hint="upload again",
            )
        if status == DoneStatus.FILE_ERROR:
            raise LinkError(f"the controller could not rename {plan.name} into place")
        if status == DoneStatus.LOAD_FAILED:
            raise LinkError(
                f"{plan.name} is in place on the controller but Load refused it",
                hint="a syntax error, or a module of that name is already loaded",
            )
        if status == DoneStatus.NO_TRANSFER:
            raise LinkError(
                "the receiver has no transfer in progress (was it restarted?)",
                hint="upload again",
            )
        raise LinkError(f"the receiver finished with unknown status {status}")

    # -- reading --------------------------------------------------------------

    def _patience(self) -> float:
        """The time-out plus the time a full window takes on the line.

        A real port accepts a write long before the bytes leave the UART, so an
        acknowledgement can only be expected once the queue ahead has drained.
        """
        baud = getattr(self.port, "baudrate", 0) or 115200
        window_bytes = self.settings.window * (MAX_PAYLOAD + OVERHEAD)
        return self.settings.timeout + window_bytes * 10 / baud

    def _answer_waits(self) -> list[float]:
        """The waits of HELLO's and END's attempts: doubled after each silence, up to 4×.

        The receiver answers those after opening, reading back, renaming or loading
        a file, which a controller's flash or a busy disk can hold up for seconds;
        a fixed pace would give up while it works, with the outcome of END in doubt.
        """
        first = self._patience()
        return [first * min(2**k, BACKOFF_LIMIT) for k in range(self.settings.retries + 1)]

    def _read_frames(self) -> list[Frame]:
        """Whatever frames have arrived, waiting at most POLL_S for the first byte."""
        chunk = self.port.read(max(1, self.port.in_waiting))
        return self._reader.feed(chunk) if chunk else []

    def _wait_for(
        self, kinds: set[FrameKind], timeout: float, keepalive: FrameKind | None = None
    ) -> Frame | None:
        """The first frame of one of `kinds` within `timeout` (renewed by `keepalive`)."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            for frame in self._read_frames():
                if frame.kind in kinds:
                    return frame
                if frame.kind == keepalive:
                    deadline = time.monotonic() + timeout
        return None


def upload_file(
    path: str | Path,
    port: str,
    baud: int = 115200,
    name: str | None = None,
    load: bool = False,
    settings: LinkSettings | None = None,
    progress: bool = False,
) -> UploadResult:
    """Open `port`, send the file at `path` (as `name`, default its file name), close."""
    source = Path(path)
    try:
        data = source.read_bytes()
    except OSError as err:
        raise LinkError(f"cannot read {source}: {err.strerror or err}", file=source) from None
    target = name or source.name
    plan_upload(data, target, load)  # refuse a bad name before touching the port
    ser = open_port(port, baud)
    try:
        return Uploader(ser, settings, progress).upload(data, target, load)
    finally:
        ser.close()
