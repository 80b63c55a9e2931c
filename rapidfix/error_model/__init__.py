"""The joint motion error model: effects, fitting, compensation, model files.

Modules: `context` (per-pose conditions), `effect` (the Effect interface and
registry), `joint_rbf` (the per-joint Gaussian RBF error), `model` (ErrorModel
and the full forward model), `forward` (kinematics on changed geometry),
`compensate` (solve for commanded joints), `fit` (models from sweep analyses),
`model_file` (JSON I/O). The names below are the ones other areas use.
"""

from typing import TYPE_CHECKING

from rapidfix import lazy_exports
from rapidfix.error_model.compensate import CompensationResult, compensate, solve_compensation
from rapidfix.error_model.context import Context
from rapidfix.error_model.effect import Effect, Geometry
from rapidfix.error_model.joint_rbf import JointRBF, OutsideRangeWarning
from rapidfix.error_model.model import ErrorModel
from rapidfix.error_model.model_file import load_model, save_model

if TYPE_CHECKING:  # what type checkers and IDEs see of the lazy exports
    from rapidfix.error_model.candidates.backlash import Backlash
    from rapidfix.error_model.candidates.compliance import JointCompliance
    from rapidfix.error_model.candidates.coupling import JointCoupling
    from rapidfix.error_model.candidates.frame_driver import FrameDriver
    from rapidfix.error_model.candidates.geometry import (
        N_ERRORS,
        LinkGeometry,
        error_names,
        identifiable_modes,
    )
    from rapidfix.error_model.candidates.gravity import nominal_robot
    from rapidfix.error_model.candidates.joint_driver import JointDriver
    from rapidfix.error_model.candidates.joint_reference import OFFSET_JOINTS, JointReference
    from rapidfix.error_model.candidates.rbf_correction import (
        CONTEXT_FEATURES,
        JOINT_FEATURES,
        RBFCorrection,
        feature_label,
        feature_values,
        gaussian_design,
    )
    from rapidfix.error_model.candidates.registration import (
        TrackerFrame,
        TrackerScale,
        world_to_base,
    )
    from rapidfix.error_model.candidates.thermal import ThermalDrift
    from rapidfix.error_model.candidates.tool_offset import ToolOffset
    from rapidfix.error_model.context import STILL_RAD, last_motion_direction
    from rapidfix.error_model.fit import fit_error_model, sweep_gaps
    from rapidfix.error_model.fit_effects import (
        EffectsFit,
        MeasuredPoints,
        fit_free_effects,
        jacobian,
        predict,
    )
    from rapidfix.error_model.joint_rbf import compiled_sums

# The other exports, name -> module of this package: each is imported from its module on
# first use (PEP 562), so exporting a name costs nothing until it is used.
# To add one: ARCHITECTURE.md, "Exports".
LAZY_EXPORTS = {
    "CONTEXT_FEATURES": "candidates.rbf_correction",
    "JOINT_FEATURES": "candidates.rbf_correction",
    "N_ERRORS": "candidates.geometry",
    "OFFSET_JOINTS": "candidates.joint_reference",
    "STILL_RAD": "context",
    "Backlash": "candidates.backlash",
    "EffectsFit": "fit_effects",
    "FrameDriver": "candidates.frame_driver",
    "JointCompliance": "candidates.compliance",
    "JointCoupling": "candidates.coupling",
    "JointDriver": "candidates.joint_driver",
    "JointReference": "candidates.joint_reference",
    "LinkGeometry": "candidates.geometry",
    "MeasuredPoints": "fit_effects",
    "RBFCorrection": "candidates.rbf_correction",
    "ThermalDrift": "candidates.thermal",
    "ToolOffset": "candidates.tool_offset",
    "TrackerFrame": "candidates.registration",
    "TrackerScale": "candidates.registration",
    "compiled_sums": "joint_rbf",
    "error_names": "candidates.geometry",
    "feature_label": "candidates.rbf_correction",
    "feature_values": "candidates.rbf_correction",
    "fit_error_model": "fit",
    "fit_free_effects": "fit_effects",
    "gaussian_design": "candidates.rbf_correction",
    "identifiable_modes": "candidates.geometry",
    "jacobian": "fit_effects",
    "last_motion_direction": "context",
    "nominal_robot": "candidates.gravity",
    "predict": "fit_effects",
    "sweep_gaps": "fit",
    "world_to_base": "candidates.registration",
}

__all__ = [
    "CONTEXT_FEATURES",
    "JOINT_FEATURES",
    "N_ERRORS",
    "OFFSET_JOINTS",
    "STILL_RAD",
    "Backlash",
    "CompensationResult",
    "Context",
    "Effect",
    "EffectsFit",
    "ErrorModel",
    "FrameDriver",
    "Geometry",
    "JointCompliance",
    "JointCoupling",
    "JointDriver",
    "JointRBF",
    "JointReference",
    "LinkGeometry",
    "MeasuredPoints",
    "OutsideRangeWarning",
    "RBFCorrection",
    "ThermalDrift",
    "ToolOffset",
    "TrackerFrame",
    "TrackerScale",
    "compensate",
    "compiled_sums",
    "error_names",
    "feature_label",
    "feature_values",
    "fit_error_model",
    "fit_free_effects",
    "gaussian_design",
    "identifiable_modes",
    "jacobian",
    "last_motion_direction",
    "load_model",
    "nominal_robot",
    "predict",
    "save_model",
    "solve_compensation",
    "sweep_gaps",
    "world_to_base",
]

__getattr__, __dir__ = lazy_exports(__name__, LAZY_EXPORTS)
