"""`Rig`: a validated rig file turned into kinematics, constraints and motor axes, with
what the instrument is (``rig.spec.light``, ``.detector``, ``.reference``; the
serial detector's driver configuration from `Rig.serial_detector_config`).

Joint angles are radians, in the order of the rig file's ``axes``. Directions are
sample-frame unit vectors (z = normal). `solve` gives, for each pair, the joint angles
to measure it (the candidate nearest the previous pose, or the home pose), the pair
actually measured (rotated about the normal for isotropic plans, where the sample
rotation stage stays home) and, for refused pairs, why (`Reason`).
"""

from __future__ import annotations

import copy
import math
from pathlib import Path
from typing import Literal

import numpy as np

from drivers.dynamixel import AxisConfig, step_seconds
from drivers.serial_detector import SerialDetectorConfig
from gonio.blocks import blockwise
from gonio.config import ConfigError, load, read_bytes, spec_text
from gonio.rig import inverse
from gonio.rig.aligned_inverse import newton, pair_residual
from gonio.rig.alignment import Alignment, Geometry, at_height
from gonio.rig.alignment_file import AlignmentFile, load_alignment
from gonio.rig.instrument import SerialInterfaceSpec
from gonio.rig.kinematics import apply, apply_transposed, chain_rotation_of, rotate_z, skew
from gonio.rig.refusals import Refusals
from gonio.rig.rig_checks import check_chains, check_reachable
from gonio.rig.schema import RigSpec
from gonio.rig.solution import Reason, Solution, Solved
from gonio.rig.travel import TravelModel
from gonio.types import ArrayLike, BoolArray, FloatArray

#: An axis whose range is narrower than a turn by more than this (rad) holds at most one
#: of an angle's representatives a turn apart, whatever the rounding of their sums.
_TURN_MARGIN = 1e-9


def named_alignment(rig_path: Path | None, name: str) -> Path:
    """Where the alignment file a rig file's ``alignment`` field names lies: relative to
    the rig file's folder (to the working folder for a rig made in code)."""
    return (rig_path.parent if rig_path is not None else Path()) / name


class Rig:
    """A rig: forward and inverse kinematics, constraints, and its motor axes.

    It holds its `Refusals` (`gonio.rig.refusals`: why a pair or a pose is refused), of
    the class ``refusals_type`` (a study may give other reasons: a subclass of `Rig`
    that names a subclass of `Refusals`); a rig file's checks beyond its schema are
    `gonio.rig.rig_checks`'s."""

    refusals_type: type[Refusals] = Refusals

    def __init__(
        self,
        spec: RigSpec,
        source: Path | None = None,
        text: bytes | None = None,
        alignment_text: bytes | None = None,
    ) -> None:
        self.spec = spec
        self.source = source
        #: The rig file's bytes as read (what a plan's content hash covers); for a rig
        #: made from a spec in code, the spec as YAML (which reads back as the same spec).
        self.text = text if text is not None else spec_text(spec)
        check_chains(spec, self._where)
        self.axes: tuple[str, ...] = tuple(spec.axes)
        #: The alignment file the rig file names (``alignment``; read from
        #: ``alignment_text`` when given, e.g. as a run stored it): its path, bytes, the
        #: file and the `Alignment` the kinematics apply (`Alignment.none` without one).
        self.alignment_path: Path | None = None
        self.alignment_text: bytes | None = None
        self.alignment_file: AlignmentFile | None = None
        self.alignment = Alignment.none()
        if spec.alignment is not None:
            self._read_alignment(spec.alignment, alignment_text)
        a = list(spec.axes.values())
        self.limits = np.radians([[s.min_deg, s.max_deg] for s in a])
        #: The rig file's velocities (rad/s) and accelerations (rad/s²): each axis's limits.
        self.velocity = np.radians([s.max_velocity_deg_s for s in a])
        self.acceleration = np.radians([s.max_acceleration_deg_s2 for s in a])
        self.motor_axes = self._motor_axes()
        #: The time a move takes at the rates the motors run (`motion_rates`).
        self.travel = TravelModel(*self.motion_rates())
        self.home = np.clip(np.zeros(len(a)), self.limits[:, 0], self.limits[:, 1])
        #: Why a pair or a pose is refused: limits, keep-out boxes, the constraints.
        self._refusals = self.refusals_type(
            self.limits, spec.constraints, self.axes, self.source_kind
        )
        self.theta_max = self._refusals.theta_max
        self.min_separation = self._refusals.min_separation
        self._rotation_index = self.axes.index("sample_rotation")
        self._chains = {
            chain: (
                [self.axes.index(n) for n in getattr(spec, chain).axes],
                [skew(np.asarray(spec.axes[n].axis)) for n in getattr(spec, chain).axes],
            )
            for chain in ("light", "detector", "sample")
        }
        self._pointing = {c: np.asarray(getattr(spec, c).pointing) for c in ("light", "detector")}
        check_reachable(
            lambda wi, wo, isotropic: self.solve(wi, wo, isotropic=isotropic).reasons,
            self._where,
        )

    @property
    def _where(self) -> str:
        """How a message names the rig file (its path, or "rig" for one made in code)."""
        return str(self.source) if self.source else "rig"

    @classmethod
    def from_yaml(
        cls, path: str | Path, raw: bytes | None = None, alignment_raw: bytes | None = None
    ) -> Rig:
        """The rig of the file at ``path`` (or of its bytes ``raw``, already read), with
        the alignment file it names (read beside it, or from its bytes ``alignment_raw``
        as a run or a plan stored them)."""
        path = Path(path)
        raw = read_bytes(path) if raw is None else raw
        return cls(load(path, RigSpec, raw=raw), path, raw, alignment_raw)

    def _read_alignment(self, name: str, raw: bytes | None, given: bool = False) -> None:
        """Read the alignment file ``name`` (relative to the rig file, or as ``given``
        in place of the one it names)."""
        where = self._where
        path = Path(name) if given else named_alignment(self.source, name)
        if raw is None:
            try:
                raw = path.read_bytes()
            except OSError as exc:
                field = f"{path}" if given else f"{where}: alignment"
                raise ConfigError(
                    f"{field}: cannot read the alignment file {str(path)!r}: {exc.strerror or exc}"
                ) from None
        file = load_alignment(path, raw)  # ConfigError naming the alignment file's field
        unknown = file.alignment.unknown_axes(self.axes)
        if unknown:
            raise ConfigError(
                f"{path}: alignment.zero_offset_deg.{unknown[0]}: no such axis in the rig "
                f"file {where} (axes: {', '.join(self.axes)})"
            )
        self.alignment_path, self.alignment_text, self.alignment_file = path, raw, file
        self.alignment = file.alignment.alignment(self.axes)

    def with_alignment(self, alignment: Alignment) -> Rig:
        """This rig with ``alignment`` (one, not a batch) in place of its own, and no
        alignment file (a fit's trial, a test)."""
        if alignment.batch_shape != ():
            raise ValueError("with_alignment: expected one alignment, not a batch")
        out = copy.copy(self)
        out.alignment, out.alignment_file = alignment, None
        out.alignment_path = out.alignment_text = None
        return out

    def realigned(self, path: str | Path, raw: bytes | None = None) -> Rig:
        """This rig with the alignment file at ``path`` (or its bytes ``raw``) in place of
        its own: the same rig file's instrument, measured later (`ConfigError`, one line,
        on a bad file)."""
        out = copy.copy(self)
        out._read_alignment(str(path), raw, given=True)
        return out

    # -- kinematics --------------------------------------------------------------------
    def _chain(self, chain: str, angles: FloatArray) -> FloatArray:
        columns, skews = self._chains[chain]
        return chain_rotation_of(skews, [angles[..., c] for c in columns])

    def forward(
        self, angles: FloatArray, alignment: Alignment | None = None
    ) -> tuple[FloatArray, FloatArray]:
        """Sample-frame (ωi, ωo) of joint angles (..., A) (any chain, no closed form); with
        an ``alignment``, those the misaligned rig really measures at the angles the rig
        file reads (`geometry`; none or `Alignment.none`: the rig file's, bit for bit; a
        batch of alignments broadcasts against the angles' leading axes)."""
        angles = np.asarray(angles, dtype=np.float64)
        if alignment is not None and not (alignment.is_none and alignment.batch_shape == ()):
            g = self.geometry(angles, alignment)
            return g.wi, g.wo
        sample = self._chain("sample", angles)
        light = apply(self._chain("light", angles), self._pointing["light"])
        detector = apply(self._chain("detector", angles), self._pointing["detector"])
        return apply_transposed(sample, light), apply_transposed(sample, detector)

    def geometry(self, angles: FloatArray, alignment: Alignment) -> Geometry:
        """What the optics of the rig misaligned by ``alignment`` see at the joint angles
        (..., A) the rig file reads: true (ωi, ωo), the spots' shifts and a point source's
        distance (`gonio.rig.alignment`: the zero offsets through every chain, the tilt
        after the sample chain, the pointing errors at the end of theirs, the height
        last)."""
        q = alignment.joints(np.asarray(angles, dtype=np.float64))
        sample = self._chain("sample", q) @ alignment.tilt_rotation()
        light = apply(
            self._chain("light", q) @ alignment.pointing_rotation("light"), self._pointing["light"]
        )
        detector = apply(
            self._chain("detector", q) @ alignment.pointing_rotation("detector"),
            self._pointing["detector"],
        )
        light_spec = self.spec.light
        distance = light_spec.distance_mm if light_spec.kind == "point" else None
        return at_height(
            apply_transposed(sample, light),
            apply_transposed(sample, detector),
            alignment.height_mm,
            distance,
        )

    def candidates(
        self, wi: FloatArray, wo: FloatArray, *, isotropic: bool = False
    ) -> tuple[FloatArray, FloatArray]:
        """Every closed-form solution (N, K', A), and the sample rotation ψ (N, K') each
        was solved with.

        An axis whose range is narrower than a turn takes the one representative of its
        angle inside the range (the one nearest the range's centre if several are on
        its edges). An axis with a range of a turn or more (an extended-position stage)
        offers each solution at −2π, 0 and +2π (out-of-range ones are refused later), so
        that the move nearest the previous pose can use the whole range. With
        ``isotropic`` the sample rotation stays home (see `solve`).
        """
        wi = np.asarray(wi, dtype=np.float64).reshape(-1, 3)
        wo = np.asarray(wo, dtype=np.float64).reshape(-1, 3)
        columns, psi, _ = self._columns(wi, wo, isotropic)
        return np.ascontiguousarray(columns.transpose(2, 1, 0)), np.ascontiguousarray(psi.T)

    def _columns(
        self, wi: FloatArray, wo: FloatArray, isotropic: bool
    ) -> tuple[FloatArray, FloatArray, BoolArray | None]:
        """`candidates` axis-major: the angles (A, K', N), ψ (K', N) and, with an
        alignment, where the candidates reach the pair in the true geometry (K', N).

        Each axis's angle of each candidate for all pairs is one contiguous row, so every
        test below (limits, keep-out boxes, travel times, the reasons' "any candidate")
        loops over long rows; in the (N, K', A) layout each numpy call looped over A
        values at a time, 20 to 50 times slower per value. Candidate k' = v K + k is
        solution k of the solver in variant v, the variants being the turns (−1, 0, +1)
        of each extended axis in turn, the last one varying fastest.
        """
        solved, converged = self._solved(wi, wo, isotropic)
        rotation = self._rotation_index
        lo, hi = self.limits[:, 0], self.limits[:, 1]
        extended = [
            int(j)
            for j in np.flatnonzero(hi - lo >= 2.0 * np.pi)
            if not (isotropic and j == rotation)
        ]
        variants = 3 ** len(extended)
        raw_rotation = solved[self.axes[rotation]]
        count, n = raw_rotation.shape
        out = np.empty((len(self.axes), variants, count, n))
        for j, name in enumerate(self.axes):
            raw = solved[name]
            if j in extended:
                every = 3 ** (len(extended) - 1 - extended.index(j))
                for v in range(variants):
                    turns = (v // every) % 3 - 1
                    np.add(raw, 2.0 * np.pi * turns, out=out[j, v])
            elif isotropic and j == rotation:
                out[j] = self.home[rotation]
            else:
                out[j] = self._representative(raw, j)
        psi = np.broadcast_to(raw_rotation, (variants, count, n)).reshape(variants * count, n)
        reached = None if converged is None else np.tile(converged, (variants, 1))
        return out.reshape(len(self.axes), variants * count, n), psi, reached

    def _solved(
        self, wi: FloatArray, wo: FloatArray, isotropic: bool
    ) -> tuple[dict[str, FloatArray], BoolArray | None]:
        """The closed form's solutions {axis: (K, N)}: the rig file's geometry's, or with
        an alignment the commanded angles that reach the pairs in the true geometry
        (`gonio.rig.aligned_inverse`), with where they do (K, N) (None: no alignment)."""
        a = self.alignment
        if a.is_none:
            return inverse.SOLVERS[self.spec.type](wi, wo), None
        tilt = a.tilt_rotation()
        solved = inverse.SOLVERS[self.spec.type](wi @ tilt.T, wo @ tilt.T)  # ω_stage = R_tilt ω
        q = np.stack([solved[name] for name in self.axes], axis=-1) - a.zero_offset
        free = list(range(len(self.axes)))
        rotation = self._rotation_index
        if isotropic:
            q[..., rotation] = self.home[rotation]
            free.remove(rotation)
        exact = not (
            isotropic
            or np.any(a.light_pointing)
            or np.any(a.detector_pointing)
            or (self.source_kind == "point" and np.any(a.height_mm))
        )
        if exact:
            converged = np.ones(q.shape[:-1], dtype=np.bool_)
        else:

            def forward(angles: FloatArray) -> tuple[FloatArray, FloatArray]:
                return self.forward(angles, a)

            shape = q.shape
            ti, to = (np.broadcast_to(w, (*shape[:-1], 3)).reshape(-1, 3) for w in (wi, wo))
            residual = pair_residual(forward, ti, to, isotropic)
            flat, reached = newton(residual, q.reshape(-1, shape[-1]), free)
            q, converged = flat.reshape(shape), reached.reshape(shape[:-1])
        return {
            name: np.ascontiguousarray(q[..., j]) for j, name in enumerate(self.axes)
        }, converged

    def _representative(self, raw: FloatArray, j: int) -> FloatArray:
        """Angles ``raw`` of axis ``j`` moved by a whole turn into its range: of raw − 2π,
        raw and raw + 2π, the one inside the range nearest its centre (the first of
        equals); raw itself where none is inside. A turn that puts no angle inside is
        skipped (float addition is monotone: the shifted extremes say so exactly)."""
        lo, hi = self.limits[j, 0], self.limits[j, 1]
        centre = 0.5 * (lo + hi)
        low, high = np.min(raw, initial=np.inf), np.max(raw, initial=-np.inf)
        turns = [
            t for t in (-1, 0, 1) if not (high + 2.0 * np.pi * t < lo or low + 2.0 * np.pi * t > hi)
        ]
        best = raw
        # Narrower than a turn (with room for rounding): at most one turn is inside.
        single = len(turns) == 1 or hi - lo < 2.0 * np.pi - _TURN_MARGIN
        best_gap = None if single else np.full(raw.shape, np.inf)
        for t in turns:
            shifted = raw + 2.0 * np.pi * t
            take = shifted >= lo
            take &= shifted <= hi
            if best_gap is not None:
                gap = np.where(take, np.abs(shifted - centre), np.inf)
                take = gap < best_gap
                np.copyto(best_gap, gap, where=take)
            best = np.where(take, shifted, best)
        return best

    def _collides(self, angles: FloatArray) -> BoolArray:
        """True where joint angles (..., A) are inside a keep-out box (`Refusals`)."""
        return self._refusals.collides(angles)

    def travel_time(self, p: FloatArray, q: FloatArray) -> FloatArray:
        """Time (s) to move every axis from p to q at once (`TravelModel.time`)."""
        return self.travel.time(p, q)

    def solve(
        self,
        wi: FloatArray,
        wo: FloatArray,
        *,
        isotropic: bool = False,
        previous: FloatArray | None = None,
    ) -> Solution:
        """Joint angles and refusal reasons for pairs (N, 3); see the module docstring.

        ``previous``: the pose (A,) the move starts from (default: home). Pairs are
        solved in blocks of `BLOCK` (`gonio.blocks`): the same answer at a flat cost per
        pair.
        """
        wi = np.asarray(wi, dtype=np.float64).reshape(-1, 3)
        wo = np.asarray(wo, dtype=np.float64).reshape(-1, 3)
        start = self.home if previous is None else np.asarray(previous, dtype=np.float64)

        def block(wi: FloatArray, wo: FloatArray) -> Solved:
            return self._solve(wi, wo, isotropic, start)

        angles, measured_wi, measured_wo, reasons, cand, usable = blockwise(block, wi, wo)
        return Solution(angles, measured_wi, measured_wo, reasons, cand, usable)

    def _solve(self, wi: FloatArray, wo: FloatArray, isotropic: bool, start: FloatArray) -> Solved:
        """`solve` of one block: (angles, ωi and ωo measured, reasons, candidates, usable)."""
        # Isotropic: the pair may turn about the normal, so the rotation stage stays home
        # and the turned pair is measured instead (ω' = R_z(ψ) ω for the candidate's ψ).
        columns, psi, reached = self._columns(wi, wo, isotropic)
        angles_last = np.moveaxis(columns, 0, -1)  # (K', N, A), a view
        limits_ok = self._refusals.inside_limits(columns)
        if reached is not None:
            limits_ok &= reached
        usable = limits_ok & ~self._collides(angles_last)
        cost = np.where(usable, self.travel_time(start, angles_last), np.inf)
        pick = np.argmin(cost, axis=0)
        rows = np.arange(len(wi))
        angles = np.ascontiguousarray(columns[:, pick, rows].T)
        reasons = self._refusals.reasons(wi, wo, limits_ok, usable)

        measured_wi, measured_wo = wi, wo
        if reached is not None:  # what the rig, as it really is, measures at the poses
            measured_wi, measured_wo = self.forward(angles, self.alignment)
        elif isotropic:
            turn = psi[pick, rows] - self.home[self._rotation_index]
            measured_wi, measured_wo = rotate_z(wi, turn), rotate_z(wo, turn)
        candidates = np.ascontiguousarray(columns.transpose(2, 1, 0))
        return angles, measured_wi, measured_wo, reasons, candidates, usable.T.copy()

    def reachable(
        self, wi: FloatArray, wo: FloatArray, *, isotropic: bool = False
    ) -> tuple[BoolArray, np.ndarray]:
        """(mask, reasons) for pairs (N, 3): True where the rig can measure the pair (the
        reasons of `solve`, without choosing a pose). Pairs are checked in blocks of
        `BLOCK` (`gonio.blocks`): the same answer at a flat cost per pair."""
        wi = np.asarray(wi, dtype=np.float64).reshape(-1, 3)
        wo = np.asarray(wo, dtype=np.float64).reshape(-1, 3)

        def block(wi: FloatArray, wo: FloatArray) -> tuple[BoolArray, np.ndarray]:
            columns, _, reached = self._columns(wi, wo, isotropic)
            limits_ok = self._refusals.inside_limits(columns)
            if reached is not None:
                limits_ok &= reached
            usable = limits_ok & ~self._collides(np.moveaxis(columns, 0, -1))
            reasons = self._refusals.reasons(wi, wo, limits_ok, usable)
            return reasons == Reason.OK, reasons

        return blockwise(block, wi, wo)

    def pose_reasons(self, angles: FloatArray) -> tuple[np.ndarray, BoolArray]:
        """(reasons (N,), commandable (N,)) of given joint angles (N, A): why the pair
        these poses measure is refused at these very poses (`Reason`; OK where it is
        not), and whether each pose may be commanded at all (inside the axes' limits,
        outside every keep-out box)."""
        angles = np.asarray(angles, dtype=np.float64).reshape(-1, len(self.axes))
        wi, wo = self.forward(angles, self.alignment)
        limits_ok = self._refusals.inside_limits(angles.T)
        commandable = limits_ok & ~self._collides(angles)
        reasons = self._refusals.reasons(wi, wo, limits_ok[None, :], commandable[None, :])
        return reasons, commandable

    # -- the instrument ------------------------------------------------------------------
    @property
    def source_kind(self) -> Literal["collimated", "point"]:
        """The light's kind (``light.kind``)."""
        return self.spec.light.kind

    @property
    def reference_diameter_mm(self) -> float:
        """The reference standard's diameter (mm): ``reference.diameter_mm``, or the
        sample's (``constraints.sample_diameter_mm``) when the rig file gives none."""
        given = self.spec.reference.diameter_mm
        return self.spec.constraints.sample_diameter_mm if given is None else given

    def reference_directions(self) -> tuple[FloatArray, FloatArray]:
        """(ωi, ωo), each (3,), of the reference standard's calibration geometry: the
        light at ``reference.theta_i_deg`` toward +x, the detector at ``theta_o_deg``
        toward −x (the sample's x-z plane)."""
        ref = self.spec.reference
        ti, to = math.radians(ref.theta_i_deg), math.radians(ref.theta_o_deg)
        wi = np.array([math.sin(ti), 0.0, math.cos(ti)])
        wo = np.array([-math.sin(to), 0.0, math.cos(to)])
        return wi, wo

    def serial_detector_config(self) -> SerialDetectorConfig:
        """The detector's ``interface`` as the driver's `SerialDetectorConfig`;
        `ConfigError` unless the interface is ``serial``."""
        interface = self.spec.detector.interface
        if not isinstance(interface, SerialInterfaceSpec):
            raise ConfigError(
                f"{self._where}: detector.interface: is {interface.kind!r}; expected 'serial' for "
                "a serial detector"
            )
        return interface.config()  # checked when the rig was read

    # -- motors ------------------------------------------------------------------------
    @property
    def on_dynamixel(self) -> bool:
        """The motors are Dynamixel servos on a bus (``bus.kind: dynamixel``)."""
        return self.spec.bus.kind == "dynamixel"

    def motion_rates(self) -> tuple[FloatArray, FloatArray]:
        """(velocity rad/s, acceleration rad/s²) per axis of the profiles the motors run:
        on a Dynamixel bus the profile registers' (each rate rounded to a register step,
        `AxisConfig.profile_rates`: 90 °/s² runs as 85.8 °/s² on a direct axis), else
        the rig file's (what the simulated motors take)."""
        if not self.on_dynamixel:
            return self.velocity, self.acceleration
        rates = np.array([axis.profile_rates() for axis in self.motor_axes], dtype=np.float64)
        return rates[:, 0].copy(), rates[:, 1].copy()

    def bus_time(self, travel: ArrayLike) -> FloatArray:
        """The time (s) the motor bus adds to each stop-and-go step whose move takes
        ``travel`` s (any shape): on a Dynamixel bus its wire time at ``bus.baud``
        (`drivers.dynamixel.wire.step_seconds`: the goals, the settle polls, the read
        back); 0 for simulated motors."""
        moves = np.asarray(travel, dtype=np.float64)
        if not self.on_dynamixel:
            return np.zeros_like(moves)
        return step_seconds(len(self.axes), self.spec.bus.baud, moves)

    def bus_axes(self) -> list[AxisConfig]:
        """The axes as `drivers.dynamixel.axis.AxisConfig` for a `DynamixelBus`."""
        return list(self.motor_axes)

    def _motor_axes(self) -> tuple[AxisConfig, ...]:
        out = []
        for name, s in self.spec.axes.items():
            try:
                out.append(s.axis_config(name))
            except ValueError as exc:
                raise ConfigError(f"{self._where}: axes.{name}: {exc}") from None
        return tuple(out)
