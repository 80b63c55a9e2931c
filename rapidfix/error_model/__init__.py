"""The joint motion error model: effects, fitting, compensation, model files.

Modules: `context` (per-pose conditions), `effect` (the Effect interface and
registry), `joint_rbf` (the per-joint Gaussian RBF error), `model` (ErrorModel
and the full forward model), `forward` (kinematics on changed geometry),
`compensate` (solve for commanded joints), `fit` (models from sweep analyses),
`model_file` (JSON I/O). The names below are the ones other areas use.
"""

from rapidfix.error_model.compensate import CompensationResult, compensate, solve_compensation
from rapidfix.error_model.context import Context
from rapidfix.error_model.effect import Effect, Geometry
from rapidfix.error_model.joint_rbf import JointRBF, OutsideRangeWarning
from rapidfix.error_model.model import ErrorModel
from rapidfix.error_model.model_file import load_model, save_model

__all__ = [
    "CompensationResult",
    "Context",
    "Effect",
    "ErrorModel",
    "Geometry",
    "JointRBF",
    "OutsideRangeWarning",
    "compensate",
    "load_model",
    "save_model",
    "solve_compensation",
]
