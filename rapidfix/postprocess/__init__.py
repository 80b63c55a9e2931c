"""The post-processor: RAPID programs rewritten with compensated targets.

Joins the RAPID layer, the kinematics and the error model. One module per idea:

- `compensator`  robot, error model (and its sha256), outside declarations, loaded once
- `resolve`      which targets are known before run time; poses, confdata, frames as arrays
- `placement`    per-move tool / work-object frames, TCP <-> flange for a batch
- `plan`         IK on the confdata branch and the compensation solve, vectorised
- `chain`        where each move starts (the motion executed just before it)
- `path`         MoveL/MoveC kept within a tolerance when they become joint moves
- `planning`     a program's plan: targets resolved, solved, compensated (`ProgramPlan`)
- `refinement`   the paths of the moves made joint moves, refined (`PathRefinement`)
- `emission`     from plan and refinement to text edits, no file I/O (`Emission`)
- `naming`       collision-free RAPID identifiers for new data
- `emission_forms` what the rewrite writes (literals, declarations, MoveAbsJ), fast forms
- `header`       the header comment, and recognising a compensated program
- `reparse_changes`  the new statements and declarations, as a program of their own
- `verify`       re-parse them (in bulk where simple) and predict where the robot will go
- `rewrite`      one file: options, result, header, file I/O; runs planning, refinement,
                 emission and the check (`rewrite_file`, `rewrite_source`)
- `batch`        a tree of programs in parallel (`run_batch`)
- `task_modules` the modules of one controller task, which see each other's data
- `execute`      the joints a nominal controller commands for a program (to "run" it)
"""

from typing import TYPE_CHECKING

from rapidfix import lazy_exports
from rapidfix.postprocess.compensator import Compensator
from rapidfix.postprocess.rewrite import (
    REWRITE_STEPS,
    RewriteOptions,
    RewriteResult,
    Skipped,
    rewrite_file,
    rewrite_source,
)

if TYPE_CHECKING:  # what type checkers and IDEs see of the lazy exports
    from rapidfix.postprocess.batch import RAPID_SUFFIXES, BatchSettings, run_batch, write_summary
    from rapidfix.postprocess.emission_forms import robtarget_literals
    from rapidfix.postprocess.execute import Execution, align_axis1, commanded_motions
    from rapidfix.postprocess.task_modules import (
        modules_beside,
        unread_task_modules,
        with_task_modules,
    )

# The other exports, name -> module of this package: each is imported from its module on
# first use (PEP 562), so exporting a name costs nothing until it is used.
# To add one: ARCHITECTURE.md, "Exports".
LAZY_EXPORTS = {
    "RAPID_SUFFIXES": "batch",
    "BatchSettings": "batch",
    "Execution": "execute",
    "align_axis1": "execute",
    "commanded_motions": "execute",
    "modules_beside": "task_modules",
    "robtarget_literals": "emission_forms",
    "run_batch": "batch",
    "unread_task_modules": "task_modules",
    "with_task_modules": "task_modules",
    "write_summary": "batch",
}

__all__ = [
    "RAPID_SUFFIXES",
    "REWRITE_STEPS",
    "BatchSettings",
    "Compensator",
    "Execution",
    "RewriteOptions",
    "RewriteResult",
    "Skipped",
    "align_axis1",
    "commanded_motions",
    "modules_beside",
    "rewrite_file",
    "rewrite_source",
    "robtarget_literals",
    "run_batch",
    "unread_task_modules",
    "with_task_modules",
    "write_summary",
]

__getattr__, __dir__ = lazy_exports(__name__, LAZY_EXPORTS)
