"""Everything that runs on the virtual robot end to end: the demo and simulated runs.

The layer above the post-processor, the diagnosis and the campaign: it joins them
with the simulator (`rapidfix.sim`) so that no lower package needs the simulator or
the pipeline. One module per step of `rapidfix demo`, plus the simulated runs the
`simulate-program` command uses:

- `programs`       rewrite the sample programs, run original and rewritten on the robot
- `ballbar_program` the source paper's ballbar test as a RAPID program (samples/ballbar.mod)
- `closed_loop`    a pick-and-place program with loads, rewritten with each model, run
- `hidden_effect`  one effect the per-joint model cannot know, named by the diagnosis
- `campaign`       the ISO 9283 cube planned, run, compensated and checked
- `program_run`    a RAPID program executed on the virtual robot (timing, payloads)
- `campaign_run`   a campaign program run and measured: a tracker export
"""

from rapidfix.demo.campaign import demo_campaign, format_campaign
from rapidfix.demo.campaign_run import ExportOptions, simulate_program
from rapidfix.demo.closed_loop import (
    LoopProgram,
    LoopRun,
    demo_on_robot,
    format_on_robot,
    measured_range,
    pick_and_place,
    run_on_robot,
)
from rapidfix.demo.hidden_effect import demo_loop, format_demo
from rapidfix.demo.programs import format_table, rewrite_and_run, sample_programs

__all__ = [
    "ExportOptions",
    "LoopProgram",
    "LoopRun",
    "demo_campaign",
    "demo_loop",
    "demo_on_robot",
    "format_campaign",
    "format_demo",
    "format_on_robot",
    "format_table",
    "measured_range",
    "pick_and_place",
    "rewrite_and_run",
    "run_on_robot",
    "sample_programs",
    "simulate_program",
]
