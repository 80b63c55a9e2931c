"""Which effects explain the residual: fit on calibration, judge on validation, add greedily.

Every model here is fitted on the calibration points only; the validation points
are only ever predicted. Starting from the given model with its tracker frame and
its joint offsets and first harmonics re-referenced on the calibration set
(`rapidfix.errors.candidates.joint_reference`), each round tries every
remaining candidate (added to what was accepted so far, everything refitted) and
accepts the best one that passes all three tests:

1. **Penalised fit (BIC).** With n calibration coordinates, residual sum of squares
   RSS and k effective parameters, BIC = n ln(RSS/n) + k ln n. The candidate must
   lower it by more than `BIC_MARGIN` (10: "very strong" evidence), after a charge
   of 2 ln(v) for having picked the best of v variants (which joint pair couples).
2. **Prediction.** On the validation points the squared residual must fall, point
   by point, significantly: a paired test of the per-point reductions with
   z ≥ `Z_MIN` (3), so an improvement that noise could make is not enough.
3. **Relevance.** The reduction must be at least `SHARE_MIN` (20 %) of the mean
   squared validation residual, so a flexible effect nibbling at a cause it does
   not describe is not taken, and nothing is taken from a residual that is
   already noise (no model can remove a fifth of the noise on points it never saw).
   (The share of the residual *above* the noise is reported too; it needs a noise
   level, and the one from the sweeps is inflated by the very effects looked for.)

Rounds continue until no candidate passes, so effects present together are found
one after the other. Parameters the data cannot separate from those already in
the model add nothing to the rank and are never accepted twice.
"""

from __future__ import annotations

import copy
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rapidfix.diagnose.candidates import CANDIDATES, Candidate, Setting, build
from rapidfix.diagnose.data import MEAN_NORM_PER_SIGMA
from rapidfix.diagnose.residuals import Residuals, residuals
from rapidfix.errors.candidates.joint_reference import JointReference
from rapidfix.errors.candidates.registration import TrackerFrame
from rapidfix.errors.effect import Effect
from rapidfix.errors.fit_effects import EffectsFit, MeasuredPoints, fit_free_effects
from rapidfix.errors.joint_rbf import OutsideRangeWarning
from rapidfix.errors.model import ErrorModel
from rapidfix.measure.registration import rigid_fit

BIC_MARGIN = 10.0
Z_MIN = 3.0
SHARE_MIN = 0.2


@dataclass
class Stage:
    """A fitted model and its residuals on both sets."""

    model: ErrorModel
    fit: EffectsFit
    calibration: Residuals
    validation: Residuals

    @property
    def bic(self) -> float:
        """n ln(RSS/n) + k ln n on the calibration coordinates."""
        n = self.fit.n_obs
        return float(n * np.log(max(self.fit.rss, 1e-300) / n) + self.fit.rank * np.log(n))


@dataclass
class Trial:
    """One candidate tried in one round, with its evidence and the verdict."""

    kind: str
    physics: str
    round: int
    detail: str = ""
    reason: str = ""
    variants: int = 1
    stage: Stage | None = None
    previous: Stage | None = None
    added_rank: int = 0
    delta_bic: float = float("nan")
    z: float = float("nan")
    share: float = float("nan")
    explained: float = float("nan")
    accepted: bool = False
    verdict: str = ""

    @property
    def effect(self) -> Effect | None:
        """The fitted effect (the last one of the trial's model)."""
        return None if self.stage is None else self.stage.model.effects[-1]


@dataclass
class Selection:
    """Every stage of the diagnosis: before, baseline, each trial, the final model."""

    before: Stage
    baseline: Stage
    trials: list[Trial] = field(default_factory=list)
    accepted: list[Trial] = field(default_factory=list)
    final: Stage | None = None
    noise_sigma_mm: float = 0.0
    noise_refined: bool = False

    @property
    def floor_mm(self) -> float:
        """Expected mean |residual| from measurement noise alone (mm)."""
        return MEAN_NORM_PER_SIGMA * self.noise_sigma_mm


def _fit(model: ErrorModel, robot: Any, cal: MeasuredPoints, val: MeasuredPoints) -> Stage:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", OutsideRangeWarning)
        fit = fit_free_effects(model, robot, cal)
    return Stage(model, fit, residuals(model, robot, cal), residuals(model, robot, val))


def initial_frame(model: ErrorModel, robot: Any, cal: MeasuredPoints) -> TrackerFrame:
    """Tracker pose from a rigid fit of the model's predictions to the calibration points."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", OutsideRangeWarning)
        p = model.predict_ball(robot, cal.q, cal.ball_mm, cal.ctx)
    R, t = rigid_fit(p, cal.xyz)
    return TrackerFrame.from_pose(R, t)


def starting_stages(model: ErrorModel, robot: Any, cal: MeasuredPoints,
                    val: MeasuredPoints) -> tuple[Stage, Stage]:
    """The given model with its tracker frame fitted (before), and re-referenced (baseline)."""
    frozen = copy.deepcopy(model)
    for eff in frozen.effects:
        eff.free = False
    frozen.effects.append(initial_frame(frozen, robot, cal))
    before = _fit(frozen, robot, cal, val)
    referenced = copy.deepcopy(before.model)
    referenced.effects.append(JointReference())
    return before, _fit(referenced, robot, cal, val)


def judge(trial: Trial, current: Stage, noise_sigma_mm: float) -> None:
    """Fill in the trial's evidence and verdict against the current stage."""
    stage = trial.stage
    assert stage is not None
    trial.added_rank = stage.fit.rank - current.fit.rank
    trial.delta_bic = (current.bic - stage.bic) - 2.0 * np.log(trial.variants)
    d = current.validation.norms**2 - stage.validation.norms**2
    spread = float(np.std(d, ddof=1)) if d.size > 1 else 0.0
    trial.z = float(d.mean() / (spread / np.sqrt(d.size))) if spread > 0 else 0.0
    trial.share = _share(trial, noise_sigma_mm)
    total = float(np.mean(current.validation.norms**2))
    trial.explained = float(d.mean() / total) if total > 0 else 0.0
    problems = []
    if trial.added_rank <= 0:
        problems.append("adds nothing the model does not already have")
    if not trial.delta_bic > BIC_MARGIN:
        problems.append(f"BIC gain {trial.delta_bic:.1f} ≤ {BIC_MARGIN:g}")
    if not trial.z >= Z_MIN:
        problems.append(f"validation gain not significant (z = {trial.z:.1f} < {Z_MIN:g})")
    if not trial.explained >= SHARE_MIN:
        problems.append(f"explains {100 * max(trial.explained, 0):.0f} % of the validation "
                        f"residual (< {100 * SHARE_MIN:.0f} %)")
    trial.verdict = "; ".join(problems) if problems else "passes"


def select(model: ErrorModel, robot: Any, cal: MeasuredPoints, val: MeasuredPoints, *,
           default_payload_kg: float, noise_sigma_mm: float,
           candidates: Sequence[str] = CANDIDATES,
           progress: Callable[[str], None] | None = None) -> Selection:
    """Greedy forward selection of candidate effects (see the module docstring)."""
    before, baseline = starting_stages(model, robot, cal, val)
    sel = Selection(before, baseline, noise_sigma_mm=noise_sigma_mm)
    setting = Setting(robot, cal, default_payload_kg)
    current = baseline
    remaining = list(candidates)
    round_no = 0
    while remaining:
        round_no += 1
        passing: list[Trial] = []
        for kind in remaining:
            if progress:
                progress(f"round {round_no}: {kind}")
            cand: Candidate = build(kind, current.model, setting)
            trial = Trial(cand.kind, cand.physics, round_no, cand.detail, cand.reason,
                          cand.variants)
            sel.trials.append(trial)
            if cand.effect is None:
                trial.verdict = f"not tried: {cand.reason}"
                continue
            trial_model = copy.deepcopy(current.model)
            trial_model.effects.append(cand.effect)
            trial.stage = _fit(trial_model, robot, cal, val)
            trial.previous = current
            judge(trial, current, noise_sigma_mm)
            if trial.verdict == "passes":
                passing.append(trial)
        if not passing:
            break
        best = max(passing, key=lambda t: t.delta_bic)
        best.accepted = True
        best.verdict = "accepted"
        sel.accepted.append(best)
        assert best.stage is not None
        current = best.stage
        remaining.remove(best.kind)
    sel.final = current if sel.accepted else before
    refine_noise(sel, current)
    return sel


def _share(trial: Trial, noise_sigma_mm: float) -> float:
    if trial.stage is None or trial.previous is None:
        return float("nan")
    d = trial.previous.validation.norms**2 - trial.stage.validation.norms**2
    excess = float(np.mean(trial.previous.validation.norms**2)) - 3.0 * noise_sigma_mm**2
    return float(d.mean() / excess) if excess > 0 else 0.0


def refine_noise(sel: Selection, best: Stage) -> None:
    """Take the smaller of the given noise level and the best model's calibration scatter.

    The sweeps' scatter overstates the noise when a hidden effect distorted the
    sweeps; the residual of the model that explains the data best, per coordinate
    and corrected for its parameters, is then the better estimate. The shares of
    the residual above noise are recomputed with it.
    """
    fit = best.fit
    scatter = float(np.sqrt(fit.rss / max(fit.n_obs - fit.rank, 1)))
    if scatter < sel.noise_sigma_mm:
        sel.noise_sigma_mm = scatter
        sel.noise_refined = True
    for trial in sel.trials:
        trial.share = _share(trial, sel.noise_sigma_mm)
