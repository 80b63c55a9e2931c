"""Frame encoding and the incremental decoder that mirrors the RAPID receiver."""

import struct

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from rapidfix.link.checksum import crc16
from rapidfix.link.protocol import (
    MAX_PAYLOAD,
    SOH,
    Frame,
    FrameReader,
    Hello,
    decode_end,
    encode_end,
    encode_frame,
)

frames_st = st.lists(
    st.builds(
        Frame,
        kind=st.sampled_from([ord(c) for c in "HDERKNBF"]),
        seq=st.integers(0, 0xFFFF),
        payload=st.binary(max_size=MAX_PAYLOAD),
    ),
    max_size=12,
)


def test_layout_byte_by_byte():
    wire = encode_frame(ord("D"), 0x1234, b"abc")
    assert wire[0] == SOH
    assert wire[1:5] == bytes([ord("D"), 0x12, 0x34, 3])
    assert wire[5:8] == b"abc"
    assert struct.unpack(">H", wire[8:]) == (crc16(wire[1:8]),)
    assert len(wire) == 7 + 3


@settings(max_examples=50, deadline=None)
@given(frames_st, st.lists(st.binary(max_size=5), max_size=13), st.integers(1, 40))
def test_stream_with_noise_between_frames_decodes_in_any_chunking(frames, noise, step):
    noise = [n.replace(bytes([SOH]), b"") for n in noise]  # noise without a start byte
    noise += [b""] * (len(frames) + 1 - len(noise))
    stream = noise[0] + b"".join(
        encode_frame(f.kind, f.seq, f.payload) + n for f, n in zip(frames, noise[1:])
    )
    reader = FrameReader()
    out = []
    for i in range(0, len(stream), step):
        out += reader.feed(stream[i : i + step])
    assert out == frames
    assert reader.bad_frames == 0


@settings(max_examples=80, deadline=None)
@given(frames_st.filter(bool), st.data())
def test_a_corrupted_byte_never_yields_a_wrong_frame(frames, data):
    wires = [encode_frame(f.kind, f.seq, f.payload) for f in frames]
    victim = data.draw(st.integers(0, len(frames) - 1))
    pos = data.draw(st.integers(1, len(wires[victim]) - 1))  # SOH itself: the frame is just skipped
    flip = data.draw(st.integers(1, 255))
    spoiled = bytearray(wires[victim])
    spoiled[pos] ^= flip
    wires[victim] = bytes(spoiled)
    out = FrameReader().feed(b"".join(wires))
    # the frames before the victim intact; after it, a subsequence of the rest
    # (a spoiled length byte may swallow the next frames), never anything else
    assert out[:victim] == frames[:victim]
    rest = iter(frames[victim + 1 :])
    assert all(any(f == g for g in rest) for f in out[victim:])


def test_too_long_length_is_rejected_and_reading_goes_on():
    bad = bytes([SOH, ord("D"), 0, 0, MAX_PAYLOAD + 1])
    good = encode_frame(ord("K"), 7)
    reader = FrameReader()
    assert reader.feed(bad + good) == [Frame(ord("K"), 7, b"")]
    assert reader.bad_frames == 1


def test_abandon_drops_a_partial_frame():
    wire = encode_frame(ord("D"), 3, b"xyz")
    reader = FrameReader()
    assert reader.feed(wire[:6]) == []
    assert reader.in_frame
    reader.abandon()
    assert not reader.in_frame
    assert reader.feed(wire[6:] + wire) == [Frame(ord("D"), 3, b"xyz")]


def test_encode_refuses_what_the_receiver_cannot_take():
    rng = np.random.default_rng(0)
    for bad in (lambda: encode_frame(68, 0x10000), lambda: encode_frame(68, 0, rng.bytes(81))):
        try:
            bad()
        except ValueError:
            continue
        raise AssertionError("accepted")


@settings(max_examples=40, deadline=None)
@given(
    st.from_regex(r"[A-Za-z0-9_][A-Za-z0-9_.\-]{0,39}", fullmatch=True),
    st.integers(0, 2**32 - 1),
    st.integers(0, 0xFFFF),
    st.booleans(),
)
def test_hello_and_end_payloads_round_trip(name, size, crc, load):
    hello = Hello(name=name, size=size, crc=crc, load=load)
    payload = hello.encode()
    assert len(payload) <= MAX_PAYLOAD
    assert Hello.decode(payload) == hello
    assert decode_end(encode_end(size, crc)) == (size, crc)
