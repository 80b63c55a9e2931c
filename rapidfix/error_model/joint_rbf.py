"""Per-joint motion error Δθ_j(θ_j) as a Gaussian radial-basis-function network.

The source paper's model: each joint's error (gear transmission error, offset)
depends on that joint's angle only. One network per joint:

    Δθ(θ) = Σ_k w_k · exp(−(θ − c_k)² / (2σ²)) + a + b·u,   u = (θ − mid) / half-range

Centres c_k are spread evenly over the measured range; the affine part (an
offset and a scale error, both physical) is not penalised, the Gaussian weights
are (ridge regression, smoothing λ). Width σ (as a multiple of the centre
spacing) and λ are chosen by k-fold cross-validation over a grid, with
interleaved folds, which mimics the real use: predicting between sweep points.

Valid range: the measured range [θ_min, θ_max]. Outside it the policy decides:
"clamp" (default) evaluates the network at the nearest edge (Δθ constant,
derivative 0) and warns once per joint with `OutsideRangeWarning`; "refuse"
raises ModelError naming the joint, the angle and the range.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from contextlib import AbstractContextManager
from dataclasses import dataclass, field
from types import ModuleType
from typing import Any, ClassVar

import numpy as np

from rapidfix.compiled import Switch, load_kernel, numpy_only
from rapidfix.error_model import rbf_tables
from rapidfix.error_model.context import Context
from rapidfix.error_model.effect import Effect
from rapidfix.exceptions import ModelError

POLICIES = ("clamp", "refuse")
#: width grid, as multiples of the centre spacing
WIDTH_FACTORS = (0.5, 0.75, 1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 9.0, 13.0)
#: smoothing grid (penalty per data point on the Gaussian weights)
SMOOTHINGS = (1e-8, 1e-6, 1e-4, 1e-3, 1e-2, 1e-1)
MAX_CENTRES = 150
#: valid ranges and widths beyond ±10 turns are not a robot's
MAX_ABS_ANGLE_RAD = 20.0 * np.pi
#: angles this close to the range edge count as inside (rad; far below 1e-9°)
_EDGE_TOL = 1e-12


#: batches smaller than this stay in numpy (a kernel call has a fixed cost)
_COMPILED_FROM = 64
#: batches from this size on read the sums from a table (`rbf_tables`: about a
#: millisecond to make per network, a few ns an angle after): a large program's
#: chunks (`chunks.COMPENSATE`, `chunks.PREDICT`), not a small program's few targets
_TABLE_FROM = 2048
#: a network wider than this many nodes keeps its sums (no valid model comes near)
_TABLE_MAX_NODES = 1 << 17
_COMPILED = Switch("rapidfix_rbf_compiled")


def compiled_sums() -> AbstractContextManager[None]:
    """Inside the block, networks evaluate their Gaussian sums with the compiled kernel
    when numba is installed (`rbf_compiled`), and a large batch's from a table of
    quintics (`rbf_tables`, read by numpy where numba is not installed): the same sums
    to rounding, several times faster. The post-processor turns it on: what it writes
    is rounded far above that level. Outside, the sums are numpy's, so a fitted or
    diagnosed model file is the same bytes with or without numba."""
    return _COMPILED.on()


def _kernel() -> ModuleType | None:
    """The compiled Gaussian sums (`rbf_compiled`), or None: numba not installed, or
    RAPIDFIX_IK_BACKEND=numpy (the environment variable that keeps the IK in numpy
    keeps these sums there too)."""
    return None if numpy_only() else load_kernel("rapidfix.error_model.rbf_compiled")


class OutsideRangeWarning(UserWarning):
    """A joint angle outside the range the model was fitted on was clamped."""


@dataclass
class RBFNetwork:
    """One joint's network. Angles and errors in radians."""

    centres: np.ndarray
    width: float
    lo: float
    hi: float
    smoothing: float
    weights: np.ndarray = field(default_factory=lambda: np.zeros(0))
    cv_rms: float | None = None

    @property
    def n_params(self) -> int:
        """Gaussian weights plus offset and slope."""
        return self.centres.shape[0] + 2

    def _u(self, x: np.ndarray) -> np.ndarray:
        half = max(0.5 * (self.hi - self.lo), 1e-12)
        return (x - 0.5 * (self.hi + self.lo)) / half

    def design(self, x: np.ndarray) -> np.ndarray:
        """Basis matrix (M, K+2) at angles x (M,)."""
        x = np.asarray(x, dtype=float)
        d = x[:, None] - self.centres[None, :]
        gauss = np.exp(-0.5 * (d / self.width) ** 2)
        return np.column_stack([gauss, np.ones_like(x), self._u(x)])

    def design_derivative(self, x: np.ndarray) -> np.ndarray:
        """d(basis)/dx (M, K+2)."""
        x = np.asarray(x, dtype=float)
        d = x[:, None] - self.centres[None, :]
        gauss = -d / self.width**2 * np.exp(-0.5 * (d / self.width) ** 2)
        half = max(0.5 * (self.hi - self.lo), 1e-12)
        return np.column_stack([gauss, np.zeros_like(x), np.full_like(x, 1.0 / half)])

    def fit(self, x: np.ndarray, y: np.ndarray) -> RBFNetwork:
        """Ridge fit of the weights to data (in place); returns self."""
        self.weights = _ridge_solve(self.design(x), y, self.smoothing, self.centres.shape[0])
        return self

    def _scaled_offsets(self, x: np.ndarray) -> np.ndarray:
        """(x - c) / width (M, K), the one large temporary of `value` and `derivative`."""
        d = np.subtract.outer(x, self.centres)
        d *= 1.0 / self.width
        return d

    def _compiled_sums(self, x: np.ndarray, slope: bool | None) -> np.ndarray | None:
        """Σ w_k g_k (slope: Σ w_k g_k d_k; None: both, (2, M)) inside `compiled_sums`: by
        the compiled kernel, a large batch from the network's table (`_table`), which
        numpy reads too where numba is not installed; None for numpy's own sums."""
        if x.shape[0] < _COMPILED_FROM or not _COMPILED.get():
            return None
        kernel = _kernel()
        if kernel is None:
            return self._table_sums(x, slope) if x.shape[0] >= _TABLE_FROM else None
        known = self.__dict__.get("_spacing")  # (centres it was made for, copy, even)
        if known is None or known[0] is not self.centres:
            c = np.ascontiguousarray(self.centres, dtype=float)
            known = self.__dict__["_spacing"] = (self.centres, c, kernel.evenly_spaced(c))
        _, c, even = known
        k = c.shape[0]
        weights = np.ascontiguousarray(self.weights[:k], dtype=float)
        if x.shape[0] >= _TABLE_FROM:
            table = self._table(kernel.sum_tables, weights)
            if table is not None:
                lo, inv_h, value, slopes = table
                out = np.empty((2, x.shape[0]) if slope is None else x.shape[0])
                first, second = (out[0], out[1]) if slope is None else (out, out)
                kernel.table_sums(np.ascontiguousarray(x), lo, inv_h, value, slopes, c,
                                  1.0 / self.width, weights,
                                  2 if slope is None else int(slope), first, second)
                return out
        step = (c[-1] - c[0]) / max(k - 1, 1) / self.width
        if slope is None:
            both = np.empty((2, x.shape[0]))
            kernel.gaussian_sums_both(np.ascontiguousarray(x), c, 1.0 / self.width, weights,
                                      step, even, both[0], both[1])
            return both
        out = np.empty(x.shape[0])
        kernel.gaussian_sums(np.ascontiguousarray(x), c, 1.0 / self.width, weights, step,
                             even, slope, out)
        return out

    def _table(self, make: Callable[..., rbf_tables.Table], weights: np.ndarray
               ) -> rbf_tables.Table | None:
        """The network's table (`rbf_tables`) as `make` makes it (compiled or numpy), made
        on first use and again whenever its centres, width, range or weights have
        changed; None for a range too wide."""
        known = self.__dict__.get("_tables")
        key = (make, self.width, self.lo, self.hi)
        if (known is not None and known[0] is self.centres and known[1] == key
                and np.array_equal(known[2], weights)):
            return known[3]
        nodes = (self.hi - self.lo) / self.width * rbf_tables.TABLE_NODES_PER_WIDTH
        table = (make(self.centres, self.width, weights, self.lo, self.hi)
                 if 0.0 < nodes < _TABLE_MAX_NODES else None)
        self.__dict__["_tables"] = (self.centres, key, weights.copy(), table)
        return table

    def _table_sums(self, x: np.ndarray, slope: bool | None) -> np.ndarray | None:
        """`_compiled_sums` of a large batch from the table in numpy (numba not
        installed); angles off the table take numpy's own sums."""
        k = self.centres.shape[0]
        table = self._table(rbf_tables.sum_tables, self.weights[:k])
        if table is None:
            return None
        lo, inv_h, value, slopes = table
        which = (value, slopes) if slope is None else (slopes if slope else value,)
        out = np.empty((len(which), x.shape[0]))
        for row, pieces in zip(out, which):
            on, row[:] = rbf_tables.table_sums(x, lo, inv_h, pieces)
        if not on.all():
            out[:, ~on] = self._sums(x[~on], slope)
        return out if slope is None else out[0]

    def _sums(self, x: np.ndarray, slope: bool | None) -> np.ndarray:
        """Σ w_k g_k (slope: Σ w_k g_k d_k; None: both, (2, M)), one exp() a term, the
        (M, K) temporaries made in place where they can be."""
        w = self.weights[:self.centres.shape[0]]
        d = self._scaled_offsets(x)
        g = np.square(d, out=d if slope is False else None)
        g *= -0.5
        np.exp(g, out=g)
        sums = g @ w
        if slope is False:
            return sums
        g *= d
        slopes = g @ w
        return slopes if slope else np.stack([sums, slopes])

    def value(self, x: np.ndarray) -> np.ndarray:
        """Δθ at angles already inside the valid range (`design(x) @ weights`, computed
        in place: this runs on every target of every program; compiled or from a table
        inside `compiled_sums`)."""
        x = np.ravel(np.asarray(x, dtype=float))
        k = self.centres.shape[0]
        sums = self._compiled_sums(x, slope=False)
        if sums is None:
            sums = self._sums(x, slope=False)
        return sums + self.weights[k] + self.weights[k + 1] * self._u(x)

    def derivative(self, x: np.ndarray) -> np.ndarray:
        """dΔθ/dθ at angles already inside the valid range (`design_derivative(x) @ weights`)."""
        x = np.ravel(np.asarray(x, dtype=float))
        k = self.centres.shape[0]
        half = max(0.5 * (self.hi - self.lo), 1e-12)
        sums = self._compiled_sums(x, slope=True)
        if sums is None:
            sums = self._sums(x, slope=True)
        return -sums / self.width + self.weights[k + 1] / half

    def value_and_derivative(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """`value(x)` and `derivative(x)` from one pass over the centres (each the same
        numbers as its own call): a Newton step needs both at the same angles."""
        x = np.ravel(np.asarray(x, dtype=float))
        k = self.centres.shape[0]
        half = max(0.5 * (self.hi - self.lo), 1e-12)
        both = self._compiled_sums(x, slope=None)
        if both is None:
            both = self._sums(x, slope=None)
        value = both[0] + self.weights[k] + self.weights[k + 1] * self._u(x)
        return value, -both[1] / self.width + self.weights[k + 1] / half

    def to_dict(self) -> dict[str, Any]:
        """JSON data (weights are the effect's parameters and stored there)."""
        return {
            "centres_rad": self.centres.tolist(),
            "width_rad": self.width,
            "range_rad": [self.lo, self.hi],
            "smoothing": self.smoothing,
            "cv_rms_rad": self.cv_rms,
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> RBFNetwork:
        """Inverse of to_dict (weights zero until set); ModelError for a malformed network.

        A network as `fit_network` makes it: centres strictly increasing, evenly spaced
        from one end of the valid range to the other (so a cut array is caught), the
        range within ±10 turns, a positive width and a non-negative smoothing.
        """
        centres = np.asarray(data["centres_rad"], dtype=float)
        rng = np.asarray(data["range_rad"], dtype=float)
        if rng.shape != (2,) or not np.all(np.isfinite(rng)) or not rng[0] < rng[1] \
                or np.max(np.abs(rng)) > MAX_ABS_ANGLE_RAD:
            raise ModelError(f"range_rad {data['range_rad']!r} is not an interval [lo, hi] "
                             "within ±10 turns", column="range_rad")
        lo, hi = float(rng[0]), float(rng[1])
        if centres.ndim != 1 or not 1 <= centres.shape[0] <= MAX_CENTRES \
                or not np.all(np.isfinite(centres)):
            raise ModelError(f"centres_rad must be 1 to {MAX_CENTRES} finite angles",
                             column="centres_rad")
        expected = np.linspace(lo, hi, centres.shape[0])
        if centres.shape[0] > 1 and not np.allclose(centres, expected, rtol=0.0,
                                                    atol=1e-9 * max(1.0, hi - lo)):
            raise ModelError(f"centres_rad ({centres.shape[0]} values) do not spread evenly "
                             f"over range_rad [{lo:.6g}, {hi:.6g}]: a cut or altered array",
                             column="centres_rad")
        width, smoothing = float(data["width_rad"]), float(data["smoothing"])
        if not (np.isfinite(width) and 0.0 < width <= MAX_ABS_ANGLE_RAD):
            raise ModelError(f"width_rad {width!r} must be a positive angle", column="width_rad")
        if not (np.isfinite(smoothing) and smoothing >= 0.0):
            raise ModelError(f"smoothing {smoothing!r} must be finite and not negative",
                             column="smoothing")
        net = cls(centres, width, lo, hi, smoothing)
        net.weights = np.zeros(net.n_params)
        cv = data.get("cv_rms_rad")
        net.cv_rms = None if cv is None else float(cv)
        if net.cv_rms is not None and not (np.isfinite(net.cv_rms) and net.cv_rms >= 0.0):
            raise ModelError(f"cv_rms_rad {cv!r} must be finite and not negative",
                             column="cv_rms_rad")
        return net


def _ridge_solve(phi: np.ndarray, y: np.ndarray, smoothing: float, n_gauss: int) -> np.ndarray:
    """Least squares with penalty smoothing·M on the Gaussian weights (not the affine part)."""
    m = phi.shape[0]
    penalty = np.zeros(phi.shape[1])
    penalty[:n_gauss] = np.sqrt(smoothing * m)
    a = np.vstack([phi, np.diag(penalty)])
    b = np.concatenate([y, np.zeros(phi.shape[1])])
    import scipy.linalg  # when used: start-up time

    sol, *_ = scipy.linalg.lstsq(a, b, lapack_driver="gelsd")
    return sol


def _ridge_path(
    phi: np.ndarray, y: np.ndarray, smoothings: np.ndarray, n_gauss: int, phi_new: np.ndarray
) -> np.ndarray:
    """Predictions at phi_new (M', S) of the ridge fits for every smoothing at once.

    Same problem as _ridge_solve. The unpenalised affine columns are projected out
    (Frisch–Waugh–Lovell), so one eigendecomposition of the Gaussian block serves
    the whole smoothing path.
    """
    m = phi.shape[0]
    gauss, affine = phi[:, :n_gauss], phi[:, n_gauss:]
    q, r = np.linalg.qr(affine)
    g_res = gauss - q @ (q.T @ gauss)
    y_res = y - q @ (q.T @ y)
    import scipy.linalg  # when used: start-up time

    evals, evecs = scipy.linalg.eigh(g_res.T @ g_res)
    coef = evecs.T @ (g_res.T @ y_res)
    w_gauss = evecs @ (coef[:, None] / (np.maximum(evals, 0.0)[:, None]
                                        + smoothings[None, :] * m))
    w_affine = scipy.linalg.solve_triangular(r, q.T @ (y[:, None] - gauss @ w_gauss))
    return phi_new[:, :n_gauss] @ w_gauss + phi_new[:, n_gauss:] @ w_affine


def centres_for(x: np.ndarray, max_centres: int = MAX_CENTRES) -> np.ndarray:
    """Centres spread evenly over the data range: one per distinct angle, at most max_centres."""
    distinct = np.unique(np.round(np.asarray(x, dtype=float), 12))
    count = int(min(distinct.shape[0], max_centres))
    return np.linspace(distinct[0], distinct[-1], count)


@dataclass(frozen=True)
class CVResult:
    """Cross-validation outcome of one joint: the chosen hyper-parameters and the grid."""

    width_factor: float
    smoothing: float
    cv_rms: float
    grid: np.ndarray  # (len(widths), len(smoothings)) CV RMS, rad


def cross_validate(
    x: np.ndarray,
    y: np.ndarray,
    *,
    width_factors: tuple[float, ...] = WIDTH_FACTORS,
    smoothings: tuple[float, ...] = SMOOTHINGS,
    folds: int = 5,
) -> CVResult:
    """k-fold CV (interleaved folds along θ) over the width × smoothing grid.

    Among settings within 2 % of the best CV RMS, the widest and then the
    smoothest wins: the simplest curve that predicts as well.
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    # folds by the rank of the distinct angle: repeats of one angle stay together
    _, rank = np.unique(x, return_inverse=True)
    fold_of = rank.ravel() % folds
    centres = centres_for(x)
    spacing = (centres[-1] - centres[0]) / max(centres.shape[0] - 1, 1) or 1.0
    grid = np.zeros((len(width_factors), len(smoothings)))
    lams = np.asarray(smoothings, dtype=float)
    for i, factor in enumerate(width_factors):
        net = RBFNetwork(centres, factor * spacing, float(x.min()), float(x.max()), 0.0)
        phi = net.design(x)
        sq = np.zeros(len(smoothings))
        for f in range(folds):
            test = fold_of == f
            pred = _ridge_path(phi[~test], y[~test], lams, centres.shape[0], phi[test])
            sq += np.sum((pred - y[test][:, None]) ** 2, axis=0)
        grid[i] = np.sqrt(sq / x.shape[0])
    best = grid.min()
    ok = grid <= best * 1.02 + 1e-15
    i_best = max(i for i in range(len(width_factors)) if ok[i].any())
    k_best = max(k for k in range(len(smoothings)) if ok[i_best, k])
    return CVResult(width_factors[i_best], smoothings[k_best], float(grid[i_best, k_best]), grid)


#: fewest distinct angles a network is fitted to
MIN_ANGLES = 5


def fit_network(x: np.ndarray, y: np.ndarray, *, folds: int = 5) -> tuple[RBFNetwork, CVResult]:
    """Choose width and smoothing by CV, then fit on all data.

    Fewer distinct angles than MIN_ANGLES is an error; fewer angles than folds
    is cross-validated leave-one-out.
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    distinct = np.unique(x).shape[0]
    if distinct < MIN_ANGLES:
        raise ModelError(
            f"{distinct} distinct measured angles are too few for a cross-validated fit",
            hint=f"measure at least {MIN_ANGLES} angles (better: 5° steps over the range)",
        )
    folds = min(folds, distinct)
    cv = cross_validate(x, y, folds=folds)
    centres = centres_for(x)
    spacing = (centres[-1] - centres[0]) / max(centres.shape[0] - 1, 1) or 1.0
    net = RBFNetwork(centres, cv.width_factor * spacing, float(x.min()), float(x.max()),
                     cv.smoothing)
    net.fit(x, y)
    net.cv_rms = cv.cv_rms
    return net, cv


class JointRBF(Effect):
    """The per-joint transmission error: six independent RBF networks (None = not modelled)."""

    type_name: ClassVar[str] = "joint_rbf"
    separable: ClassVar[bool] = True
    adds_joint_delta: ClassVar[bool] = True

    def __init__(
        self,
        networks: list[RBFNetwork | None] | None = None,
        name: str | None = None,
        *,
        policy: str = "clamp",
        free: bool = True,
    ) -> None:
        super().__init__(name, free=free)
        if policy not in POLICIES:
            raise ModelError(f"unknown out-of-range policy {policy!r}", hint="clamp or refuse")
        self.networks: list[RBFNetwork | None] = list(networks or [None] * 6)
        self.policy = policy
        self._warned: set[int] = set()

    @property
    def param_names(self) -> tuple[str, ...]:
        """j<J>_w<k>_rad for the Gaussian weights, j<J>_offset_rad, j<J>_slope_rad."""
        names: list[str] = []
        for j, net in enumerate(self.networks):
            if net is None:
                continue
            names += [f"j{j + 1}_w{k:03d}_rad" for k in range(net.centres.shape[0])]
            names += [f"j{j + 1}_offset_rad", f"j{j + 1}_slope_rad"]
        return tuple(names)

    def params(self) -> np.ndarray:
        """All networks' weights, joint by joint."""
        parts = [net.weights for net in self.networks if net is not None]
        return np.concatenate(parts) if parts else np.zeros(0)

    def set_fitted(self, p: np.ndarray) -> None:
        """Write the weights back, joint by joint."""
        p = self._check_length(p)
        start = 0
        for net in self.networks:
            if net is not None:
                net.weights = p[start : start + net.n_params].copy()
                start += net.n_params

    def reset_warnings(self) -> None:
        """Warn again (once per joint) from now on, e.g. for the next file of a batch."""
        self._warned.clear()

    @property
    def valid_range(self) -> np.ndarray:
        """(6, 2) rad; NaN rows for joints without a network."""
        out = np.full((6, 2), np.nan)
        for j, net in enumerate(self.networks):
            if net is not None:
                out[j] = (net.lo, net.hi)
        return out

    def _inside(self, j: int, net: RBFNetwork, x: np.ndarray) -> np.ndarray:
        """x clamped into the valid range, applying the out-of-range policy."""
        outside = (x < net.lo - _EDGE_TOL) | (x > net.hi + _EDGE_TOL)
        if outside.any():
            worst = float(x[outside][np.argmax(np.abs(x[outside] - 0.5 * (net.lo + net.hi)))])
            message = (
                f"joint {j + 1} at {np.degrees(worst):.3f}° is outside the range the model was "
                f"fitted on [{np.degrees(net.lo):.3f}°, {np.degrees(net.hi):.3f}°]"
            )
            if self.policy == "refuse":
                raise ModelError(message, hint="measure that range or use policy 'clamp'")
            if j not in self._warned:
                self._warned.add(j)
                warnings.warn(message + "; the error at the edge is used", OutsideRangeWarning,
                              stacklevel=3)
        return np.clip(x, net.lo, net.hi)

    def joint_delta(self, q_cmd: np.ndarray, ctx: Context) -> np.ndarray:
        """Δθ (N, 6) rad from each joint's network (zero for unmodelled joints)."""
        q = np.atleast_2d(np.asarray(q_cmd, dtype=float))
        out = np.zeros_like(q)
        for j, net in enumerate(self.networks):  # six joints, vectorised over poses
            if net is not None:
                out[:, j] = net.value(self._inside(j, net, q[:, j]))
        return out

    def joint_delta_derivative(self, q_cmd: np.ndarray, ctx: Context) -> np.ndarray:
        """dΔθ_j/dθ_j (N, 6); zero outside the valid range (clamped) and for unmodelled joints."""
        q = np.atleast_2d(np.asarray(q_cmd, dtype=float))
        out = np.zeros_like(q)
        for j, net in enumerate(self.networks):
            if net is not None:
                x = q[:, j]
                inside = (x >= net.lo) & (x <= net.hi)
                out[:, j] = np.where(inside, net.derivative(np.clip(x, net.lo, net.hi)), 0.0)
        return out

    def joint_delta_and_derivative(self, q_cmd: np.ndarray,
                                   ctx: Context) -> tuple[np.ndarray, np.ndarray]:
        """`joint_delta` and `joint_delta_derivative` at once (one pass per network)."""
        q = np.atleast_2d(np.asarray(q_cmd, dtype=float))
        out = np.zeros_like(q)
        slope = np.zeros_like(q)
        for j, net in enumerate(self.networks):
            if net is not None:
                x = q[:, j]
                inside = (x >= net.lo) & (x <= net.hi)
                value, derivative = net.value_and_derivative(self._inside(j, net, x))
                out[:, j] = value
                slope[:, j] = np.where(inside, derivative, 0.0)
        return out, slope

    def _state(self) -> dict[str, Any]:
        return {
            "policy": self.policy,
            "networks": [None if n is None else n.to_dict() for n in self.networks],
        }

    @classmethod
    def _from_state(cls, name: str, state: dict[str, Any]) -> JointRBF:
        nets = state["networks"]
        if not isinstance(nets, list) or len(nets) != 6:
            raise ValueError("state.networks must be a list of 6 networks (or null)")
        networks: list[RBFNetwork | None] = []
        for j, n in enumerate(nets):
            try:
                networks.append(None if n is None else RBFNetwork.from_dict(n))
            except ModelError as err:
                raise ModelError(f"joint {j + 1} network: {err.message}",
                                 column=f"networks[{j}].{err.column}") from None
        return cls(networks, name, policy=state.get("policy", "clamp"))

    def describe(self) -> str:
        """One line: which joints are modelled."""
        joints = [str(j + 1) for j, n in enumerate(self.networks) if n is not None]
        return f"{self.name} (Gaussian RBF per joint, joints {','.join(joints) or 'none'})"
