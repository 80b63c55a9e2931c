"""CRC-16/CCITT-FALSE: the published check value and the byte-register form used in RAPID."""

from hypothesis import given, settings
from hypothesis import strategies as st

from rapidfix.link.checksum import crc16, crc16_step


def bitwise_crc(data: bytes) -> int:
    """Textbook MSB-first shift register, polynomial 0x1021, init 0xFFFF."""
    crc = 0xFFFF
    for byte in data:
        crc ^= byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) if crc & 0x8000 else crc << 1
            crc &= 0xFFFF
    return crc


def test_check_value_of_the_catalogue():
    assert crc16(b"123456789") == 0x29B1


@settings(max_examples=60, deadline=None)
@given(st.binary(max_size=300))
def test_byte_register_form_matches_the_shift_register(data):
    hi, lo = 0xFF, 0xFF
    for byte in data:
        hi, lo = crc16_step(hi, lo, byte)
        assert 0 <= hi <= 255 and 0 <= lo <= 255
    assert (hi << 8) | lo == bitwise_crc(data) == crc16(data)


@settings(max_examples=60, deadline=None)
@given(st.binary(min_size=1, max_size=87), st.data())
def test_every_burst_of_up_to_16_bits_changes_the_crc(data, draw):
    start = draw.draw(st.integers(0, len(data) * 8 - 1))
    width = draw.draw(st.integers(1, 16))
    pattern = draw.draw(st.integers(0, (1 << width) - 1)) | 1 | (1 << (width - 1))
    value = int.from_bytes(data, "big") ^ (pattern << start)
    spoiled = (value & ((1 << (len(data) * 8)) - 1)).to_bytes(len(data), "big")
    if spoiled != data:
        assert crc16(spoiled) != crc16(data)
