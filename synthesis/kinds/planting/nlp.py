"""The planting-arm problem: every rule of a planting_fourbar spec, declared for the solve core.

Decision variables: the design variables (fixed ones get lo = hi), the crank angles of P1-P6 and, with a
``[key_poses]`` table, the crank angle of each free pose (pinned where the tip comes nearest its target).
The precision points are where the path meets the seedbed lines and the soil, written as
structural equalities on their crank angles, so IPOPT sees smooth rows instead of min/max over
samples.  The lowest point is stationary (vy = 0) and no sample of the turn lies lower.  The rules
are :func:`synthesis.kinds.planting.rule_set.planting_rules` of the symbolic trace; back-off, the elastic
form and the robust objective's epigraph are :mod:`synthesis.core.transcribe`'s.

:class:`PlantingProblem` builds the problem and its maps; :func:`declare` hands them to the core as a
:class:`~synthesis.core.declared.Declared`, which compiles it and solves each start.
"""

from __future__ import annotations

import math
from typing import cast

import casadi as ca
import numpy as np

from synthesis.core.declared import Declared
from synthesis.core.ipopt import CompiledNLP, NLPOutcome
from synthesis.core.kind import Setting
from synthesis.core.problem import (Envelope, MaxMinMargin, ObjectiveParts, Operating, Problem,
                                    scaled_backoff)
from synthesis.dynamics.linkage import PEAK_OBJECTIVES, peak_epigraph, peak_of
from synthesis.errors import AssemblyError
from synthesis.kinds.planting.check import CHECK_TURN_SAMPLES, soil_contact
from synthesis.kinds.planting.dynamics import (SoilContact, arm_dynamics, arm_linkage, counterweight_of,
                                               rocker_counterweight_of)
from synthesis.constraints.poses import nearest_row
from synthesis.kinds.planting.kinematics import (claw_attitude, link_function, path_positions,
                                                 rocker_counterweight_y_function, tip_derivatives)
from synthesis.kinds.planting.rule_set import PHASES, POINTS, TWO_PI, PoseReading, Trace, phase_bounds, planting_rules
from synthesis.kinds.planting.rules.counterweight import CounterweightReading, declared
from synthesis.kinds.planting.scene import PlantingScene, assembly_status, find_precision_points
from synthesis.spec.design_info import units_of
from synthesis.spec.common import bounds_of, is_free, value_of
from synthesis.spec.operating import ranges_of
from synthesis.kinds.planting.spec import PlantingFourbarSpec

MIN_GAP = math.radians(1.0)          # smallest crank-angle gap between consecutive precision points (default)
THETA_BOUNDS = (-4 * math.pi, 6 * math.pi)
#: the rules without which the kinematics is undefined stay hard in the elastic diagnosis
HARD_IN_ELASTIC = ("grashof_crank_rocker",)
#: the design variables no design may take below zero (a mass, a radius)
NOT_NEGATIVE = ("counterweight_mass", "counterweight_radius", "rocker_counterweight_mass",
                "rocker_counterweight_radius")
#: the min-peak objectives (synthesis.dynamics.linkage.peak_epigraph) and their units
PEAK_UNITS = {name: unit for name, (unit, _) in PEAK_OBJECTIVES.items()}


def declare(setting: Setting) -> Declared:
    """The planting problem of the setting's spec, with its start map (the crank angles of P1-P6 guessed from the
    start design's numeric points), its objective in report units and each start's solver crank angles."""
    return PlantingProblem(setting.spec, setting).declared()


class PlantingProblem:
    """The problem of a planting_fourbar spec as a setting sees it (operating conditions as symbols or numbers),
    and the maps the core solves it through."""

    def __init__(self, spec: PlantingFourbarSpec, setting: Setting | None = None):
        setting = setting or Setting(spec)
        self.spec = spec
        variables = spec.variables()
        self.names = list(variables)
        self.bounds = np.array([bounds_of(v) for v in variables.values()], dtype=float)
        self.init = np.array([value_of(v) for v in variables.values()], dtype=float)
        # a range given in the spec is its nominal value here once validated (ranges_of keeps the range)
        self.omega = cast(float, spec.operation.crank_speed) * TWO_PI / 60.0
        # an operating condition given as a range is a symbol (the core holds the rules that read it once per
        # sampled value: an envelope); with any range, or when the sensitivity analysis asks, both conditions are
        # symbols, resolved at their numbers where not sampled (so `agrisynth tolerance` has every rule's derivative
        # w.r.t. both); otherwise, as a solve of a nominal spec sees them, both stay numbers
        ranges = ranges_of(spec)
        symbolic = bool(ranges) or setting.operating_symbols
        self.operating = [Operating(n, ca.SX.sym(n), getattr(spec.operation, n), unit)
                          for n, unit in (("forward_speed", "m/s"), ("crank_speed", "r/min")) if symbolic]
        op = {o.name: o.symbol for o in self.operating}
        self.forward_speed = op.get("forward_speed", cast(float, spec.operation.forward_speed))       # m/s
        self.omega_sym = op["crank_speed"] * TWO_PI / 60.0 if "crank_speed" in op else self.omega
        x = ca.SX.sym("x", len(self.names))
        # a seedling clearance adds the crank angle of the loop's top before P1 (see _structural), each free key pose
        # its own crank angle after those (see _poses)
        self.clearance = float(spec.solver.seedling_clearance)
        self.free_poses = [n for n, pose in spec.key_poses.items() if pose.at is None and pose.crank_angle is None]
        self.pose_offset = 7 if self.clearance > 0.0 else 6
        th = ca.SX.sym("theta", self.pose_offset + len(self.free_poses))
        v = {n: x[i] for i, n in enumerate(self.names)}
        theta = dict(zip(POINTS, (th[i] for i in range(6))))
        p = self._arm(v)
        tip = tip_derivatives(spec.arm.branch)
        states = {n: self._state(tip, theta[n], p) for n in POINTS}
        # in a tolerance box the rows that make P1-P6 exist -- each crossing's direction, their order around the turn
        # and, with a clearance, the loop top's height above the seedling-top line -- are held at their linearised
        # worst case, like a rule's: the points stay crossings, in their order, for every design in the box, not at
        # the nominal only (robust_redesign_from_example1 without them: P3 fell after P4, soil entry, in 2 of 2,000
        # Monte-Carlo samples, and the five rules that read P1-P3 could not be evaluated there)
        structural = self._structural(v, p, theta, states, th[6] if self.clearance > 0.0 else None)
        self.surface = self._soil_surface(v, states)
        # the soil law's surface: the [soil] level (a number or a design variable) or the analysis depth above P5,
        # whose crank angle is a decision variable, as the structural rows place it
        self.contact = (SoilContact(self.surface, self.forward_speed)
                        if spec.dynamics is not None and spec.dynamics.soil is not None else None)
        poses, nearest = self._poses(p, theta, states, th)
        structural += nearest
        self.problem = Problem(
            name="planting",
            x=ca.vertcat(x, th),
            lbx=np.concatenate([self.bounds[:, 0], np.full(th.numel(), THETA_BOUNDS[0])]),
            ubx=np.concatenate([self.bounds[:, 1], np.full(th.numel(), THETA_BOUNDS[1])]),
            structural=structural,
            robust_structural=self._existence_rows,
            rules=planting_rules(self._trace(v, p, theta, states, poses), spec.rules),
            objective=self._objective(x, v),
            backoff=scaled_backoff(spec.solver.backoff),
            hard_in_elastic=HARD_IN_ELASTIC,
            ipopt="standard",
            max_iter=spec.solver.max_iter,
            operating=self.operating,
            envelope=Envelope({n: r.solver_values() for n, (_, r) in ranges.items()}) if ranges else None,
            x_units=[*units_of(spec, self.names), *["rad"] * th.numel()],
            structural_units=self._structural_units(), objective_unit="",
        )

    def declared(self) -> Declared:
        return Declared(self.problem, self.names, self.bounds, self.init, design=self.design, start=self.start,
                        objective=self.reported, details=self.details)

    # ------------------------------------------------------------------ the declaration

    @staticmethod
    def _arm(v):
        """The kinematics' parameter vector (mm, rad) of the design variables."""
        rad = math.pi / 180.0
        return ca.vertcat(v["l1"], v["l2"], v["l3"], v["l4"], v["l5"], v["zeta"] * rad, v["phi"] * rad)

    def _state(self, tip, theta, p) -> tuple:
        """(position mm, velocity mm/s, velocity at the nominal crank speed mm/s) of the claw tip at crank
        angle theta: one node each, shared by the rules and the structural rows (which read the velocity at the
        nominal crank speed: the directions they fix are the same at any crank speed, and the rows stay free of
        the crank-speed symbol an envelope samples)."""
        pos, dpos, _ = tip(theta, p)
        vel = dpos * self.omega_sym
        return pos, vel, (vel if isinstance(self.omega_sym, float) else dpos * self.omega)

    def _poses(self, p, theta, states, th) -> tuple[list[PoseReading], list]:
        """The claw at each key pose on decision variables -- at its precision point's crank angle, at its
        prescribed one, or at its own (a free pose) -- and the rows pinning each free pose's angle where the tip
        comes nearest its target (the check's reading: synthesis.kinds.planting.scene.nearest_crank_angle)."""
        branch, readings, rows = self.spec.arm.branch, [], []
        tip = tip_derivatives(branch)
        for name, pose in self.spec.key_poses.items():
            if pose.at is not None:
                angle, pos = theta[pose.at], states[pose.at][0]
            else:
                angle = (th[self.pose_offset + self.free_poses.index(name)] if pose.crank_angle is None
                         else math.radians(pose.crank_angle))
                pos, dpos, _ = tip(angle, p)
                if pose.crank_angle is None:
                    rows.append((nearest_row(pos[0] - pose.x, pos[1] - pose.y, dpos[0], dpos[1]), 0.0, 0.0))
            readings.append(PoseReading(name, pose, angle, (pos[0], pos[1]), claw_attitude(angle, p, branch)))
        return readings, rows

    def _trace(self, v, p, theta, states, poses: list[PoseReading]) -> Trace:
        """The rules' trace on decision variables, sampled as ``[solver]`` says."""
        spec, omega = self.spec, self.omega_sym
        n = spec.solver.samples_per_phase
        s = np.linspace(0.0, 1.0, n)
        tip = tip_derivatives(spec.arm.branch).map(n)
        accel = {}
        for phase in PHASES:
            ta, tb = phase_bounds(theta, phase)
            accel[phase] = ca.vec(tip(ca.horzcat(*[ta + si * (tb - ta) for si in s]), p)[2][1, :]) * omega**2
        m = spec.solver.samples_per_turn
        turn = np.linspace(0.0, TWO_PI, m, endpoint=False).reshape(1, -1)
        mu = link_function(spec.arm.branch).map(m)(turn, p)[0]
        return Trace(theta=theta, pos={k: (st[0][0], st[0][1]) for k, st in states.items()},
                     vel={k: (st[1][0], st[1][1]) for k, st in states.items()},
                     accel_y=accel, links=(v["l1"], v["l2"], v["l3"], v["l4"]),
                     mu_deg=ca.vec(mu) * (180.0 / math.pi), omega=omega, forward=self.forward_speed * 1000.0,
                     acc_scale=self.omega**2 * value_of(spec.arm.l2),
                     dynamics=arm_dynamics(spec.dynamics, p, spec.arm.branch, omega, counterweight_of(v),
                                           rocker_counterweight_of(v), self.contact), poses=poses,
                     counterweights=self._counterweights(v, p, turn))

    def _counterweights(self, v, p, turn: np.ndarray) -> list[CounterweightReading]:
        """Each counterweight whose mass is free or not zero, its heights above the soil surface (mm): the crank's
        at its lowest point exactly (-radius: it circles the origin O), the rocker's at the turn's samples."""
        table = self.spec.dynamics
        out: list[CounterweightReading] = []
        if table is None:
            return out
        for name, weight, heights in (
                ("counterweight", table.counterweight, lambda r: -r - self.surface),
                ("rocker_counterweight", table.rocker_counterweight,
                 lambda r: ca.vec(rocker_counterweight_y_function(self.spec.arm.branch).map(turn.size)(
                     turn, p, r)) - self.surface)):
            if weight is None or not declared((value_of(weight.mass), None), is_free(weight.mass)):
                continue
            out.append(CounterweightReading(name, heights(v[f"{name}_radius"]), table.counterweight_clearance))
        return out

    def _soil_surface(self, v, states):
        """Y of the soil surface (mm, machine frame) on decision variables: the [soil] level or the analysis depth
        above the lowest point P5."""
        spec = self.spec
        return v["soil_level"] if spec.soil.level is not None else states["P5"][0][1] + spec.soil.analysis_depth

    def _structural(self, v, p, theta, states, top=None) -> list:
        """Definitions of P1-P6 (equalities, crossing directions, order) and the lowest-point bound; with a
        seedling clearance, the loop's top (crank angle ``top``: the height above the seedbed stationary there,
        between P6 and P1) at least that far above the seedling-top line, so P1 is a crossing with a sign change
        and not a touch."""
        spec = self.spec
        pos = {k: st[0] for k, st in states.items()}
        vel = {k: st[2] for k, st in states.items()}          # at the nominal crank speed (see _state)
        tilt = v["seedbed_tilt"] * math.pi / 180.0
        normal = (-ca.sin(tilt), ca.cos(tilt))

        def height(q):
            return normal[0] * (q[0] - v["seedbed_x"]) + normal[1] * (q[1] - v["seedbed_y"])

        soil = self._soil_surface(v, states)
        rows = [
            (pos["P4"][1] - soil, 0.0, 0.0), (pos["P6"][1] - soil, 0.0, 0.0),        # on the soil line
            (vel["P5"][1], 0.0, 0.0),                                                  # lowest: vy = 0
            (height(pos["P3"]), 0.0, 0.0),
            (height(pos["P2"]) - spec.seedbed.thickness, 0.0, 0.0),
            (height(pos["P1"]) - spec.seedbed.seedling_height, 0.0, 0.0),
            (vel["P4"][1], None, 0.0), (vel["P6"][1], 0.0, None),                     # entering / leaving
        ]
        for n in ("P1", "P2", "P3"):                                                   # passing into the mat
            rows.append((normal[0] * vel[n][0] + normal[1] * vel[n][1], None, 0.0))
        order = ("P5", "P6", "P1", "P2", "P3", "P4")
        gap = MIN_GAP if spec.solver.point_gap == 1.0 else math.radians(spec.solver.point_gap)
        self.order_rows = {}                           # "P3-P4": the index of the row theta_P4 - theta_P3 >= gap
        for a, b in zip(order, order[1:]):
            self.order_rows[f"{a}-{b}"] = len(rows)
            rows.append((theta[b] - theta[a], gap, None))
        self.order_rows["P4-P5"] = len(rows)
        rows.append((theta["P5"] + TWO_PI - theta["P4"], gap, None))
        # the crossings' directions and the points' order: every inequality row so far
        existence = [i for i, (_, lb, ub) in enumerate(rows) if lb is None or ub is None or lb != ub]
        if top is not None:          # the top: height stationary (n.v = 0, pins it), between P6 and P1, clear
            q, dq, _ = tip_derivatives(spec.arm.branch)(top, p)
            rows += [(normal[0] * dq[0] + normal[1] * dq[1], 0.0, 0.0),
                     (top - theta["P6"], MIN_GAP, None), (theta["P1"] - top, MIN_GAP, None),
                     (height(q) - spec.seedbed.seedling_height, self.clearance, None)]
            existence += [len(rows) - 3, len(rows) - 2, len(rows) - 1]
        self._existence_rows = tuple(existence)
        per_turn = spec.solver.samples_per_turn
        samples = [theta["P5"] + TWO_PI * k / per_turn for k in range(1, per_turn)]
        ys = tip_derivatives(spec.arm.branch).map(len(samples))(ca.horzcat(*samples), p)[0][1, :]
        rows.append((ca.vec(ys) - pos["P5"][1], 0.0, None))
        return rows

    def _structural_units(self) -> list[str]:
        """The unit of each row of :meth:`_structural`, in its order."""
        units = ["mm", "mm", "mm/s", "mm", "mm", "mm", "mm/s", "mm/s"] + ["mm/s"] * 3 + ["rad"] * 6
        if self.clearance > 0.0:
            units += ["mm/rad", "rad", "rad", "mm"]
        return units + ["mm"] + ["mm^2/rad"] * len(self.free_poses)

    def _objective(self, x, v) -> ObjectiveParts | MaxMinMargin:
        name = self.spec.objective.name
        if name == "nearest":          # squared change, relative to each variable's bounds
            width = np.maximum(self.bounds[:, 1] - self.bounds[:, 0], 1e-9)
            return ObjectiveParts(f=ca.sumsqr((x - self.init) / width))
        if name == "robust":
            return MaxMinMargin()
        if name in PEAK_UNITS:
            return self._peak_objective(v)
        # smooth: minimise the peak squared acceleration over the turn (an epigraph variable z)
        m = self.spec.solver.samples_per_turn
        grid = np.linspace(0.0, TWO_PI, m, endpoint=False).reshape(1, -1)
        acc = tip_derivatives(self.spec.arm.branch).map(m)(grid, self._arm(v))[2] * self.omega**2
        z = ca.SX.sym("peak_acc_sq")
        # z: the peak squared acceleration in units of (omega^2 x 100 mm)^2, a plain number
        return ObjectiveParts(f=z, extra=z, extra_lb=[0.0], extra_ub=[math.inf], extra_init=[0.0],
                              rows=[(z - ca.vec(ca.sum1(acc**2)) / self._smooth_scale(), 0.0, None)],
                              extra_units=[""], row_units=[""])

    def _peak_objective(self, v) -> ObjectiveParts:
        """Minimise the peak input torque, shaking force or shaking moment over a turn (an epigraph variable, scaled
        by the given design's peak so the objective is about 1 at the start; the force's epigraph is in N^2)."""
        spec, name, n = self.spec, self.spec.objective.name, self.spec.solver.samples_per_turn
        peak = self.float_peak(PlantingScene.from_spec(spec), n)
        # a given design that cannot turn (NaN) or moves no mass (0) gives no scale: 1 in the rule's unit then, so
        # the objective stays finite from every start
        peak = peak if math.isfinite(peak) and peak > 0.0 else 1.0
        self.peak_typical = peak * peak if name == "min_peak_shaking_force" else peak
        t, rows, unit = peak_epigraph(arm_linkage(spec.dynamics, self._arm(v), spec.arm.branch, self.omega_sym,
                                                  counterweight_of(v), rocker_counterweight_of(v), self.contact),
                                      name, n)
        return ObjectiveParts(f=t / self.peak_typical, extra=t, extra_lb=[0.0], extra_ub=[math.inf],
                              extra_init=[self.peak_typical], rows=rows, extra_units=[unit],
                              row_units=[unit] * len(rows))

    def _smooth_scale(self) -> float:
        return (self.omega**2 * 100.0) ** 2

    def float_peak(self, scene: PlantingScene, samples: int) -> float:
        """The min-peak objective's peak of a numeric design over ``samples`` crank angles, at the nominal operating
        condition (NaN where the crank cannot turn; with a soil law its surface is found from the design's own lowest
        point, which a crank that does not turn has not)."""
        table = self.spec.dynamics
        assert table is not None             # a min-peak objective needs the table (the spec's validator)
        contact = None
        if table.soil is not None:
            try:
                if assembly_status(scene.design) is not None:
                    return math.nan
            except AssemblyError:
                return math.nan
            contact = soil_contact(scene)
        return float(peak_of(arm_linkage(table, scene.design.parameters(), self.spec.arm.branch, self.omega,
                                         scene.counterweight, scene.rocker_counterweight, contact),
                             self.spec.objective.name, samples))

    # ------------------------------------------------------------------ solving

    def theta_guess(self, values: dict[str, float]) -> np.ndarray:
        """Crank angles of P1-P6 for a start: the numeric precision points where they exist."""
        scene = PlantingScene.from_spec(self.spec, values)
        try:
            pts = find_precision_points(scene)
            th5 = pts.theta["P5"]
            assert th5 is not None        # the lowest point of a turn always exists where the linkage assembles
        except Exception:   # noqa: BLE001 - a start that does not assemble: spread the points over the turn
            pts, th5 = None, 0.0
        spread = {"P5": 0.0, "P6": 0.6, "P1": 2.5, "P2": 3.2, "P3": 3.6, "P4": 5.4}
        out = []
        for n in POINTS:
            t = pts.theta[n] if pts is not None else None
            out.append(th5 + spread[n] if t is None else t)
        if self.clearance > 0.0:      # the loop's top: the highest sample above the seedbed between P6 and P2
            lo, hi = out[POINTS.index("P6")], out[POINTS.index("P2")]
            grid = np.linspace(lo, hi if hi > lo else lo + TWO_PI, 721)[1:-1]
            pos = tip_derivatives(self.spec.arm.branch).map(len(grid))(grid.reshape(1, -1),
                                                                       scene.design.parameters())[0]
            out.append(float(grid[int(np.argmax(scene.seedbed.height(np.asarray(pos, float))))]))
        for name in self.free_poses:     # a free pose: the nearest sample of the start design's path
            out.append(self.nearest_sample(scene, self.spec.key_poses[name].tip))
        return np.array(out)

    @staticmethod
    def nearest_sample(scene: PlantingScene, target, samples: int = 720) -> float:
        """The crank angle (rad) of the sample of a turn where the start design's tip comes nearest ``target`` (mm);
        0 where it assembles nowhere on the turn."""
        grid = np.linspace(0.0, TWO_PI, samples, endpoint=False)
        pos = path_positions(scene.design, grid)
        distance = (pos[0] - target[0]) ** 2 + (pos[1] - target[1]) ** 2
        return float(grid[int(np.nanargmin(distance))]) if np.isfinite(distance).any() else 0.0

    def objective_value(self, f: float, elastic: bool) -> float:
        """The NLP's objective in report units: nearest as solved, robust as the smallest normalised
        margin at the solver's samples (the fine-grid re-check replaces it), smooth as peak |a| in mm/s^2, a peak
        objective as its peak at the solver's samples (N m for the torque and the moment, N for the force)."""
        if elastic:
            return f
        if self.spec.objective.name == "robust":
            return -f
        if self.spec.objective.name == "smooth":
            return math.sqrt(max(f, 0.0)) * self.omega**2 * 100.0
        if self.spec.objective.name in ("min_peak_torque", "min_peak_shaking_moment"):   # N m at the solver's samples
            return f * self.peak_typical
        if self.spec.objective.name == "min_peak_shaking_force":   # N at the solver's samples
            return math.sqrt(max(f * self.peak_typical, 0.0))
        return f

    def start(self, x_design: np.ndarray, elastic: bool) -> tuple[np.ndarray, None]:
        """The decision vector of a start: its design and the crank angles of P1-P6 guessed from its numeric
        points."""
        x_design = np.asarray(x_design, dtype=float)
        return np.concatenate([x_design, self.theta_guess(dict(zip(self.names, x_design)))]), None

    def design(self, x: np.ndarray) -> dict:
        """The design variables of a solution; a counterweight's mass or radius at its lower bound 0 comes back from
        IPOPT up to its bound relaxation (1e-8) below it, which the spec would refuse as negative (its solved.toml
        could not be checked): those are taken at 0."""
        design = dict(zip(self.names, (float(v) for v in x[:len(self.names)])))
        for name in NOT_NEGATIVE:
            if name in design and design[name] < 0.0:
                design[name] = 0.0
        return design

    def reported(self, out: NLPOutcome, design: dict, elastic: bool) -> float:
        """A start's objective in report units; a peak objective is the design's own peak on the check's grid."""
        if self.spec.objective.name in PEAK_UNITS and not elastic:
            return self.float_peak(PlantingScene.from_spec(self.spec, design), CHECK_TURN_SAMPLES)
        return self.objective_value(out.objective, elastic)

    def details(self, out: NLPOutcome, compiled: CompiledNLP) -> dict:
        """A start's crank angles of P1-P6 and of the free key poses (deg), and the objective at the solver's own
        samples."""
        n = len(self.names)
        crank = {k: math.degrees(float(t)) for k, t in zip(POINTS, out.x[n:n + 6])}
        first = n + self.pose_offset
        crank.update({f"key pose {name}": math.degrees(float(t))
                      for name, t in zip(self.free_poses, out.x[first:first + len(self.free_poses)])})
        return {"solver_crank_deg": crank, "solver_objective": self.objective_value(out.objective, compiled.elastic)}
