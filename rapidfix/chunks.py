"""Batch sizes of the vectorised hot paths, in one place.

Kinematics, the error model and the path check work on arrays of poses; on a CAM
program of a million moves one big array would leave the CPU cache, so each hot
path goes through its batch in chunks of these many rows. Each size was chosen by
timing its own loop (see docs/performance.md); results never depend on them.
"""

from __future__ import annotations

#: forward products (screws.py): their (chunk, 4, 4) temporaries stay in the L2 cache
FK = 2048
#: forward products in numpy columns (fk_columns.py): about thirty (chunk,) columns alive
FK_COLUMNS = 4096
#: `RobotModel.ik_conf` on large batches: IK on the confdata branch, one chunk at a time
IK_CONF = 8192
#: closed-form IK with numpy (ik.solve_all): temporaries of a chunk stay in L2/L3
IK_SOLVE = 4096
#: compiled closed-form IK (ik_compiled): the atan2 arguments of a chunk stay in L2
IK_COMPILED = 1024
#: the per-joint compensation solve (compensate.py)
COMPENSATE = 4096
#: joint vectors per call of the error model's prediction on a path (postprocess/path.py):
#: its temporaries (poses × basis functions) stay in the cache
PREDICT = 4096
#: segments per call of the line bound (postprocess/refinement.py): its temporaries take
#: about 0.5 KB a segment, which a million-line program would hold all at once
LINE_BOUND = 8192
#: targets per pass of naming the confdata that do reach a target (postprocess/plan.py):
#: every branch and turn of each is solved and classified, about 10 KB a target
EXPLAIN_CONF = 2048
#: targets per pass of the model's error of the original moves (postprocess/rewrite.py):
#: its flange, frame and TCP poses take about 1 KB a target, and they came at the
#: rewrite's peak, with the program model, the plan and the emission alive (a figure
#: the rewrite only prints: its last bits follow BLAS's matrix-vector products, whose
#: rounding depends on how many rows a call has)
PREDICTED_BEFORE = 16384
#: declarations given to the editor at a time after their anchors (postprocess/emission.py):
#: the anchors' offsets and line starts take about 200 bytes each while they are placed,
#: at the rewrite's peak
INSERTED_DECLARATIONS = 16384
