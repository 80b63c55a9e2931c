"""Effects beyond the per-joint error, one physical cause per module.

`rapidfix diagnose` tries each as an explanation of what the per-joint model leaves
unexplained: `compliance` (joints 2 and 3 deflecting under gravity and payload),
`geometry` (errors of the joint screws, identifiable part only), `tool_offset`,
`backlash`, `thermal` (arm growth with temperature or time), `coupling` (one
joint's error depending on another's angle), `registration` (tracker frame and
scale) and `joint_reference` (the per-joint model's offsets and first harmonics re-referenced
on new data), and `joint_driver`: one joint's error as a low-order function of one
driver (gravity torque, temperature, time, payload, another joint's direction or angle),
and `frame_driver`: the tool, the base or one link moved by a driver (the tool bending
under gravity, the base tilting with the overturning moment, a link growing with heat),
and `rbf_correction`: the fallback, a cross-validated smooth correction of one joint
over a few features, for a residual no cause above describes.
All are registered with `rapidfix.error_model.effect` by their `type_name`.
"""

from rapidfix.error_model.candidates import (  # noqa: F401  (registers every effect)
    backlash,
    compliance,
    coupling,
    frame_driver,
    geometry,
    gravity,
    joint_driver,
    joint_reference,
    rbf_correction,
    registration,
    thermal,
    tool_offset,
)
