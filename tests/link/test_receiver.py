"""The controller's state machine, driven frame by frame without a port."""

import numpy as np
import pytest

from rapidfix.link.checksum import crc16
from rapidfix.link.protocol import (
    MAX_PAYLOAD,
    DoneStatus,
    Frame,
    FrameKind,
    FrameReader,
    Hello,
    ReadyStatus,
    encode_end,
)
from rapidfix.link.receiver import ControllerReceiver, ReceiverState, temp_name

DATA = np.random.default_rng(7).integers(0, 256, 5 * MAX_PAYLOAD + 17, dtype=np.uint8).tobytes()
CHUNKS = [DATA[i : i + MAX_PAYLOAD] for i in range(0, len(DATA), MAX_PAYLOAD)]
HELLO = Hello(name="PROG.mod", size=len(DATA), crc=crc16(DATA))
N, SIZE, CRC = len(CHUNKS), len(DATA), crc16(DATA)


def replies(receiver, kind, seq=0, payload=b""):
    """Decoded replies of the receiver to one frame."""
    wire = b"".join(receiver.handle(Frame(kind, seq, payload)))
    return [(f.kind, f.seq, f.payload) for f in FrameReader().feed(wire)]


def hello(receiver, h=HELLO):
    return replies(receiver, FrameKind.HELLO, 0, h.encode())


def end(receiver, n=N, size=SIZE, crc=CRC):
    return replies(receiver, FrameKind.END, n, encode_end(size, crc))


def test_in_order_transfer_lands_under_the_real_name_only_after_end(tmp_path):
    rx = ControllerReceiver(tmp_path, loader=None)
    assert hello(rx) == [(FrameKind.READY, 0, bytes([1, ReadyStatus.ACCEPTED]))]
    for n, chunk in enumerate(CHUNKS):
        assert replies(rx, FrameKind.DATA, n, chunk) == [(FrameKind.ACK, n + 1, b"")]
        assert not (tmp_path / "PROG.mod").exists()
    assert end(rx) == [(FrameKind.DONE, len(CHUNKS), bytes([DoneStatus.OK]))]
    assert (tmp_path / "PROG.mod").read_bytes() == DATA
    assert sorted(p.name for p in tmp_path.iterdir()) == ["PROG.mod"]
    # DONE lost: the repeated END gets the same answer and changes nothing
    assert end(rx) == [(FrameKind.DONE, len(CHUNKS), bytes([DoneStatus.OK]))]
    assert rx.state == ReceiverState.FINISHED


def test_duplicates_are_acknowledged_not_written_and_a_gap_is_nakked_once(tmp_path):
    rx = ControllerReceiver(tmp_path, loader=None)
    hello(rx)
    assert replies(rx, FrameKind.DATA, 0, CHUNKS[0]) == [(FrameKind.ACK, 1, b"")]
    assert replies(rx, FrameKind.DATA, 0, CHUNKS[0]) == [(FrameKind.ACK, 1, b"")]
    assert replies(rx, FrameKind.DATA, 2, CHUNKS[2]) == [(FrameKind.NAK, 1, b"")]
    assert replies(rx, FrameKind.DATA, 3, CHUNKS[3]) == []
    assert end(rx) == [(FrameKind.NAK, 1, b"")]
    for n in range(1, len(CHUNKS)):
        assert replies(rx, FrameKind.DATA, n, CHUNKS[n]) == [(FrameKind.ACK, n + 1, b"")]
    assert end(rx)[0][2] == bytes([DoneStatus.OK])
    assert (tmp_path / "PROG.mod").read_bytes() == DATA


def test_resume_with_the_same_file_and_restart_with_another(tmp_path):
    rx = ControllerReceiver(tmp_path, loader=None)
    hello(rx)
    for n in range(3):
        replies(rx, FrameKind.DATA, n, CHUNKS[n])
    assert hello(rx) == [(FrameKind.READY, 3, bytes([1, 0]))]
    other = Hello(name="PROG.mod", size=len(DATA), crc=crc16(DATA) ^ 1)
    assert hello(rx, other) == [(FrameKind.READY, 0, bytes([1, 0]))]
    assert (tmp_path / temp_name("PROG.mod")).stat().st_size == 0


def test_a_file_failing_the_whole_file_check_is_removed(tmp_path):
    (tmp_path / "PROG.mod").write_bytes(b"old program")
    wrong = Hello(name="PROG.mod", size=len(DATA), crc=crc16(DATA) ^ 0x0100)
    rx = ControllerReceiver(tmp_path, loader=None)
    hello(rx, wrong)
    for n, chunk in enumerate(CHUNKS):
        replies(rx, FrameKind.DATA, n, chunk)
    assert end(rx, crc=wrong.crc) == [
        (FrameKind.DONE, len(CHUNKS), bytes([DoneStatus.CHECK_FAILED]))
    ]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["PROG.mod"]
    assert (tmp_path / "PROG.mod").read_bytes() == b"old program"


def test_busy_frames_while_reading_back_a_large_file(tmp_path):
    data = bytes(range(256)) * 40  # 10240 bytes: two full 4096-byte blocks
    rx = ControllerReceiver(tmp_path, loader=None)
    hello(rx, Hello(name="BIG.mod", size=len(data), crc=crc16(data)))
    chunks = [data[i : i + MAX_PAYLOAD] for i in range(0, len(data), MAX_PAYLOAD)]
    for n, chunk in enumerate(chunks):
        replies(rx, FrameKind.DATA, n, chunk)
    out = end(rx, len(chunks), len(data), crc16(data))
    assert [k for k, _, _ in out] == [FrameKind.BUSY, FrameKind.BUSY, FrameKind.DONE]


def test_version_mismatch_and_bad_names_are_refused(tmp_path):
    rx = ControllerReceiver(tmp_path, loader=None, version=2)
    assert hello(rx) == [(FrameKind.READY, 0, bytes([2, ReadyStatus.VERSION_REFUSED]))]
    assert rx.state == ReceiverState.IDLE
    rx = ControllerReceiver(tmp_path, loader=None)
    bad = Hello(name="../PROG.mod", size=1, crc=0)
    assert hello(rx, bad) == [(FrameKind.READY, 0, bytes([1, ReadyStatus.CANNOT_CREATE]))]
    assert list(tmp_path.iterdir()) == []
    assert end(rx)[0][2] == bytes([DoneStatus.NO_TRANSFER])


@pytest.mark.parametrize("fails", [False, True])
def test_load_after_rename(tmp_path, fails):
    seen = []

    def loader(path):
        seen.append(path.read_bytes())
        if fails:
            raise RuntimeError("syntax error")

    rx = ControllerReceiver(tmp_path, loader=loader)
    hello(rx, Hello(name="PROG.mod", size=len(DATA), crc=crc16(DATA), load=True))
    for n, chunk in enumerate(CHUNKS):
        replies(rx, FrameKind.DATA, n, chunk)
    status = DoneStatus.LOAD_FAILED if fails else DoneStatus.OK
    assert end(rx)[0][2] == bytes([status])
    assert seen == [DATA]
    assert (tmp_path / "PROG.mod").read_bytes() == DATA
