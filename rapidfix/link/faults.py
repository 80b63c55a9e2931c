"""Fault injection on the simulated serial line, for tests and demonstrations.

The simulated controller passes every frame through a :class:`FaultInjector`
in both directions. Host bytes arrive as a clean stream, so the injector cuts
them into frames first (by SOH and the length byte) and then, per frame, with
probabilities from :class:`LinkFaults` and a seeded generator:

- drops it (a frame lost on the line),
- corrupts bytes in it (each byte with probability `corrupt_byte`),
- duplicates it,
- stalls the line for `delay_s` before it (longer than the host's time-out),
- and, once, kills the link in both directions for `outage_s` seconds after
  `outage_after` host frames (a cable pulled and plugged back).
"""

from __future__ import annotations

import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from rapidfix.link.protocol import HEADER_SIZE, OVERHEAD, SOH


@dataclass(frozen=True)
class LinkFaults:
    """What goes wrong on the line, and how often (probabilities per frame)."""

    seed: int = 0
    drop: float = 0.0
    corrupt_byte: float = 0.0
    duplicate: float = 0.0
    delay: float = 0.0
    delay_s: float = 0.0
    outage_after: int | None = None
    outage_s: float = 0.0
    replies_too: bool = True  # apply drop/corrupt/duplicate to the controller's replies


class FaultInjector:
    """Applies :class:`LinkFaults` to the frames crossing the simulated line."""

    def __init__(self, faults: LinkFaults, clock: Callable[[], float] = time.monotonic) -> None:
        self.faults = faults
        self.rng = np.random.default_rng(faults.seed)
        self.clock = clock
        self.counts: Counter[str] = Counter()
        self._pending = bytearray()
        self._host_frames = 0
        self._dead_until: float | None = None

    def link_dead(self) -> bool:
        """True while the outage lasts."""
        return self._dead_until is not None and self.clock() < self._dead_until

    def from_host(self, data: bytes) -> list[tuple[float, bytes]]:
        """Host bytes in; (stall seconds, bytes to deliver) pieces out, in order."""
        self._pending += data
        pieces: list[tuple[float, bytes]] = []
        for frame in self._cut_frames():
            self._host_frames += 1
            outage_after = self.faults.outage_after
            if outage_after is not None and self._host_frames == outage_after + 1:
                self._dead_until = self.clock() + self.faults.outage_s
                self.counts["outage"] += 1
            pieces.extend(self._apply(frame, spoil=True))
        return pieces

    def to_host(self, frame: bytes) -> list[tuple[float, bytes]]:
        """One controller reply in; what reaches the host out."""
        return self._apply(frame, spoil=self.faults.replies_too)

    def _cut_frames(self) -> list[bytes]:
        buf = self._pending
        frames: list[bytes] = []
        while buf:
            if buf[0] != SOH:
                start = buf.find(SOH)
                cut = len(buf) if start < 0 else start
                frames.append(bytes(buf[:cut]))
                del buf[:cut]
                continue
            if len(buf) < HEADER_SIZE:
                break
            end = OVERHEAD + buf[4]
            if len(buf) < end:
                break
            frames.append(bytes(buf[:end]))
            del buf[:end]
        return frames

    def _apply(self, frame: bytes, spoil: bool) -> list[tuple[float, bytes]]:
        if self.link_dead():
            self.counts["lost_in_outage"] += 1
            return []
        if not spoil:
            return [(0.0, frame)]
        f = self.faults
        draw = self.rng.random(4)
        if draw[0] < f.drop:
            self.counts["dropped"] += 1
            return []
        stall = 0.0
        if draw[1] < f.delay:
            self.counts["delayed"] += 1
            stall = f.delay_s
        data = np.frombuffer(frame, dtype=np.uint8).copy()
        hit = self.rng.random(data.size) < f.corrupt_byte
        if hit.any():
            self.counts["corrupted"] += 1
            data[hit] ^= self.rng.integers(1, 256, size=int(hit.sum()), dtype=np.uint8)
        out = [(stall, data.tobytes())]
        if draw[2] < f.duplicate:
            self.counts["duplicated"] += 1
            out.append((0.0, data.tobytes()))
        return out
