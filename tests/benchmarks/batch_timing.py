"""Wall time of one batch run on 1 core and on every core (shared by the batch benchmarks)."""

from __future__ import annotations

import os
import shutil
import time
from pathlib import Path

from rapidfix.postprocess.batch import BatchSettings, run_batch


def batch_timings(src: Path, work: Path, settings: BatchSettings, n_files: int
                  ) -> dict[int, float]:
    """Seconds of `run_batch` over `src` with 1 worker and with os.cpu_count() workers;
    every file must come out "ok"."""
    cores = os.cpu_count() or 1
    timings = {}
    for workers in (1, cores):
        out = work / f"out{workers}"
        t0 = time.perf_counter()
        summary = run_batch(src, out, settings, workers=workers, progress=False)
        timings[workers] = time.perf_counter() - t0
        assert summary.count("ok") == n_files
        shutil.rmtree(out)
    return timings
