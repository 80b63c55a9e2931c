"""Serial upload throughput as a fraction of the line rate (target: at least 85 %).

The simulated controller takes bytes in at the line rate (10 bit times per
byte at 115 200 baud). The baseline is the time the same payload takes through
the same paced pty with no protocol at all, measured in this run; the
theoretical line time is printed beside it.

    pytest tests/benchmarks/test_link_throughput.py -n 0 -s
"""

import time

import numpy as np
import serial

from rapidfix.link.simulator import SimulatedController
from rapidfix.link.uploader import upload_file

BAUD = 115200
SIZE = 96 * 1024


def raw_line_seconds(tmp_path, data):
    """Push the bare payload through a paced simulated line; time until all arrived."""
    with SimulatedController(tmp_path / "raw", baud=BAUD, paced=True, loader=None) as sim:
        port = serial.Serial(sim.port, BAUD, exclusive=True)
        try:
            start = time.perf_counter()
            port.write(data)
            while sim.bytes_received < len(data):
                time.sleep(0.001)
            return time.perf_counter() - start
        finally:
            port.close()


def test_upload_reaches_85_percent_of_the_line_rate(tmp_path):
    data = np.random.default_rng(0).integers(0, 256, SIZE, dtype=np.uint8).tobytes()
    src = tmp_path / "BIG.mod"
    src.write_bytes(data)
    baseline = raw_line_seconds(tmp_path, data)
    theory = SIZE * 10 / BAUD
    with SimulatedController(tmp_path / "ctrl", baud=BAUD, paced=True, loader=None) as sim:
        start = time.perf_counter()
        result = upload_file(src, sim.port, BAUD)
        elapsed = time.perf_counter() - start
    assert (tmp_path / "ctrl" / "BIG.mod").read_bytes() == data
    fraction = baseline / elapsed
    print(
        f"\nupload of {SIZE} bytes at {BAUD} baud: {elapsed:.2f} s "
        f"({result.frames} frames, {result.resent} sent again)\n"
        f"baseline, bare payload through the paced line: {baseline:.2f} s "
        f"(theory {theory:.2f} s)\n"
        f"throughput: {fraction:.1%} of the measured line rate, "
        f"{theory / elapsed:.1%} of the theoretical line rate"
    )
    assert fraction >= 0.85
