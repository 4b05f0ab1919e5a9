"""The clamp-cam NLP: every rule of a clamp_cam spec as an IPOPT constraint (CasADi, exact AD).

Decision variables: the design variables of the spec (fixed ones get lo = hi): base radius,
roller radius, offset or pivot distance and arm length, where the rise starts and the four
segment angles; plus tau, the peak |pressure angle|, for that objective.  The rise and the return
are sampled at fixed fractions u of their length, so the normalised law values are numbers and
the segment angles enter smoothly (ds/dphi = h v(u)/beta, d2s/dphi2 = h a(u)/beta^2).  Pressure
angle and curvature are semi-infinite rules sampled here; solve re-checks them on a 10x finer grid
without CasADi.  The NLP itself (rows, backoff, elastic slacks, IPOPT and its log) is the core's
:class:`synthesis.core.problem.Problem`, transcribed by the core; this module declares the kind's variables, rows and objective.
"""

from __future__ import annotations

import dataclasses
import math

import casadi as ca
import numpy as np

from synthesis.constraints.base import Rule
from synthesis.kinds.clamp_cam.motion import Timing
from synthesis.kinds.clamp_cam.scene import (DynamicsTrace, body_of, decelerating, follower_of, generalised_unit,
                                             omega_of, rules_of, stroke_of)
from synthesis.core.declared import Declared, named
from synthesis.core.kind import Setting
from synthesis.core.problem import Envelope, ObjectiveParts, Operating, Problem, Row, per_rule_backoff
from synthesis.kinds.clamp_cam.kinematics import cam_follower as cf
from synthesis.kinds.clamp_cam.kinematics import follower_dynamics as fd
from synthesis.kinds.clamp_cam.kinematics.motion_laws import law as closed_form_law
from synthesis.kinds.clamp_cam.spec import ClampCamSpec
from synthesis.spec.design_info import units_of
from synthesis.spec.common import bounds_of, value_of
from synthesis.spec.operating import ranges_of

DEG = math.pi / 180.0
#: sampled rules: tightened by the backoff so they hold between the samples too (timing rows are exact)
SAMPLED = ("pressure_angle_rise", "pressure_angle_return", "no_undercut", "no_undercut_outer", "max_acceleration",
           "contact_force_min", "hertz_stress_max", "jump_speed_min")
#: unit of each objective's value in the result; nearest: the squared changes, each relative to its bounds' width;
#: spring_force: N, or N m for an oscillating follower's torsional spring (:func:`objective_unit`)
OBJECTIVE_UNITS = {"base_radius": "mm", "pressure_angle": "deg", "nearest": "-", "spring_force": "N"}


def objective_unit(spec: ClampCamSpec) -> str:
    """The unit of the spec's objective value in the result."""
    if spec.objective.name == "spring_force":
        return generalised_unit(spec)
    return OBJECTIVE_UNITS[spec.objective.name]


def peak_spring_load(spec: ClampCamSpec, v):
    """The spring's largest load over the turn, at full stroke: preload + stiffness x stroke (N, or N m), of
    design values ``v`` (numbers or CasADi symbols)."""
    d = spec.dynamics
    assert d is not None, "the spring_force objective needs a [dynamics] table (validated)"
    _, preload, stiffness = d.body_fields(spec.follower.type)
    return v[preload] + v[stiffness] * stroke_of(spec)


def problem(setting: Setting) -> Declared:
    """The problem of one spec (``setting.data``: an optimised law's fit): tau started at a start design's peak
    |pressure angle| (the pressure_angle objective), the objective reported in its units."""
    spec, cam = setting.spec, _CamProblem(setting.spec, setting.data, setting.operating_symbols)
    names, name = cam.names, spec.objective.name

    def start(x_design: np.ndarray, elastic: bool) -> tuple[np.ndarray, np.ndarray | None]:
        """Start value of tau (pressure_angle objective): the start design's peak |pressure angle|."""
        x_design = np.asarray(x_design, dtype=float)
        if elastic or name != "pressure_angle":
            return x_design, None
        alpha = np.asarray(cam.alpha_function(x_design)).ravel()
        return x_design, np.array([float(np.max(np.abs(alpha)))])

    def reported(out, design: dict[str, float], elastic: bool) -> float:
        """The objective in report units: base radius mm, peak pressure angle deg, or the distance."""
        if name == "base_radius":
            return design["base_radius"]
        if name == "pressure_angle":
            return out.objective * 10.0
        if name == "spring_force":
            return peak_spring_load(spec, design)
        return out.objective

    return Declared(cam.problem, names, cam.bounds, cam.init, design=named(names), start=start, objective=reported)


class _CamProblem:
    """The cam's problem, declared piece by piece (variables, sampled pressure angles, rows, rules, objective)."""

    def __init__(self, spec: ClampCamSpec, optimised, operating_symbols: bool):
        self.spec = spec
        variables = spec.variables()
        self.names = list(variables)
        self.bounds = np.array([bounds_of(v) for v in variables.values()], dtype=float)
        self.init = np.array([value_of(v) for v in variables.values()], dtype=float)
        if spec.motion.law == "optimised" and optimised.spring is not None:
            # the spring-shaped law's fit found a spring for it: the NLP starts there, free as the spec says
            assert spec.dynamics is not None, "validation asks the spring-shaped law for a [dynamics] table"
            _, preload, stiffness = spec.dynamics.body_fields(spec.follower.type)
            for name, value in ((preload, optimised.spring["preload"]), (stiffness, optimised.spring["stiffness"])):
                self.init[self.names.index(name)] = value
        x = ca.SX.sym("x", len(self.names))
        self.x = x
        v = {n: x[i] for i, n in enumerate(self.names)}
        if spec.motion.law == "optimised":
            rise_law, return_law = optimised.rise, optimised.return_
        else:
            rise_law = return_law = closed_form_law(spec.motion.law)
        # the tolerance analysis's build only: the crank speed a symbol (resolved at its value by the core), for
        # d rule / d crank speed (the acceleration's omega^2, windows timed in seconds).  Not with an optimised law
        # under an acceleration cap or shaped for the spring: that law is refitted (cvxpy) at each speed, a change
        # the NLP cannot see
        # an operating envelope (a crank-speed range: validation allows it with a closed-form law only) samples it
        ranges = ranges_of(spec)
        refitted_per_speed = spec.motion.law == "optimised" and (spec.rules.max_acceleration is not None
                                                                 or spec.bspline.minimise == "spring_force")
        self.operating = ([Operating("crank_speed", ca.SX.sym("crank_speed"), spec.operation.speed, "r/min")]
                          if ranges or (operating_symbols and not refitted_per_speed)
                          else [])
        alpha, kappa, acc = self._sampled(v, rise_law, return_law)
        self.alpha_function = ca.Function("alpha", [x], [ca.vertcat(alpha["rise"], alpha["return"])])
        dynamics = self._dynamics(v, rise_law, return_law) if spec.dynamics is not None else None
        rules = self._rules(v, alpha, kappa, acc, dynamics)
        backoff = spec.solver.backoff
        structural = self._structural(v)
        translating = spec.follower.type == "translating"
        objective = self._objective(x, v, alpha)
        self.problem = Problem("clamp_cam", x, self.bounds[:, 0], self.bounds[:, 1], structural, rules,
                               objective, max_iter=spec.solver.max_iter, ipopt="moderate",
                               x_units=units_of(spec, self.names),
                               structural_units=["deg", "mm^2"] if translating else ["deg", "mm", "mm^2", "rad"],
                               objective_unit="deg" if spec.objective.name == "pressure_angle" else "",
                               backoff=per_rule_backoff(lambda rule: backoff if rule.name in SAMPLED else 0.0),
                               operating=self.operating,
                               envelope=Envelope({n: r.solver_values() for n, (_, r) in ranges.items()})
                               if ranges else None,
                               # in a tolerance box the follower geometry exists for every design in it: its rows
                               # (all but the first, the turn's 360 deg) held at their linearised worst case
                               robust_structural=tuple(range(1, len(structural))))
        self.rules = self.problem.rules

    # ------------------------------------------------------------------ model pieces

    def _sampled(self, v, rise_law, return_law):
        """Pressure angle (deg) per motion segment, pitch curvature and acceleration at the samples."""
        spec = self.spec
        n = spec.solver.samples_per_segment
        u = np.linspace(0.0, 1.0, n)
        h = stroke_of(spec)
        follower = follower_of(spec, v)
        alpha, kappa, acc = {}, [], []
        for name, law, sign in (("rise", rise_law, 1.0), ("return", return_law, -1.0)):
            beta = v[name] * DEG
            s = h * (law.s(u) if sign > 0 else 1.0 - law.s(u))
            ds = sign * h * ca.DM(law.v(u)) / beta
            dds = sign * h * ca.DM(law.a(u)) / beta**2
            c = cf.roller_centre(follower, ca.DM(s), ds, dds)
            alpha[name] = cf.degrees(cf.pressure_angle(c))
            kappa.append(cf.pitch_curvature(c))
            acc.append(dds)
        # the dwells (at rest and at full stroke) count with the rise: constant angle -atan(e / s0) there
        rest = cf.roller_centre(follower, ca.DM([0.0, h]), ca.DM.zeros(2), ca.DM.zeros(2))
        alpha["rise"] = ca.vertcat(alpha["rise"], cf.degrees(cf.pressure_angle(rest)))
        return alpha, ca.vertcat(*kappa), ca.vertcat(*acc)

    def _dynamics(self, v, rise_law, return_law) -> DynamicsTrace:
        """The follower's loads at the NLP's samples of the rise and the return and one of each dwell (at rest, at
        full stroke), for the [dynamics] rules; its cam speed is set by _rules."""
        spec = self.spec
        n = spec.solver.samples_per_segment
        u = np.linspace(0.0, 1.0, n)
        h = stroke_of(spec)
        follower = follower_of(spec, v)
        body = body_of(spec, v)
        assert body is not None, "only with a [dynamics] table"
        s, ds, dds, pulled = [], [], [], []
        for name, law, sign in (("rise", rise_law, 1.0), ("return", return_law, -1.0)):
            beta = v[name] * DEG
            s.append(ca.DM(h * (law.s(u) if sign > 0 else 1.0 - law.s(u))))
            ds.append(sign * h * ca.DM(law.v(u)) / beta)
            dds.append(sign * h * ca.DM(law.a(u)) / beta**2)
            pulled.append(decelerating(sign * np.asarray(law.a(u), dtype=float)))     # q'' has its sign whatever beta
        s.append(ca.DM([0.0, h]))
        ds.append(ca.DM.zeros(2))
        dds.append(ca.DM.zeros(2))
        pulled.append(np.zeros(2, dtype=bool))
        s_all, dds_all = ca.vertcat(*s), ca.vertcat(*dds)
        c = cf.roller_centre(follower, s_all, ca.vertcat(*ds), dds_all)
        loads = fd.contact_loads(follower, body, c, s_all, dds_all)
        # |dF/d omega^2| at the given design, for the jump rows' scale: the loads' numbers at the start values
        given = np.abs(np.asarray(ca.Function("given", [self.x], [loads.per_omega2])(self.init), dtype=float)).ravel()
        pulled_all = np.concatenate(pulled)
        if spec.motion.law == "optimised" and spec.bspline.minimise == "spring_force" and pulled_all.any():
            # where a jump row can bind: the spring-shaped law lands on the near dwell with |q''| many times the
            # deceleration its spring holds, which would make each row's backoff worth that many times more force
            # (the symmetric laws' two peaks differ by their cos alpha only; they keep the scale they were solved
            # with)
            given = given[pulled_all]
        reference = max(float(np.max(given)), 1e-12)
        return DynamicsTrace(loads, omega_of(spec), cf.pitch_curvature(c), v["roller_radius"], pulled_all, reference)

    def _structural(self, v) -> list[Row]:
        """The segments fill one turn; the follower geometry exists (real s0, the arm reaches the cam)."""
        spec = self.spec
        rows: list[Row] = [(v["rise"] + v["far_dwell"] + v["return"] + v["near_dwell"], 360.0, 360.0)]
        r0 = v["base_radius"]
        if spec.follower.type == "translating":
            rows.append((v["offset"] ** 2 - (0.9 * r0) ** 2, None, 0.0))
        else:
            a, l = v["pivot_distance"], v["arm_length"]
            rows += [(r0 - (a + l), None, -1e-3), ((a - l) ** 2 - r0**2, None, -1e-3)]
            rest = cf.Oscillating(r0, a, l, spec.follower.side).rest_angle()
            rows.append((rest + stroke_of(spec), None, 170.0 * DEG))       # the arm never folds past 170 deg
        return rows

    def _rules(self, v, alpha, kappa, acc, dynamics: DynamicsTrace | None) -> list[Rule]:
        spec = self.spec
        scale = 1.0 if spec.follower.type == "translating" else 180.0 / math.pi     # model -> report units
        reference = Timing.from_design(dict(zip(self.names, self.init)))
        if not self.operating:
            trace = None if dynamics is None else dataclasses.replace(dynamics, omega=omega_of(spec))
            return rules_of(spec, alpha["rise"], alpha["return"], kappa, v["roller_radius"], Timing.from_design(v),
                            acc * (scale * omega_of(spec) ** 2), reference, dynamics=trace)
        n = self.operating[0].symbol
        omega = n * (2.0 * math.pi / 60.0)
        trace = None if dynamics is None else dataclasses.replace(dynamics, omega=omega)
        return rules_of(spec, alpha["rise"], alpha["return"], kappa, v["roller_radius"], Timing.from_design(v),
                        acc * (scale * omega**2), reference, crank_speed=n, dynamics=trace)

    def _objective(self, x, v, alpha) -> ObjectiveParts:
        """base_radius (relative to the given one), nearest (scaled squared change) or pressure_angle:
        the peak |pressure angle| tau (deg) over rise and return, as an epigraph."""
        name = self.spec.objective.name
        if name == "base_radius":
            return ObjectiveParts(f=v["base_radius"] / self.init[self.names.index("base_radius")])
        if name == "spring_force":
            given = peak_spring_load(self.spec, dict(zip(self.names, self.init)))
            return ObjectiveParts(f=peak_spring_load(self.spec, v) / (given if given > 0.0 else 1.0))
        if name == "nearest":
            width = np.maximum(self.bounds[:, 1] - self.bounds[:, 0], 1e-9)
            return ObjectiveParts(f=ca.sumsqr((x - self.init) / width))
        tau = ca.SX.sym("tau")
        both = ca.vertcat(alpha["rise"], alpha["return"])
        return ObjectiveParts(f=tau / 10.0, extra=tau, extra_lb=[0.0], extra_ub=[90.0], extra_init=[0.0],
                              rows=[(tau - both, 0.0, None), (tau + both, 0.0, None)], extra_units=["deg"],
                              row_units=["deg", "deg"])
