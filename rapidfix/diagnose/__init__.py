"""Closing the loop: find what the model misses, name the physical effect, add it, prove it.

`run.diagnose` / `run.diagnose_files` (the `rapidfix diagnose` command) fit every
candidate effect (`candidates`, physics in `rapidfix.error_model.candidates`) on the
calibration points with the generic fitter (`rapidfix.error_model.fit_effects`),
judge it on the validation points (`selection`: BIC, a significance test of the
predicted change and the share of the validation residual explained), add the
accepted ones greedily and save the refitted model; `report` writes the
before/after report with the evidence, `features`/`plots` the residual against
what exposed each effect.
`rapidfix.demo.demo_loop` shows the whole loop on a virtual robot with one hidden effect.
"""

from typing import TYPE_CHECKING

from rapidfix import lazy_exports

if TYPE_CHECKING:  # what type checkers and IDEs see of the lazy exports
    from rapidfix.diagnose.candidate_builders import CANDIDATES
    from rapidfix.diagnose.run import diagnose_files, summary_lines

# The other exports, name -> module of this package: each is imported from its module on
# first use (PEP 562), so exporting a name costs nothing until it is used.
# To add one: ARCHITECTURE.md, "Exports".
LAZY_EXPORTS = {
    "CANDIDATES": "candidate_builders",
    "diagnose_files": "run",
    "summary_lines": "run",
}

__all__ = [
    "CANDIDATES",
    "diagnose_files",
    "summary_lines",
]

__getattr__, __dir__ = lazy_exports(__name__, LAZY_EXPORTS)
