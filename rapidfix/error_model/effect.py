"""The Effect interface: one physical cause of robot error, with a few parameters.

An error model (`rapidfix.error_model.model.ErrorModel`) is a list of effects. Each
effect is one physical cause — the per-joint transmission error, joint
compliance under gravity, a link-length error, backlash, thermal drift, a wrong
tool or target-ball offset, a mis-registered tracker — and contributes to the
forward model in one (or both) of two ways:

* **joint errors**: `joint_delta(q_cmd, ctx) -> (N, 6)` rad, added to the
  commanded joints: θ_actual = θ_cmd + Σ Δθ. Effects whose error on joint j
  depends only on θ_j (and the context) set `separable = True`; a model made only
  of those is compensated joint by joint (fast), anything else by the general
  solve on the full forward model (`rapidfix.error_model.compensate`), with no new code.
* **geometry**: `apply_geometry(geometry, q_cmd, ctx) -> Geometry` returns a
  changed copy of the joint axes, tool0 home pose, tool correction or measurement
  frame (see `Geometry`). Arrays may be per pose (leading N axis) when the change
  depends on the context (time, temperature).

Parameters. Every effect exposes a flat float vector `params()` with matching
`param_names` (units in the names: "_deg", "_mm", "_ppm", …), `set_fitted(p)`
to write it back, and `uncertainty` (same length, or None before a fit). A
generic least-squares fitter can therefore stack the vectors of all free effects
(`free=True`), perturb them, and write the solution back, without knowing what
the effects are. Internal units are radians and mm, like the rest of the model.

Serialisation. `to_dict()` returns plain JSON data with a `"type"` key;
`rapidfix.error_model.registry.effect_from_dict(d)` rebuilds any registered effect. A subclass
registers
itself by defining a unique class attribute `type_name` (via
`__init_subclass__`), so adding an effect is writing one class in one module and
importing it in `rapidfix.error_model.registry` (the registry's import list).

Contract for implementers:
- vectorised over N poses, no Python loop over poses;
- return zeros (or the geometry unchanged) for poses the effect does not touch;
- raise `rapidfix.exceptions.ModelError` when a needed context field is missing;
- `_state()` / `_from_state()` cover everything that is not the parameter vector
  (hyper-parameters, valid ranges), so `to_dict` round-trips exactly;
- an effect that needs the arm itself (gravity torques from the joint frames)
  keeps the robot name in its state and loads the model with
  `rapidfix.kinematics.load_robot` (cached), so the interface stays robot-free.

A minimal effect (a constant offset on joint 2, compensated by the per-joint solve):

    class Joint2Offset(Effect):
        type_name = "joint2_offset"
        separable = True
        adds_joint_delta = True
        param_names = ("offset_rad",)

        def __init__(self, name=None, *, free=True, offset=0.0):
            super().__init__(name, free=free)
            self.offset = offset

        def params(self):
            return np.array([self.offset])

        def set_fitted(self, p):
            self.offset = float(self._check_length(p)[0])

        def joint_delta(self, q_cmd, ctx):
            out = np.zeros_like(q_cmd)
            out[:, 1] = self.offset
            return out
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, ClassVar

import numpy as np

from rapidfix.error_model.context import Context
from rapidfix.exceptions import ModelError
from rapidfix.kinematics import RobotModel

_REGISTRY: dict[str, type[Effect]] = {}


@dataclass(frozen=True)
class Geometry:
    """What geometry effects change, in the robot base frame, mm and rad.

    axis_dirs:   (6, 3) or (N, 6, 3), unit joint axes at θ = 0;
    axis_points: (6, 3) or (N, 6, 3), a point on each axis, mm;
    home:   (4, 4) or (N, 4, 4), tool0 pose at θ = 0;
    tool:   (4, 4) or (N, 4, 4), correction applied after the declared target-ball
            offset, in that ball's frame (parallel to the flange; identity = the
            declaration is right); like `world` it describes the measurement and is
            used only when predicting measurements, never when compensating;
    world:  (4, 4) or (N, 4, 4), base frame → measurement (tracker) frame, used only
            when predicting measurements, never when compensating.
    """

    axis_dirs: np.ndarray
    axis_points: np.ndarray
    home: np.ndarray
    tool: np.ndarray
    world: np.ndarray

    @classmethod
    def nominal(cls, robot: RobotModel) -> Geometry:
        """The robot's nominal geometry (identity tool correction and frame)."""
        eye = np.eye(4)
        return cls(
            np.asarray(robot.axis_dirs, float),
            np.asarray(robot.axis_points, float),
            np.asarray(robot.home, float),
            eye,
            eye,
        )

    def replaced(self, **changes: np.ndarray) -> Geometry:
        """A copy with some fields replaced."""
        return replace(self, **changes)

    def same_kinematics(self, robot: RobotModel) -> bool:
        """True when axes and home are exactly the robot's (robot.fk can be used)."""
        return (
            self.axis_dirs.shape == (6, 3)
            and self.home.shape == (4, 4)
            and np.array_equal(self.axis_dirs, robot.axis_dirs)
            and np.array_equal(self.axis_points, robot.axis_points)
            and np.array_equal(self.home, robot.home)
        )


class Effect:
    """Base class of every effect. See the module docstring for the contract."""

    type_name: ClassVar[str] = ""
    #: error on joint j depends only on θ_j (and the context): per-joint compensation works
    separable: ClassVar[bool] = False
    #: contributes joint errors / changes geometry (lets the forward model skip work)
    adds_joint_delta: ClassVar[bool] = False
    changes_geometry: ClassVar[bool] = False
    #: describes the measurement, not the robot (the tracker's pose or scale, where the
    #: target ball sits): fitted with the data, never applied to a program's moves
    measurement_only: ClassVar[bool] = False

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if cls.type_name:
            if cls.type_name in _REGISTRY and _REGISTRY[cls.type_name] is not cls:
                raise TypeError(f"effect type {cls.type_name!r} registered twice")
            _REGISTRY[cls.type_name] = cls

    def __init__(self, name: str | None = None, *, free: bool = True) -> None:
        self.name = name or self.type_name
        self.free = free
        self.uncertainty: np.ndarray | None = None

    # -- parameters -------------------------------------------------------------
    @property
    def param_names(self) -> tuple[str, ...]:
        """Names of the entries of `params()`, units in the name."""
        raise NotImplementedError

    def params(self) -> np.ndarray:
        """The parameter vector (a copy)."""
        raise NotImplementedError

    def set_fitted(self, p: np.ndarray) -> None:
        """Write a parameter vector of the same length back."""
        raise NotImplementedError

    def _check_length(self, p: np.ndarray) -> np.ndarray:
        p = np.asarray(p, dtype=float).ravel()
        if p.shape[0] != len(self.param_names):
            raise ValueError(
                f"{self.name}: {p.shape[0]} parameters given, {len(self.param_names)} expected"
            )
        return p

    # -- contributions ----------------------------------------------------------
    def joint_delta(self, q_cmd: np.ndarray, ctx: Context) -> np.ndarray:
        """Joint errors (N, 6) rad added to the commanded joints (N, 6) rad."""
        return np.zeros_like(np.asarray(q_cmd, dtype=float))

    def joint_delta_derivative(self, q_cmd: np.ndarray, ctx: Context) -> np.ndarray:
        """∂Δθ_j/∂θ_j (N, 6) for separable effects; the general solve uses it if given."""
        return np.zeros_like(np.asarray(q_cmd, dtype=float))

    def apply_geometry(self, geometry: Geometry, q_cmd: np.ndarray, ctx: Context) -> Geometry:
        """The geometry with this effect applied (unchanged by default)."""
        return geometry

    def context_fields(self) -> frozenset[str]:
        """The `Context` fields this effect reads (what a rewrite must know or assume)."""
        return frozenset()

    # -- serialisation ----------------------------------------------------------
    def _state(self) -> dict[str, Any]:
        """JSON data besides the parameter vector (override when there is any)."""
        return {}

    @classmethod
    def _from_state(cls, name: str, state: dict[str, Any]) -> Effect:
        """Build an instance from `_state()` output; parameters are set afterwards."""
        return cls(name)

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON data with a "type" key; `effect_from_dict` reverses it."""
        out: dict[str, Any] = {
            "type": self.type_name,
            "name": self.name,
            "free": self.free,
            "params": dict(zip(self.param_names, self.params().tolist())),
        }
        if self.uncertainty is not None:
            out["uncertainty"] = dict(zip(self.param_names, np.asarray(self.uncertainty).tolist()))
        state = self._state()
        if state:
            out["state"] = state
        return out

    def describe(self) -> str:
        """One line for summaries."""
        return f"{self.name} ({self.type_name}, {len(self.param_names)} parameters)"


def defined_effects() -> dict[str, type[Effect]]:
    """Type name → class of every Effect subclass defined so far (the modules imported);
    `rapidfix.error_model.registry.registered_effects` imports them all first."""
    return dict(_REGISTRY)


def build_effect(data: dict[str, Any], types: dict[str, type[Effect]],
                 where: str = "effect") -> Effect:
    """Rebuild an effect of one of `types` from `to_dict()` output; ModelError names the
    bad key (`rapidfix.error_model.registry.effect_from_dict` passes every registered type)."""
    try:
        kind = data["type"]
        name = data.get("name", kind)
        values = data["params"]
    except (KeyError, TypeError, AttributeError) as err:
        raise ModelError(f"{where}: missing key {err}", column=str(err).strip("'")) from None
    if kind not in types:
        raise ModelError(
            f"{where}: unknown effect type {kind!r}", hint=f"known: {', '.join(sorted(types))}"
        )
    cls = types[kind]
    if not isinstance(values, dict):
        raise ModelError(f"{where}.params: an object of named numbers expected",
                         column="params")
    try:
        state = data.get("state", {})
        _check_finite(state, f"{where}.state")
        effect = cls._from_state(name, state)
        names = effect.param_names
        missing = [n for n in names if n not in values]
        if missing:
            raise ModelError(f"{where}.params: missing {missing[0]!r}", column=missing[0])
        extra = [n for n in values if n not in names]
        if extra:
            raise ModelError(f"{where}.params: unexpected {extra[0]!r} (the effect's state "
                             f"describes {len(names)} parameters, the file holds "
                             f"{len(values)})", column=extra[0])
        effect.set_fitted(np.array([_parameter(values[n], f"{where}.params", n)
                                    for n in names]))
        if "uncertainty" in data:
            unc = data["uncertainty"]
            if not isinstance(unc, dict):
                raise ModelError(f"{where}.uncertainty: an object expected",
                                 column="uncertainty")
            effect.uncertainty = np.array([_parameter(unc[n], f"{where}.uncertainty", n)
                                           for n in names])
        effect.free = bool(data.get("free", True))
    except ModelError:
        raise
    except (KeyError, TypeError, ValueError, IndexError, AttributeError, OverflowError) as err:
        raise ModelError(f"{where}: malformed effect data ({err})") from None
    return effect


#: Largest magnitude of a parameter: ±10 turns for angles (names ending _rad), else 1e6
#: of its unit (mm, ppm, …). Anything larger is a corrupt file, not a robot.
MAX_ABS_RAD = 20.0 * np.pi
MAX_ABS_OTHER = 1e6


def _parameter(value: Any, where: str, name: str) -> float:
    """One parameter value: a finite number within its physical bound."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ModelError(f"{where}: {name!r} is not a number ({value!r})", column=name)
    try:
        x = float(value)
    except OverflowError:
        x = float("inf")
    bound = MAX_ABS_RAD if name.endswith("_rad") else MAX_ABS_OTHER
    if not np.isfinite(x):
        raise ModelError(f"{where}: {name!r} is not a finite number of its unit",
                         column=name)
    if abs(x) > bound:
        raise ModelError(f"{where}: {name!r} = {x:g} is beyond the physical bound "
                         f"±{bound:g}", column=name)
    return x


def _check_finite(value: Any, where: str) -> None:
    """Every number in nested JSON data is finite (json reads NaN and Infinity)."""
    if isinstance(value, float) and not np.isfinite(value):
        raise ModelError(f"{where}: {value!r} is not finite", column=where.rsplit(".", 1)[-1])
    if isinstance(value, dict):
        for key, item in value.items():
            _check_finite(item, f"{where}.{key}")
    elif isinstance(value, list):
        for i, item in enumerate(value):
            _check_finite(item, f"{where}[{i}]")
