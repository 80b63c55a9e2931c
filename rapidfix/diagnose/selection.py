"""Which effects explain the residual: fit on calibration, judge on validation, add greedily.

Every model here is fitted on the calibration points only; the validation points
are only ever predicted. Starting from the given model with its tracker frame and
its joint offsets and first harmonics re-referenced on the calibration set
(`rapidfix.error_model.candidates.joint_reference`), each round tries every
remaining candidate (added to what was accepted so far, everything refitted) and
accepts the best one that passes all three tests:

1. **Penalised fit (BIC).** With n calibration coordinates, residual sum of squares
   RSS and k effective parameters, BIC = n ln(RSS/n) + k ln n. The candidate must
   lower it by more than `BIC_MARGIN` (10: "very strong" evidence), after a charge
   of 2 ln(v) for having picked the best of v variants (which joint pair couples).
2. **Prediction.** On the validation points the residual must lean, significantly,
   the way the candidate moves the predictions: a t test of the per-point products
   of residual and predicted change (or, if larger, a signed-rank test of them) with
   z ≥ `Z_MIN` (3), so a change that fitted noise could make is not enough
   (`validation_z`). It is the score test of the candidate on points it never saw;
   testing the per-point fall of the squared
   error instead has half its signal to the same noise and misses a real second
   effect that is small next to the noise (test 3 judges how much the error falls).
3. **Relevance.** The reduction must be at least `SHARE_MIN` (20 %) of the mean
   squared validation residual, so a flexible effect nibbling at a cause it does
   not describe is not taken, and nothing is taken from a residual that is
   already noise (no model can remove a fifth of the noise on points it never saw).
   (The share of the residual *above* the noise is reported too; it needs a noise
   level, and the one from the sweeps is inflated by the very effects looked for.)

Rounds continue until no candidate passes, so effects present together are found
one after the other. Parameters the data cannot separate from those already in
the model add nothing to the rank and are never accepted twice. Because a
flexible candidate can stand in for two simple causes at once (link geometry
spans a tool offset and a tracker scale), a round won by one candidate looks one
step ahead: two simpler ones that together pass and beat it by the BIC margin are
accepted instead (`simpler_pair`).

When a round has no passing candidate but the validation residual is still above
the noise floor, the non-parametric fallback (`rapidfix.diagnose.fallback`: a
cross-validated RBF correction of one joint over the joints the residual follows)
is fitted and judged by the same three tests, charged for every setting it
searched; it is tried once. It is also tried in a round whose winner leaves the
validation residual above `FLOOR_CLEAR` × the noise floor: when the correction
brings it to the floor and gains more than `BIC_MARGIN` over the winner, the
winner is not named (a cause that explains only part of what a correction of
unknown cause explains is not the cause).
"""

from __future__ import annotations

import copy
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.stats import norm, wilcoxon

from rapidfix.diagnose.candidate_builders import CANDIDATES, REPEATABLE, Candidate, Setting, build
from rapidfix.diagnose.data import MEAN_NORM_PER_SIGMA
from rapidfix.diagnose.fallback import PHYSICS as FALLBACK_PHYSICS
from rapidfix.diagnose.fallback import Proposal, propose
from rapidfix.diagnose.residuals import Residuals, residuals
from rapidfix.diagnose.structured import Screened, screen
from rapidfix.error_model import (
    Effect,
    EffectsFit,
    ErrorModel,
    JointReference,
    MeasuredPoints,
    OutsideRangeWarning,
    TrackerFrame,
    fit_free_effects,
)
from rapidfix.kinematics import RobotModel
from rapidfix.measure import rigid_fit

BIC_MARGIN = 10.0
Z_MIN = 3.0
SHARE_MIN = 0.2
#: at most this many rounds (structured effects may be accepted more than once)
MAX_ROUNDS = 8
#: the fallback is tried only on a validation residual above this × the noise floor
FALLBACK_FROM = 1.25
#: a winner leaving the validation residual above this × the floor may give way to it
FLOOR_CLEAR = 1.5
#: the fallback's kind, as trials and the report name it
FALLBACK = "rbf_correction"


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
    #: for a pair look-ahead, the candidate this one was tried on top of
    after: str = ""

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
    #: what the final residual correlates with: joint × driver variants, best first
    ranking: list[Screened] = field(default_factory=list)
    #: the fallback's search (settings by cross-validation), when it was tried
    fallback: Proposal | None = None

    @property
    def floor_mm(self) -> float:
        """Expected mean |residual| from measurement noise alone (mm)."""
        return MEAN_NORM_PER_SIGMA * self.noise_sigma_mm


def _fit(model: ErrorModel, robot: RobotModel, cal: MeasuredPoints, val: MeasuredPoints) -> Stage:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", OutsideRangeWarning)
        fit = fit_free_effects(model, robot, cal)
    return Stage(model, fit, residuals(model, robot, cal), residuals(model, robot, val))


def initial_frame(model: ErrorModel, robot: RobotModel, cal: MeasuredPoints) -> TrackerFrame:
    """Tracker pose from a rigid fit of the model's predictions to the calibration points."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", OutsideRangeWarning)
        p = model.predict_ball(robot, cal.q, cal.row_balls_mm, cal.ctx)
    R, t = rigid_fit(p, cal.xyz)
    return TrackerFrame.from_pose(R, t)


def starting_stages(model: ErrorModel, robot: RobotModel, cal: MeasuredPoints,
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
    trial.z = validation_z(current.validation, stage.validation)
    trial.share = _share(trial, noise_sigma_mm)
    total = float(np.mean(current.validation.norms**2))
    trial.explained = float(d.mean() / total) if total > 0 else 0.0
    problems = []
    if trial.added_rank <= 0:
        problems.append("adds nothing the model does not already have")
    if not trial.delta_bic > BIC_MARGIN:
        problems.append(f"BIC gain {trial.delta_bic:.1f} ≤ {BIC_MARGIN:g}")
    if not trial.z >= Z_MIN:
        problems.append(f"validation change not significant (z = {trial.z:.1f} < "
                        f"{Z_MIN:g})")
    if not trial.explained >= SHARE_MIN:
        problems.append(f"explains {100 * max(trial.explained, 0):.0f} % of the validation "
                        f"residual (< {100 * SHARE_MIN:.0f} %)")
    trial.verdict = "; ".join(problems) if problems else "passes"


def validation_z(before: Residuals, after: Residuals) -> float:
    """z of the projection of the validation residual on the change the candidate predicts.

    Per point, c = r·Δ with r the residual before and Δ = r − r' how far the candidate
    moves the prediction. If the change is fitted noise, r (noise on points never
    fitted) is independent of Δ and c averages zero; if the candidate describes
    something real, r leans the way Δ points. The t statistic of c tests just that.
    (The per-point fall of the squared error, |r|² − |r'|² = 2c − |Δ|², has the noise
    of 2c but, for a right candidate, only half its mean: it needs four times the
    points to see the same effect. How much the error falls is the relevance test's.)

    A t statistic is weak when one point carries most of the signal (heavy tails give
    a large spread). Under the same null hypothesis c is symmetric about zero, so the
    Wilcoxon signed-rank test is valid too and is not swayed by one point; the larger of
    the two z values is taken (both tests see the same data, so the false alarm rate
    at most doubles: about 0.3 % at z = 3, and the BIC and relevance tests still hold).
    """
    r = before.vectors
    c = np.einsum("ij,ij->i", r, r - after.vectors)
    spread = float(np.std(c, ddof=1)) if c.size > 1 else 0.0
    z_t = float(c.mean() / (spread / np.sqrt(c.size))) if spread > 0 else 0.0
    if c.size < 10 or not np.any(c != 0.0):
        return z_t
    p = float(wilcoxon(c, alternative="greater").pvalue)
    z_rank = float(norm.isf(p)) if p > 0.0 else float("inf")
    return max(z_t, z_rank)


def _try(kind: str, current: Stage, setting: Setting, val: MeasuredPoints,
         noise_sigma_mm: float, round_no: int) -> Trial:
    """Candidate `kind` added to the current stage, fitted and judged."""
    cand: Candidate = build(kind, current.model, setting)
    trial = Trial(cand.kind, cand.physics, round_no, cand.detail, cand.reason, cand.variants)
    if cand.effect is None:
        trial.verdict = f"not tried: {cand.reason}"
        return trial
    trial_model = copy.deepcopy(current.model)
    trial_model.effects.append(cand.effect)
    trial.stage = _fit(trial_model, setting.robot, setting.calibration, val)
    trial.previous = current
    judge(trial, current, noise_sigma_mm)
    return trial


def simpler_pair(best: Trial, tried: Sequence[Trial], setting: Setting, val: MeasuredPoints,
                 noise_sigma_mm: float) -> tuple[list[Trial], list[Trial]]:
    """Two simpler effects that together beat the round's most flexible winner, if any.

    Greedy selection takes the largest BIC gain; a flexible candidate (link geometry
    spans a tool offset and a scale) can win a round with one acceptance where two
    simple causes are at work. So when the winner adds more parameters than a pair
    would, each passing simpler candidate A is tried with each other candidate B on
    top (together fewer parameters than the winner). A + B replace the winner when B
    passes all three tests on top of A and the pair's BIC gain beats the winner's by
    more than `BIC_MARGIN`. Returns the trials of B made on the way, and the effects
    to accept: the pair (A, B) or the winner alone.
    """
    made: list[Trial] = []
    choice: tuple[Trial, Trial] | None = None
    gain = best.delta_bic + BIC_MARGIN
    for first in tried:
        if first is best or first.verdict != "passes" or first.added_rank >= best.added_rank:
            continue
        assert first.stage is not None
        for other in tried:
            if (other.stage is None or other.kind in (best.kind, first.kind)
                    or first.added_rank + max(other.added_rank, 1) >= best.added_rank):
                continue
            second = _try(other.kind, first.stage, setting, val, noise_sigma_mm, best.round)
            second.after = first.kind
            second.detail = f"on top of {first.kind} (pair look-ahead) {second.detail}".strip()
            made.append(second)
            if second.verdict == "passes" and first.delta_bic + second.delta_bic > gain:
                choice, gain = (first, second), first.delta_bic + second.delta_bic
    return made, [best] if choice is None else list(choice)


def try_fallback(current: Stage, setting: Setting, val: MeasuredPoints,
                 noise_sigma_mm: float, round_no: int) -> tuple[Trial, Proposal]:
    """The fallback's proposal on the current stage, fitted and judged like a candidate."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", OutsideRangeWarning)
        proposal = propose(current.model, setting.robot, setting.calibration)
    trial = Trial(FALLBACK, FALLBACK_PHYSICS, round_no, proposal.detail, proposal.reason,
                  proposal.variants)
    if proposal.effect is None:
        trial.verdict = f"not tried: {proposal.reason}"
        return trial, proposal
    trial_model = copy.deepcopy(current.model)
    trial_model.effects.append(proposal.effect)
    trial.stage = _fit(trial_model, setting.robot, setting.calibration, val)
    trial.previous = current
    judge(trial, current, noise_sigma_mm)
    effect = trial.stage.model.effects[-1]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", OutsideRangeWarning)
        size = effect.joint_delta(setting.calibration.q, setting.calibration.ctx)
    effect.cv["rms_deg"] = float(np.degrees(np.sqrt(np.mean(size[:, effect.joint] ** 2))))
    return trial, proposal


def select(model: ErrorModel, robot: RobotModel, cal: MeasuredPoints, val: MeasuredPoints, *,
           default_payload_kg: float, noise_sigma_mm: float,
           candidates: Sequence[str] = CANDIDATES,
           progress: Callable[[str], None] | None = None) -> Selection:
    """Greedy forward selection of candidate effects (see the module docstring)."""
    before, baseline = starting_stages(model, robot, cal, val)
    sel = Selection(before, baseline, noise_sigma_mm=noise_sigma_mm)
    setting = Setting(robot, cal, default_payload_kg)
    current = baseline
    remaining = list(candidates)
    # the fallback needs the ranking of the structured search; it is tried at most once
    fallback_open = any(kind in REPEATABLE for kind in candidates)
    round_no = 0
    while remaining and round_no < MAX_ROUNDS:
        round_no += 1
        tried: list[Trial] = []
        for kind in remaining:
            if progress:
                progress(f"round {round_no}: {kind}")
            tried.append(_try(kind, current, setting, val, noise_sigma_mm, round_no))
        sel.trials.extend(tried)
        passing = [t for t in tried if t.verdict == "passes"]
        floor = MEAN_NORM_PER_SIGMA * noise_sigma_mm
        if not passing:
            if not fallback_open or current.validation.mean_mm <= FALLBACK_FROM * floor:
                break
            if progress:
                progress(f"round {round_no}: {FALLBACK}")
            fallback, sel.fallback = try_fallback(current, setting, val, noise_sigma_mm,
                                                  round_no)
            fallback_open = False
            sel.trials.append(fallback)
            if fallback.verdict != "passes":
                break
            passing = [fallback]
        best = prefer_physical(max(passing, key=lambda t: t.delta_bic), passing)
        ahead, chosen = simpler_pair(best, tried, setting, val, noise_sigma_mm)
        sel.trials.extend(ahead)
        if best not in chosen:
            best.verdict = (f"passes, but {' + '.join(t.kind for t in chosen)} gain more BIC "
                            "with fewer parameters (pair look-ahead)")
        if fallback_open and best.kind != FALLBACK:
            last = chosen[-1].stage
            assert last is not None
            if last.validation.mean_mm > FLOOR_CLEAR * floor:
                if progress:
                    progress(f"round {round_no}: {FALLBACK} (against {best.kind})")
                fallback, proposal = try_fallback(current, setting, val, noise_sigma_mm,
                                                  round_no)
                sel.trials.append(fallback)
                gain = sum(t.delta_bic for t in chosen)
                if (fallback.verdict == "passes" and fallback.stage is not None
                        and fallback.stage.validation.mean_mm <= FLOOR_CLEAR * floor
                        and fallback.delta_bic > gain + BIC_MARGIN):
                    for t in chosen:
                        t.verdict = (f"passes, but leaves the validation residual above "
                                     f"{FLOOR_CLEAR:g}× the noise floor where the correction "
                                     "of unknown cause brings it there with more than "
                                     f"{BIC_MARGIN:g} more BIC gain: not named")
                    chosen = [fallback]
                    sel.fallback = proposal
                    fallback_open = False
        for trial in chosen:
            trial.accepted = True
            trial.verdict = "accepted"
            sel.accepted.append(trial)
            assert trial.stage is not None
            current = trial.stage
            if trial.kind not in REPEATABLE and trial.kind in remaining:
                remaining.remove(trial.kind)
    sel.final = current if sel.accepted else before
    refine_noise(sel, current)
    if any(kind in REPEATABLE for kind in candidates):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", OutsideRangeWarning)
            sel.ranking = screen(current.model, robot, cal, default_payload_kg)
    return sel


def prefer_physical(best: Trial, passing: Sequence[Trial]) -> Trial:
    """The round's winner, or a physical candidate that explains the data about as well.

    A structured effect (a joint and a driver) that wins a round by no more than
    `BIC_MARGIN` over a passing physical candidate gives way to it: the physical
    cause is the better-founded description, and the report says both fit.
    """
    if best.kind not in REPEATABLE:
        return best
    physical = [t for t in passing if t.kind not in REPEATABLE
                and best.delta_bic - t.delta_bic <= BIC_MARGIN]
    if not physical:
        return best
    chosen = max(physical, key=lambda t: t.delta_bic)
    best.verdict = (f"passes, explains it about as well as {chosen.kind} (BIC within "
                    f"{BIC_MARGIN:g}); the physical candidate is preferred")
    return chosen


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
