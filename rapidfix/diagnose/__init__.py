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
