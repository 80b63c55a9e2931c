"""Wall time of one batch run on 1 core and on every core (shared by the batch benchmarks)."""

from __future__ import annotations

import os
import shutil
import time
from pathlib import Path

from rapidfix.postprocess.batch import BatchSettings, run_batch

#: runs per worker count, taken in turns (1, all, 1, all, ...); the fastest of each counts.
#: A shared VM's other load makes one run of a few seconds vary by 20 % and more, which
#: alone moved the speed-up between 1.6x and 2.1x in runs of the same code.
REPEATS = int(os.environ.get("RAPIDFIX_BENCH_BATCH_REPEATS", "3"))


def batch_timings(src: Path, work: Path, settings: BatchSettings, n_files: int
                  ) -> dict[int, float]:
    """Seconds of `run_batch` over `src` with 1 worker and with os.cpu_count() workers,
    the fastest of REPEATS runs each; every file must come out "ok"."""
    cores = os.cpu_count() or 1
    timings: dict[int, float] = {}
    for _ in range(max(1, REPEATS)):
        for workers in (1, cores):
            out = work / f"out{workers}"
            t0 = time.perf_counter()
            summary = run_batch(src, out, settings, workers=workers, progress=False)
            spent = time.perf_counter() - t0
            timings[workers] = min(spent, timings.get(workers, spent))
            assert summary.count("ok") == n_files
            shutil.rmtree(out)
    return timings
