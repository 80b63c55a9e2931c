"""The true errors of a virtual robot: what the fitter has to find, drawn from a seed.

Written independently of `rapidfix.error_model` on purpose: the simulator is the truth
the error model is judged against, so it shares no code with it.

Always present: a per-joint, angle-dependent error Δθ_j(θ_j) = offset + Σ gear
harmonics, 0.005–0.05° in size. Optional effects (names as `rapidfix diagnose`
uses them):

- ``joint_compliance``: joints 2 and 3 deflect by compliance × gravity torque of the
  links and the payload, the torque taken in the arm's actual configuration;
- ``link_geometry``: axis points, axis directions (joints 2–6) and tool0's home
  pose differ from the nominal model;
- ``backlash``: joints 1–3 lag by half their backlash against the direction they
  last moved;
- ``thermal_drift``: the arm grows by α·(T − T_ref) as it warms up over time;
- ``tool_offset``: the target ball is not where setup.toml says;
- ``joint_coupling``: one joint's error depends on another joint's angle;
- ``registration_scale``: the tracker's length scale is off by some ppm.

Effects the diagnosis has no ready-made candidate for (issue #14: it must trace
them by the joint they act on and what drives them):

- ``wrist_compliance``: joint 4 or 5 deflects under the gravity torque of the tool
  body and the payload about its own axis (a soft wrist gearbox);
- ``encoder_thermal``: the angle scale of one of joints 1–3 grows with the arm's
  temperature (an encoder or gear ratio that drifts as the drive warms); the sweeps
  are taken cold, then the work cycle starts (at `cycle_start_s`, the session's
  points) and the arm's temperature swings by a few kelvin with it;
- ``direction_zero_shift``: one joint's zero shifts with the direction another
  joint last moved (a wrist gear train or a dress pack that pulls on the next axis);
- ``joint_coupling2``: one joint's error follows the second harmonic of another
  joint's angle (an elliptic bearing or gear, twice per turn).

Effects that act where no joint error can (issue #14, frames: tool, base, link):

- ``tool_bending``: the tool bends at a compliant mount (a tool changer, a slender
  adapter) under the gravity moment of its own body and the payload about a hinge
  on the flange axis; bending only, the mount is stiff in torsion. Everything on
  the flange (the target ball, every tool) turns with it;
- ``base_tilt``: a compliant foundation: the base tilts about horizontal axes
  through a pivot below the base origin, in proportion to the overturning moment of
  the arm's links and the payload about the base;
- ``link_thermal``: one link (the lower or the upper arm) grows by α·L·ΔT (α of
  steel) as the drive next to it warms up once the work cycle starts (at
  `cycle_start_s`, the session's points; the sweeps are taken cold).
An effect that neither a candidate nor one joint and one driver describes (issue #14,
section 2: only a smooth correction over several joints can follow it):

- ``hose_pull``: the dress pack pulls on joint 5 as the forearm (joint 4) and the
  wrist (joint 6) twist it together: A · sin θ4 · sin θ6 (A 0.03–0.05°). The sweeps
  hold joints 4 and 6 at 0, so no sweep sees it, and its average over either angle
  alone is about zero, so no function of one joint's angle describes it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from rapidfix.kinematics import RobotModel

EFFECTS: tuple[str, ...] = (
    "joint_compliance",
    "link_geometry",
    "backlash",
    "thermal_drift",
    "tool_offset",
    "joint_coupling",
    "registration_scale",
    "wrist_compliance",
    "encoder_thermal",
    "direction_zero_shift",
    "joint_coupling2",
    # -- issue #14, frames (tool, base, link) --
    "tool_bending",
    "base_tilt",
    "link_thermal",
    "hose_pull",
)

GRAVITY = np.array([0.0, 0.0, -9.81])  # m/s², base z is up
# Lumped mass model of an IRB 1600-class arm (kg): link 2 (lower arm), link 3
# (upper arm), the wrist; each body's centre of mass lies a fraction of the way
# between two joint-axis points of the current pose: (body, from joint, to, fraction).
LINK_MASSES_KG = {"lower_arm": 17.0, "upper_arm": 21.0, "wrist": 6.0}
_BODIES = (("lower_arm", 1, 2, 0.5), ("upper_arm", 2, 4, 0.4), ("wrist", 4, 4, 0.0))


@dataclass
class JointErrors:
    """Per joint: Δθ(θ) = offset + Σ_k amp_k sin(order_k θ + phase_k), all rad."""

    offset: np.ndarray  # (6,)
    orders: np.ndarray  # (6, K) int
    amps: np.ndarray  # (6, K)
    phases: np.ndarray  # (6, K)

    def __call__(self, q: np.ndarray) -> np.ndarray:
        """Δθ (N, 6) at commanded joints q (N, 6) rad."""
        q = np.atleast_2d(q)
        arg = q[:, :, None] * self.orders[None] + self.phases[None]
        return self.offset + np.sum(self.amps[None] * np.sin(arg), axis=-1)

    @classmethod
    def draw(cls, rng: np.random.Generator, n_harmonics: int = 3) -> JointErrors:
        """Random errors 0.005–0.05° in size: an offset plus gear harmonics of orders 1–8."""
        size = np.radians(rng.uniform(0.012, 0.05, 6))
        weights = rng.dirichlet(np.ones(n_harmonics + 1), 6)
        offset = size * weights[:, 0] * rng.choice([-1.0, 1.0], 6)
        orders = np.stack([np.sort(rng.choice(np.arange(1, 9), n_harmonics, replace=False))
                           for _ in range(6)])
        amps = size[:, None] * weights[:, 1:]
        phases = rng.uniform(0.0, 2.0 * np.pi, (6, n_harmonics))
        return cls(offset, orders, amps, phases)

    def to_dict(self) -> dict[str, Any]:
        return {"offset_deg": np.degrees(self.offset).tolist(),
                "orders": self.orders.tolist(),
                "amplitude_deg": np.degrees(self.amps).tolist(),
                "phase_rad": self.phases.tolist()}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> JointErrors:
        return cls(np.radians(d["offset_deg"]), np.asarray(d["orders"], dtype=int),
                   np.radians(d["amplitude_deg"]), np.asarray(d["phase_rad"], dtype=float))


@dataclass
class TrueErrors:
    """Every true error of one virtual robot (internal units: rad, mm, 1/K, s)."""

    joint: JointErrors
    compliance: np.ndarray | None = None  # (2,) rad/(N·m) for joints 2 and 3
    axis_dirs: np.ndarray | None = None  # (6, 3) actual screws (link_geometry)
    axis_points: np.ndarray | None = None
    home: np.ndarray | None = None  # (4, 4)
    backlash: np.ndarray | None = None  # (6,) full width, rad
    thermal: dict[str, float] | None = None  # alpha_per_k, t_ref_c, t_start_c, rise_k, tau_s
    tool_offset: np.ndarray | None = None  # (3,) true minus declared ball offset, mm
    coupling: dict[str, float] | None = None  # source, target (0-based), amp rad, phase
    scale_ppm: float = 0.0
    #: joint (0-based), k_rad_per_nm, tool_kg, tool_cog_mm (flange frame)
    wrist: dict[str, Any] | None = None
    #: joint (0-based), ppm_per_k, t_ref_c, swing_k, period_s
    encoder: dict[str, float] | None = None
    #: source, target (0-based), shift_rad (half the zero shift between directions)
    direction_shift: dict[str, float] | None = None
    #: source, target (0-based), amp_rad, phase_rad of a second harmonic
    coupling2: dict[str, float] | None = None
    # -- issue #14, frames --
    #: k_rad_per_nm, tool_kg, tool_cog_mm (on the flange axis), hinge_mm
    tool_bending: dict[str, float] | None = None
    #: k_rad_per_nm, pivot_depth_mm
    base_tilt: dict[str, float] | None = None
    #: link (1-based: the link after that joint), alpha_per_k, t_ref_c, rise_k, tau_s,
    #: cycle_start_s
    link_thermal: dict[str, float] | None = None
    extra: dict[str, Any] = field(default_factory=dict)
    #: hose_pull: amp_rad (issue #14 section 2; drawn by `draw_hose_pull`)
    hose: dict[str, float] | None = None

    @property
    def effects(self) -> list[str]:
        """Names of the optional effects that are on."""
        on = {"joint_compliance": self.compliance is not None,
              "link_geometry": self.axis_dirs is not None,
              "backlash": self.backlash is not None,
              "thermal_drift": self.thermal is not None,
              "tool_offset": self.tool_offset is not None,
              "joint_coupling": self.coupling is not None,
              "registration_scale": self.scale_ppm != 0.0,
              "wrist_compliance": self.wrist is not None,
              "encoder_thermal": self.encoder is not None,
              "direction_zero_shift": self.direction_shift is not None,
              "joint_coupling2": self.coupling2 is not None,
              "tool_bending": self.tool_bending is not None,
              "base_tilt": self.base_tilt is not None,
              "link_thermal": self.link_thermal is not None,
              "hose_pull": self.hose is not None}
        return [name for name in EFFECTS if on[name]]

    # ---- drawing ---------------------------------------------------------------------

    @classmethod
    def draw(cls, robot: RobotModel, effects: tuple[str, ...] | list[str],
             rng: np.random.Generator) -> TrueErrors:
        """Random true errors for `robot` (a RobotModel) with the named optional effects."""
        unknown = sorted(set(effects) - set(EFFECTS))
        if unknown:
            raise ValueError(f"unknown effect(s) {', '.join(unknown)}; "
                             f"known: {', '.join(EFFECTS)}")
        # Draw everything whether used or not, so adding an effect leaves the others unchanged.
        hose = draw_hose_pull(rng)  # its own stream; `rng` does not advance
        joint = JointErrors.draw(rng)
        compliance = rng.uniform(0.6e-6, 1.5e-6, 2)
        dirs, points, home = _perturbed_geometry(robot, rng)
        backlash = np.zeros(6)
        backlash[:3] = np.radians(rng.uniform(0.01, 0.03, 3))
        thermal = {"alpha_per_k": float(rng.uniform(1.0e-5, 2.3e-5)), "t_ref_c": 20.0,
                   "t_start_c": 20.0, "rise_k": float(rng.uniform(4.0, 8.0)),
                   "tau_s": float(rng.uniform(1200.0, 3600.0))}
        tool = rng.normal(size=3)
        tool *= rng.uniform(0.2, 0.6) / np.linalg.norm(tool)
        pairs = ((1, 2), (3, 4), (4, 5), (0, 1))
        src, dst = pairs[int(rng.integers(len(pairs)))]
        coupling = {"source": src, "target": dst,
                    "amp_rad": float(np.radians(rng.uniform(0.01, 0.03))),
                    "phase_rad": float(rng.uniform(0.0, 2.0 * np.pi))}
        scale = float(rng.uniform(30.0, 80.0) * rng.choice([-1.0, 1.0]))
        # effects outside the diagnosis' candidates: their own stream, derived from the
        # state here without advancing `rng` (the tracker is placed from it next)
        state = rng.bit_generator.state["state"]
        rng = np.random.default_rng([int(state["state"]) % 2**63, int(state["inc"]) % 2**63, 14])
        wrist = {"joint": int(rng.choice([3, 4])),
                 "k_rad_per_nm": float(rng.uniform(5e-5, 1e-4)),
                 "tool_kg": float(rng.uniform(1.5, 3.0)),
                 "tool_cog_mm": [0.0, 0.0, float(rng.uniform(60.0, 120.0))]}
        encoder = {"joint": int(rng.integers(3)), "ppm_per_k": float(rng.uniform(30.0, 60.0)),
                   "t_ref_c": 20.0, "swing_k": float(rng.uniform(2.0, 3.5)),
                   "period_s": float(rng.uniform(300.0, 500.0)), "cycle_start_s": 3000.0}
        shift_pairs = ((3, 4), (2, 1), (4, 3), (0, 2))
        src2, dst2 = shift_pairs[int(rng.integers(len(shift_pairs)))]
        shift = {"source": src2, "target": dst2,
                 "shift_rad": float(np.radians(rng.uniform(0.015, 0.03))
                                    * rng.choice([-1.0, 1.0]))}
        pairs2 = ((1, 2), (3, 4), (0, 1), (2, 1))
        src3, dst3 = pairs2[int(rng.integers(len(pairs2)))]
        coupling2 = {"source": src3, "target": dst3,
                     "amp_rad": float(np.radians(rng.uniform(0.015, 0.03))),
                     "phase_rad": float(rng.uniform(0.0, 2.0 * np.pi))}
        frames = _draw_frames(rng)
        on = set(effects)
        geometry = "link_geometry" in on
        return cls(
            joint=joint,
            compliance=compliance if "joint_compliance" in on else None,
            axis_dirs=dirs if geometry else None,
            axis_points=points if geometry else None,
            home=home if geometry else None,
            backlash=backlash if "backlash" in on else None,
            thermal=thermal if "thermal_drift" in on else None,
            tool_offset=tool if "tool_offset" in on else None,
            coupling=coupling if "joint_coupling" in on else None,
            scale_ppm=scale if "registration_scale" in on else 0.0,
            wrist=wrist if "wrist_compliance" in on else None,
            encoder=encoder if "encoder_thermal" in on else None,
            direction_shift=shift if "direction_zero_shift" in on else None,
            coupling2=coupling2 if "joint_coupling2" in on else None,
            **{key: value for key, value in frames.items() if key in on},
            hose=hose if "hose_pull" in on else None,
        )

    # ---- evaluation ------------------------------------------------------------------

    @property
    def needs_direction(self) -> bool:
        """True when some error depends on the direction joints last moved."""
        return self.backlash is not None or self.direction_shift is not None

    @property
    def needs_temperature(self) -> bool:
        """True when some error depends on the arm's temperature."""
        return (self.thermal is not None or self.encoder is not None
                or self.link_thermal is not None)

    def joint_delta(self, q: np.ndarray, direction: np.ndarray | None,
                    temp_c: np.ndarray | None = None) -> np.ndarray:
        """Joint errors (N, 6) rad that depend on the commanded joints, the motion
        direction and the temperature (None: the reference temperature)."""
        delta = self.joint(q)
        if self.coupling is not None:
            c = self.coupling
            delta[:, int(c["target"])] += c["amp_rad"] * np.sin(
                q[:, int(c["source"])] + c["phase_rad"])
        if self.coupling2 is not None:
            c = self.coupling2
            delta[:, int(c["target"])] += c["amp_rad"] * np.sin(
                2.0 * q[:, int(c["source"])] + c["phase_rad"])
        if self.hose is not None:
            delta[:, 4] += hose_pull(q, self.hose)
        if self.backlash is not None and direction is not None:
            delta -= 0.5 * self.backlash * direction
        if self.direction_shift is not None and direction is not None:
            c = self.direction_shift
            delta[:, int(c["target"])] += c["shift_rad"] * direction[:, int(c["source"])]
        if self.encoder is not None and temp_c is not None:
            e = self.encoder
            j = int(e["joint"])
            growth = 1e-6 * e["ppm_per_k"] * (np.asarray(temp_c, dtype=float) - e["t_ref_c"])
            delta[:, j] += growth * q[:, j]
        return delta

    def temperature(self, time_s: np.ndarray) -> np.ndarray:
        """Arm temperature (°C) at time t: a first-order warm-up from t_start_c, plus the
        work cycle's swing when the encoder scale depends on it."""
        th = self.thermal or {"t_start_c": 20.0, "rise_k": 0.0, "tau_s": 1.0}
        t = np.asarray(time_s, dtype=float)
        out = th["t_start_c"] + th["rise_k"] * -np.expm1(-t / th["tau_s"])
        if self.encoder is not None:
            e = self.encoder
            cycle = np.maximum(t - e.get("cycle_start_s", 0.0), 0.0)
            out = out + e["swing_k"] * np.sin(2.0 * np.pi * cycle / e["period_s"])
        if self.link_thermal is not None:
            lt = self.link_thermal
            warm = np.maximum(t - lt["cycle_start_s"], 0.0)
            out = out + lt["rise_k"] * -np.expm1(-warm / lt["tau_s"])
        return out

    def thermal_scale(self, temp_c: np.ndarray | None) -> np.ndarray | float:
        """Length factor of the arm at temperature T: 1 + α (T − T_ref)."""
        if self.thermal is None or temp_c is None:
            return 1.0
        return 1.0 + self.thermal["alpha_per_k"] * (np.asarray(temp_c) - self.thermal["t_ref_c"])

    # ---- serialisation ---------------------------------------------------------------

    def to_dict(self) -> dict[str, Any]:
        """JSON data (degrees, mm, ppm at the interface)."""
        d: dict[str, Any] = {"effects": self.effects, "joint_errors": self.joint.to_dict()}
        if self.compliance is not None:
            d["joint_compliance_rad_per_nm"] = {"j2": float(self.compliance[0]),
                                                "j3": float(self.compliance[1]),
                                                "link_masses_kg": LINK_MASSES_KG}
        if self.axis_dirs is not None:
            d["link_geometry"] = {"axis_dirs": self.axis_dirs.tolist(),
                                  "axis_points_mm": self.axis_points.tolist(),
                                  "home": self.home.tolist()}
        if self.backlash is not None:
            d["backlash_deg"] = np.degrees(self.backlash).tolist()
        if self.thermal is not None:
            d["thermal_drift"] = dict(self.thermal)
        if self.tool_offset is not None:
            d["tool_offset_error_mm"] = self.tool_offset.tolist()
        if self.coupling is not None:
            c = self.coupling
            d["joint_coupling"] = {"source_joint": int(c["source"]) + 1,
                                   "target_joint": int(c["target"]) + 1,
                                   "amplitude_deg": float(np.degrees(c["amp_rad"])),
                                   "phase_rad": c["phase_rad"]}
        if self.scale_ppm:
            d["registration_scale_ppm"] = self.scale_ppm
        if self.wrist is not None:
            d["wrist_compliance"] = {**self.wrist, "joint": int(self.wrist["joint"]) + 1}
        if self.encoder is not None:
            d["encoder_thermal"] = {**self.encoder, "joint": int(self.encoder["joint"]) + 1}
        if self.direction_shift is not None:
            c = self.direction_shift
            d["direction_zero_shift"] = {"source_joint": int(c["source"]) + 1,
                                         "target_joint": int(c["target"]) + 1,
                                         "shift_deg": float(np.degrees(c["shift_rad"]))}
        if self.coupling2 is not None:
            c = self.coupling2
            d["joint_coupling2"] = {"source_joint": int(c["source"]) + 1,
                                    "target_joint": int(c["target"]) + 1,
                                    "amplitude_deg": float(np.degrees(c["amp_rad"])),
                                    "phase_rad": c["phase_rad"]}
        for key in ("tool_bending", "base_tilt", "link_thermal"):
            if getattr(self, key) is not None:
                d[key] = dict(getattr(self, key))
        if self.hose is not None:
            d["hose_pull"] = {"joint": 5, "depends_on_joints": [4, 6],
                              "amplitude_deg": float(np.degrees(self.hose["amp_rad"]))}
        return d

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> TrueErrors:
        """Inverse of `to_dict`."""
        geo = d.get("link_geometry")
        comp = d.get("joint_compliance_rad_per_nm")
        coup = d.get("joint_coupling")
        wrist = d.get("wrist_compliance")
        enc = d.get("encoder_thermal")
        shift = d.get("direction_zero_shift")
        coup2 = d.get("joint_coupling2")
        hose = d.get("hose_pull")
        return cls(
            joint=JointErrors.from_dict(d["joint_errors"]),
            compliance=None if comp is None else np.array([comp["j2"], comp["j3"]]),
            axis_dirs=None if geo is None else np.asarray(geo["axis_dirs"]),
            axis_points=None if geo is None else np.asarray(geo["axis_points_mm"]),
            home=None if geo is None else np.asarray(geo["home"]),
            backlash=None if "backlash_deg" not in d else np.radians(d["backlash_deg"]),
            thermal=d.get("thermal_drift"),
            tool_offset=(None if "tool_offset_error_mm" not in d
                         else np.asarray(d["tool_offset_error_mm"])),
            coupling=None if coup is None else {
                "source": coup["source_joint"] - 1, "target": coup["target_joint"] - 1,
                "amp_rad": float(np.radians(coup["amplitude_deg"])),
                "phase_rad": coup["phase_rad"]},
            scale_ppm=float(d.get("registration_scale_ppm", 0.0)),
            wrist=None if wrist is None else {**wrist, "joint": int(wrist["joint"]) - 1},
            encoder=None if enc is None else {**enc, "joint": int(enc["joint"]) - 1},
            direction_shift=None if shift is None else {
                "source": shift["source_joint"] - 1, "target": shift["target_joint"] - 1,
                "shift_rad": float(np.radians(shift["shift_deg"]))},
            coupling2=None if coup2 is None else {
                "source": coup2["source_joint"] - 1, "target": coup2["target_joint"] - 1,
                "amp_rad": float(np.radians(coup2["amplitude_deg"])),
                "phase_rad": coup2["phase_rad"]},
            tool_bending=d.get("tool_bending"),
            base_tilt=d.get("base_tilt"),
            link_thermal=d.get("link_thermal"),
            hose=None if hose is None else {
                "amp_rad": float(np.radians(hose["amplitude_deg"]))},
        )


def _perturbed_geometry(robot: RobotModel, rng: np.random.Generator
                        ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Screws of joints 2–6 and tool0's home pose moved by link-length and tilt errors.

    Joint 1's axis stays: it defines the base frame, which the tracker registration
    absorbs anyway. Points move ~0.15 mm across their axes, axes tilt ~0.01°.
    """
    dirs = np.array(robot.axis_dirs, dtype=float)
    points = np.array(robot.axis_points, dtype=float)
    for j in range(1, 6):
        tilt = np.cross(dirs[j], rng.normal(size=3))
        tilt *= np.radians(rng.uniform(0.005, 0.02)) / np.linalg.norm(tilt)
        dirs[j] = Rotation.from_rotvec(tilt).apply(dirs[j])
        shift = np.cross(dirs[j], rng.normal(size=3))
        points[j] += shift * rng.uniform(0.05, 0.3) / np.linalg.norm(shift)
    home = np.array(robot.home, dtype=float)
    home[:3, 3] += rng.normal(0.0, 0.1, 3)
    home[:3, :3] = Rotation.from_rotvec(rng.normal(0.0, np.radians(0.01), 3)).as_matrix() \
        @ home[:3, :3]
    return dirs, points, home


def gravity_torque(axis_dirs: np.ndarray, axis_points: np.ndarray, payload_pos: np.ndarray,
                   payload_kg: np.ndarray) -> np.ndarray:
    """Gravity torque (N, 2) N·m about joints 2 and 3 from the links and the payload.

    `axis_dirs`/`axis_points` (N, 6, 3) are the current joint axes (mm), the payload
    hangs at `payload_pos` (N, 3) mm. The lumped bodies sit between joint-axis
    points (see `_BODIES`); the wrist at the wrist centre (axis-5 point).
    """
    n = axis_points.shape[0]
    centres, masses = [], []
    for name, a, b, frac in _BODIES:
        centres.append(axis_points[:, a] + frac * (axis_points[:, b] - axis_points[:, a]))
        masses.append(np.full(n, LINK_MASSES_KG[name]))
    centres.append(payload_pos)
    masses.append(np.broadcast_to(np.asarray(payload_kg, dtype=float), (n,)))
    c = np.stack(centres, axis=1) * 1e-3  # (N, B, 3) m
    m = np.stack(masses, axis=1)  # (N, B)
    force = m[..., None] * GRAVITY  # (N, B, 3) N
    # Joint 2 carries every body; joint 3 every body but the lower arm.
    carried = np.array([[1, 1, 1, 1], [0, 1, 1, 1]], dtype=float)  # (2, B)
    out = np.empty((n, 2))
    for k, j in enumerate((1, 2)):
        lever = c - axis_points[:, j][:, None, :] * 1e-3
        moment = np.cross(lever, force)  # (N, B, 3)
        out[:, k] = np.einsum("nbi,ni,b->n", moment, axis_dirs[:, j], carried[k])
    return out


def torque_about(axis_dir: np.ndarray, axis_point: np.ndarray, positions: np.ndarray,
                 masses: np.ndarray) -> np.ndarray:
    """Gravity torque (N,) N·m about one axis (N, 3) through (N, 3) mm of point masses
    (kg, (N, B)) at positions (N, B, 3) mm."""
    lever = (positions - axis_point[:, None, :]) * 1e-3
    force = masses[..., None] * GRAVITY
    return np.einsum("nbi,ni->n", np.cross(lever, force), axis_dir)


# ---- issue #14: effects on frames (tool, base, link) ---------------------------------


def _draw_frames(rng: np.random.Generator) -> dict[str, dict[str, float]]:
    """Parameters of the frame effects, from their own stream (derived from `rng`'s
    state without advancing it, so no other effect's draw changes)."""
    state = rng.bit_generator.state["state"]
    own = np.random.default_rng([int(state["state"]) % 2**63, int(state["inc"]) % 2**63,
                                 1402])
    return {
        "tool_bending": {"k_rad_per_nm": float(own.uniform(1.2e-4, 2.5e-4)),
                         "tool_kg": float(own.uniform(2.0, 4.0)),
                         "tool_cog_mm": float(own.uniform(80.0, 160.0)),
                         "hinge_mm": float(own.uniform(0.0, 40.0))},
        "base_tilt": {"k_rad_per_nm": float(own.uniform(2e-7, 4e-7)),
                      "pivot_depth_mm": float(own.uniform(0.0, 300.0))},
        "link_thermal": {"link": int(own.choice([2, 3])), "alpha_per_k": 11.5e-6,
                         "t_ref_c": 20.0, "rise_k": float(own.uniform(12.0, 20.0)),
                         "tau_s": float(own.uniform(150.0, 300.0)), "cycle_start_s": 3000.0},
    }


def _rotations(omega: np.ndarray) -> np.ndarray:
    """Rotation matrices (N, 3, 3) of small rotation vectors (N, 3) rad."""
    return Rotation.from_rotvec(omega).as_matrix()


def tool_bend(bend: dict[str, float], R_flange: np.ndarray, payload_kg: np.ndarray,
              payload_cog_mm: np.ndarray) -> np.ndarray:
    """The bent tool's pose on the flange (N, 4, 4): a rotation about the hinge on the
    flange axis by compliance × the bending part of the gravity moment of the tool
    body and the payload (flange frame, mm)."""
    n = R_flange.shape[0]
    down = np.einsum("nji,j->ni", R_flange, GRAVITY)  # gravity (m/s²) in the flange frame
    hinge = np.array([0.0, 0.0, bend["hinge_mm"]])
    tool_at = np.array([0.0, 0.0, bend["tool_cog_mm"]])
    moment = (np.cross((tool_at - hinge) * 1e-3, bend["tool_kg"] * down)
              + np.cross((payload_cog_mm - hinge) * 1e-3,
                         np.asarray(payload_kg, dtype=float)[:, None] * down))
    moment[:, 2] = 0.0  # stiff in torsion
    R = _rotations(bend["k_rad_per_nm"] * moment)
    out = np.broadcast_to(np.eye(4), (n, 4, 4)).copy()
    out[:, :3, :3] = R
    out[:, :3, 3] = hinge - R @ hinge
    return out


def base_tilt(tilt: dict[str, float], axis_points: np.ndarray, payload_at: np.ndarray,
              payload_kg: np.ndarray) -> np.ndarray:
    """The base's tilt (N, 4, 4): a turn about horizontal axes through the pivot below
    the base origin by compliance × the overturning moment about the base origin of
    the lumped links (see `_BODIES`) and the payload at `payload_at` (N, 3) mm."""
    n = axis_points.shape[0]
    centres = [axis_points[:, a] + frac * (axis_points[:, b] - axis_points[:, a])
               for _, a, b, frac in _BODIES] + [payload_at]
    masses = [np.full(n, LINK_MASSES_KG[name]) for name, *_ in _BODIES]
    masses.append(np.broadcast_to(np.asarray(payload_kg, dtype=float), (n,)))
    moment = sum(np.cross(c * 1e-3, m[:, None] * GRAVITY) for c, m in zip(centres, masses))
    moment[:, 2] = 0.0  # the foundation turns about horizontal axes only
    R = _rotations(tilt["k_rad_per_nm"] * moment)
    pivot = np.array([0.0, 0.0, -tilt["pivot_depth_mm"]])
    out = np.broadcast_to(np.eye(4), (n, 4, 4)).copy()
    out[:, :3, :3] = R
    out[:, :3, 3] = pivot - R @ pivot
    return out


def link_growth(growth: dict[str, float], axis_dirs: np.ndarray, axis_points: np.ndarray,
                home: np.ndarray, q: np.ndarray, temp_c: np.ndarray) -> np.ndarray:
    """Displacement (N, 3) mm of the distal chain when link L grows by α L (T − T_ref):
    the link's home vector, turned by the joints before it."""
    link = int(growth["link"])
    end = home[:3, 3] if link == 6 else axis_points[link]
    v = end - axis_points[link - 1]
    grown = growth["alpha_per_k"] * (np.asarray(temp_c, dtype=float) - growth["t_ref_c"])
    R = np.broadcast_to(np.eye(3), (q.shape[0], 3, 3))
    for j in range(link):  # the joints before the link
        R = R @ _rotations(q[:, j:j + 1] * axis_dirs[j])
    return grown[:, None] * (R @ v)
# ---- hose_pull (issue #14 section 2): a smooth error over two joints -------------------


def draw_hose_pull(rng: np.random.Generator) -> dict[str, float]:
    """The hose's amplitude, from a stream of its own derived from `rng`'s state without
    advancing it (so every other effect's draws stay as they were for every seed)."""
    state = rng.bit_generator.state["state"]
    own = np.random.default_rng([int(state["state"]) % 2**63, int(state["inc"]) % 2**63,
                                 1401])
    return {"amp_rad": float(np.radians(own.uniform(0.03, 0.05)) * own.choice([-1.0, 1.0]))}


def hose_pull(q: np.ndarray, hose: dict[str, float]) -> np.ndarray:
    """Joint 5's error (N,) rad: A · sin θ4 · sin θ6."""
    return hose["amp_rad"] * np.sin(q[:, 3]) * np.sin(q[:, 5])
