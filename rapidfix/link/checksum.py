"""CRC-16/CCITT-FALSE, the checksum of every frame and of the whole file.

Polynomial 0x1021, initial value 0xFFFF, no reflection, no final XOR; the check
value of b"123456789" is 0x29B1. It catches every burst error of up to 16 bits,
which a sum such as Fletcher-16 does not (it cannot tell 0x00 from 0xFF).

The RAPID receiver has no 16-bit integers, so it keeps the register as two
bytes (high, low) and updates them per byte with BitXOr, BitLSh and BitRSh only;
:func:`crc16_step` is that exact update, written out so that the Python side and
the RAPID module can be compared line by line. :func:`crc16` computes the same
value at C speed through :func:`binascii.crc_hqx`.
"""

from __future__ import annotations

import binascii

CRC_INIT = 0xFFFF


def crc16(data: bytes, crc: int = CRC_INIT) -> int:
    """CRC-16/CCITT-FALSE of `data`, continuing from register value `crc`."""
    return binascii.crc_hqx(data, crc)


def crc16_step(hi: int, lo: int, byte: int) -> tuple[int, int]:
    """Feed one byte to the register held as two bytes; the RAPID receiver's CrcByte.

    With x = hi XOR byte, then x = x XOR (x >> 4), the 16-bit update
    crc' = (crc << 8) XOR (x << 12) XOR (x << 5) XOR x splits into
    hi' = lo XOR (x >> 3) XOR (x << 4) and lo' = (x << 5) XOR x, every shift
    truncated to 8 bits as RAPID's BitLSh does on a byte.
    """
    x = hi ^ byte
    x ^= x >> 4
    new_hi = lo ^ (x >> 3) ^ ((x << 4) & 0xFF)
    new_lo = ((x << 5) & 0xFF) ^ x
    return new_hi, new_lo
