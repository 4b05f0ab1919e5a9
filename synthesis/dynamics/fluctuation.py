"""The crank's speed over a turn when the motor's torque is constant, and the flywheel that keeps it steady.

Model.  The motor puts a constant torque T_m on the crank shaft; everything turning with the shaft (flywheel, gears,
the motor's rotor reflected to it) has the inertia J_f.  The four-bar, reduced to its crank angle theta, has

* the generalized inertia J_m(theta) = 2 x its kinetic energy at omega = 1 (so its kinetic energy is
  1/2 J_m omega^2),
* the potential V(theta) of gravity,
* the external loads' power P_ext(theta, omega): constant forces and couples give omega times a function of theta;
  the soil law's force turns with the point's velocity relative to the soil, so its power/omega depends on omega.

Lagrange's equation of the crank angle, with omega d(omega)/d(theta) = alpha, the crank's angular acceleration::

    (J_f + J_m) omega d(omega)/d(theta) + 1/2 J_m' omega^2 = T_m - V' + P_ext / omega

(' is d/d(theta)).  The linkage's load torque at a speed, T_load(theta, omega) = 1/2 J_m' omega^2 + V' -
P_ext / omega, is what the shaft must give the crank to hold that speed (the constant-speed input torque); the shaft
gives the crank T_m - J_f alpha, and the linkage's inverse dynamics at (omega, alpha) must return exactly that (the
equation above, which is built here from the energies alone, while :mod:`synthesis.dynamics.fourbar`'s torque comes
from Newton-Euler: tests/test_speed_fluctuation.py holds the two together).

The steady state is the periodic solution, omega(theta + 2 pi) = omega(theta), whose mean speed is the nominal crank
speed.  The mean is the time mean over a turn, 2 pi / (time of a turn): a turn then takes as long as at the nominal
speed, so a planter's plant spacing (forward speed x time of a turn) is the nominal one.  Over a periodic turn the
kinetic and potential energies come back, so the motor's work is the loads' work: T_m 2 pi = -integral of
P_ext / omega d(theta), the mean load torque over the turn.  When the loads' power is proportional to omega (no
soil), that is a number known before the speed is (the mean of the constant-speed input torque), every solution
is periodic, and the shooting is on omega(0) alone; with the soil law T_m and omega(0) are found together.  Both by
scipy: ``solve_ivp`` (DOP853, relative tolerance :data:`RTOL`) integrates omega and the time over the turn,
``scipy.optimize.root`` finds omega(0) (and T_m) from the periodicity and the mean.  The coefficient of speed
fluctuation is delta = (omega_max - omega_min) / omega_mean, its extremes where alpha = 0 (located by
``solve_ivp``'s events, not read off the samples).

Flywheel sizing (the classic approximation).  At constant nominal speed omega_n the shaft would have to give
T_load(theta, omega_n); with the constant T_m instead, the energy surplus E(theta) = integral from 0 to theta of
(T_m - T_load) d(theta) goes into the turning masses' kinetic energy.  Its largest swing over a turn, Delta E_max =
max E - min E, is what the turning masses' kinetic energy 1/2 J omega^2 swings by, 1/2 J (omega_max^2 -
omega_min^2) = J omega_mean^2 delta when omega_max + omega_min = 2 omega_mean; so, to first order in delta,

    J_f = Delta E_max / (delta omega_n^2) - J_m_mean,

J_m_mean the linkage's generalized inertia averaged over the crank angle (it turns with the flywheel; where the
extremes fall J_m differs from its mean, one source of the formula's error, the other the neglected terms of order
delta).  The ODE with that J_f then gives the coefficient actually achieved, reported beside the one asked for.
As J_f grows, delta (J_f + J_m_mean) omega_n^2 / Delta E_max -> 1.

Numbers only (check and result.json): no rule reads the fluctuation.  A clockwise crank (omega < 0) is the same
equations with theta still running over [0, 2 pi]; the coefficient uses |omega|.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import casadi as ca
import numpy as np

from synthesis.dynamics.facts import peaks
from synthesis.dynamics.fourbar import JOINTS, SOIL, inverse_dynamics

TWO_PI = 2.0 * math.pi
#: solve_ivp's relative tolerance (each state's absolute tolerance is this times the state's own scale)
RTOL = 1.0e-10
#: what the mean crank speed is
MEAN = ("time mean over a turn, 2 pi / (time of a turn): a turn takes as long as at the nominal speed (a planter's "
        "plant spacing stays the nominal one)")
#: the crank counts as stalled below this fraction of the nominal speed (no steady turn at that mean speed)
STALL_FRACTION = 1.0e-3


class NoSteadySpeed(ValueError):
    """No periodic crank speed was found (the crank stalls within a turn, or the root finding failed)."""


class CrankModel:
    """A four-bar reduced to its crank angle: J_m(theta), J_m'(theta), V'(theta) and P_ext(theta, omega), built from
    the energies of :func:`synthesis.dynamics.fourbar.inverse_dynamics` with CasADi's exact derivatives in theta.

    ``linkage``: a :class:`synthesis.dynamics.linkage.FourbarDynamics` on numbers (its omega and alpha are not
    read: the speed is this model's unknown); its couples, if any, one constant value per link."""

    def __init__(self, linkage) -> None:
        moments = linkage.moments
        if moments is not None and np.size(moments) != 3:
            raise ValueError("speed fluctuation: the couples on the links must be constant over the turn (one value "
                             "per link), not given per sample")
        self.soil = None if linkage.soil is None else tuple(float(v) for v in linkage.soil)
        f = inverse_dynamics(linkage.branch, moments is not None, self.soil is not None)
        theta, omega = ca.SX.sym("theta"), ca.SX.sym("omega")

        def energies(speed):
            out = f(theta, ca.DM(list(linkage.geometry)), ca.DM(list(linkage.mass)), ca.DM(list(linkage.loads)),
                    speed, 0.0, ca.DM([0.0, 0.0, 0.0] if moments is None else list(np.ravel(moments))),
                    ca.DM(list(self.soil) if self.soil is not None else [0.0] * len(SOIL)),
                    ca.DM(list(linkage.gravity)))
            return dict(zip(f.name_out(), out))

        at_unit_speed, at_speed = energies(1.0), energies(omega)
        inertia = 2.0 * at_unit_speed["kinetic_energy"]
        inertia_rate = ca.jacobian(inertia, theta)
        gravity_torque = ca.jacobian(at_unit_speed["potential_energy"], theta)
        load_power_per_speed = at_speed["external_power"] / omega
        load_torque = 0.5 * inertia_rate * omega ** 2 + gravity_torque - load_power_per_speed
        #: (theta, omega) -> J_m kg m^2, T_load N m, P_ext / omega N m, the soil point's depth mm (0 without soil)
        self.terms = ca.Function("crank_terms", [theta, omega],
                                 [inertia, load_torque, load_power_per_speed, at_unit_speed["soil_depth"]],
                                 ["theta", "omega"], ["inertia", "load_torque", "load_power_per_speed", "depth"])
        #: crank angles (rad, in (0, 2 pi)) where the soil point enters or leaves the soil: the soil force starts or
        #: stops there (with a jump when f0 > 0), so the integration restarts at each instead of stepping over it
        self.breaks = self._soil_crossings() if self.soil is not None else ()
        motor, flywheel = ca.SX.sym("motor_torque"), ca.SX.sym("flywheel_inertia")
        alpha = (motor - load_torque) / (flywheel + inertia)
        # one flat input and output, read through CasADi's buffer: a call costs ~2 us instead of ~50 us, and the
        # integrator calls it some 500 times a turn
        self._ode = ca.Function("crank_ode", [ca.vertcat(theta, omega, motor, flywheel)],
                                [ca.vertcat(alpha / omega, 1.0 / omega, load_power_per_speed, alpha, inertia,
                                            load_torque)])

    def _soil_crossings(self, grid: int = 3600) -> tuple[float, ...]:
        from scipy.optimize import brentq

        theta = np.linspace(0.0, TWO_PI, grid + 1)
        depth = self.at(theta, 1.0)["depth"]

        def depth_at(t: float) -> float:
            return float(self.terms(t, 1.0)[3])

        crossings = [brentq(depth_at, theta[k], theta[k + 1], xtol=1.0e-14)
                     for k in range(grid) if depth[k] * depth[k + 1] < 0.0]
        return tuple(t for t in crossings if 0.0 < t < TWO_PI)

    @property
    def speed_independent_loads(self) -> bool:
        """Whether P_ext / omega is a function of theta alone (no soil law), so T_m is known before the speed."""
        return self.soil is None

    def evaluator(self):
        """A fast float evaluation of the ODE: (theta, omega, T_m, J_f) -> (d omega/d theta, d t/d theta,
        P_ext / omega, alpha, J_m, T_load)."""
        buffer, evaluate = self._ode.buffer()
        arg, res = np.zeros(4), np.zeros(6)
        buffer.set_arg(0, memoryview(arg))
        buffer.set_res(0, memoryview(res))

        def call(theta: float, omega: float, motor: float, flywheel: float) -> np.ndarray:
            arg[0], arg[1], arg[2], arg[3] = theta, omega, motor, flywheel
            evaluate()
            return res.copy()

        # the buffer holds the pointers evaluate() writes through: it must live as long as call does
        call.buffer = buffer  # type: ignore[attr-defined]

        return call

    def at(self, crank: np.ndarray, omega) -> dict[str, np.ndarray]:
        """J_m, T_load and P_ext / omega at the crank angles ``crank`` (rad) and speeds ``omega`` (one or per
        sample)."""
        n = int(np.size(crank))
        out = self.terms.map(n)(np.asarray(crank, float).reshape(1, -1),
                                np.broadcast_to(np.asarray(omega, float), (n,)).reshape(1, -1))
        return {k: np.asarray(v, float).ravel() for k, v in zip(self.terms.name_out(), out)}


@dataclass(frozen=True)
class ConstantSpeedEnergy:
    """The turn at the constant nominal speed: the mean load torque (the motor's constant torque), the energy
    surplus's largest swing Delta E_max and where its extremes are, and the linkage's mean generalized inertia."""

    omega: float
    mean_load_torque: float
    energy_swing: float
    surplus_max_at: float
    surplus_min_at: float
    mean_inertia: float


@dataclass(frozen=True)
class SteadySpeed:
    """The periodic crank speed with a flywheel: the motor torque, the speed and acceleration at the samples, the
    extremes and the coefficient, and the turn's balance (each as the ODE gives it)."""

    flywheel_inertia: float
    omega_mean: float
    motor_torque: float
    crank: np.ndarray
    omega: np.ndarray
    alpha: np.ndarray
    omega_min: float
    omega_min_at: float
    omega_max: float
    omega_max_at: float
    coefficient: float
    periodicity_residual: float
    turn_time: float
    load_work: float

    @property
    def motor_work(self) -> float:
        """The motor's work over a turn, J (T_m times the crank's turn, in its direction)."""
        return self.motor_torque * TWO_PI * math.copysign(1.0, self.omega_mean)


@dataclass(frozen=True)
class FlywheelSizing:
    """The classic flywheel for a coefficient, and the coefficient the ODE gives with it."""

    coefficient: float
    inertia: float
    formula_inertia: float
    achieved: SteadySpeed

    @property
    def relative_error(self) -> float:
        """(achieved - asked) / asked: the classic formula's error."""
        return (self.achieved.coefficient - self.coefficient) / self.coefficient


@dataclass
class _Turn:
    """solve_ivp's answer over the turn, gathered over the pieces between the model's breaks."""

    status: int                      # 0: the whole turn; 1: a terminal event or a failed step stopped it
    t_end: float                     # where it stopped (2 pi for the whole turn)
    y_end: np.ndarray
    t_edges: np.ndarray              # 0, the breaks and 2 pi (as far as the integration went)
    y_edges: np.ndarray              # the state there, one column each
    t_eval: np.ndarray
    y_eval: np.ndarray
    t_events: list
    y_events: list


def _integrate(fun, y0, breaks=(), events=None, t_eval=None, atol=None) -> _Turn:
    """``fun`` integrated over theta from 0 to 2 pi by solve_ivp (DOP853, :data:`RTOL`), restarted at each of
    ``breaks`` (where the right-hand side jumps or kinks); ``t_eval`` in [0, 2 pi]; ``events`` as solve_ivp's."""
    from scipy.integrate import solve_ivp

    events = list(events or [])
    edges = [0.0, *sorted(breaks), TWO_PI]
    wanted = np.asarray([] if t_eval is None else t_eval, float)
    y = np.asarray(y0, float)
    ts, ys = [], []
    t_edges, y_edges = [0.0], [y]
    t_events: list[list] = [[] for _ in events]
    y_events: list[list] = [[] for _ in events]
    status = 0
    for k, (start, stop) in enumerate(zip(edges[:-1], edges[1:])):
        last = k == len(edges) - 2
        here = wanted[(wanted >= start) & ((wanted <= stop) if last else (wanted < stop))]
        # the piece's end is always asked for: the next piece starts from it
        times = None if t_eval is None else np.unique(np.append(here, stop))
        run = solve_ivp(fun, (start, stop), y, method="DOP853", rtol=RTOL, atol=atol, events=events or None,
                        t_eval=times)
        for j in range(len(events)):
            t_events[j] += list(run.t_events[j])
            y_events[j] += list(run.y_events[j])
        if run.status != 0:
            status, stop = 1, float(run.t[-1])
            break
        y = run.y[:, -1]
        t_edges.append(stop)
        y_edges.append(y)
        if t_eval is not None:
            kept = np.isin(run.t, here)
            ts.append(run.t[kept])
            ys.append(run.y[:, kept])
    return _Turn(status, stop, y, np.asarray(t_edges), np.column_stack(y_edges), np.concatenate(ts) if ts else np.zeros(0),
                 np.concatenate(ys, axis=1) if ys else np.zeros((len(y0), 0)),
                 [np.asarray(t) for t in t_events], [np.asarray(v).reshape(-1, len(y0)) for v in y_events])


def constant_speed_energy(model: CrankModel, omega: float) -> ConstantSpeedEnergy:
    """The turn at constant speed ``omega`` (rad/s): T_m the mean load torque, the surplus E(theta) = integral of
    (T_m - T_load) and its largest swing, the mean of J_m over theta; by solve_ivp (the surplus's extremes are its
    events, where T_load = T_m)."""
    call = model.evaluator()

    def first(theta, y):
        r = call(theta, omega, 0.0, 0.0)
        return [-r[5], r[4]]

    scale = max(float(np.abs(model.at(np.linspace(0.0, TWO_PI, 64, endpoint=False), omega)["load_torque"]).max()),
                1.0e-12)
    whole = _integrate(first, [0.0, 0.0], model.breaks, atol=[RTOL * scale, RTOL * 1.0e-6])
    if whole.status != 0:
        raise NoSteadySpeed(f"the load torque could not be integrated over the turn at constant speed (stopped at "
                            f"{math.degrees(whole.stop):.1f} deg)")
    mean_torque = -float(whole.y_end[0]) / TWO_PI
    mean_inertia = float(whole.y_end[1]) / TWO_PI

    def surplus(theta, y):
        return [mean_torque - call(theta, omega, 0.0, 0.0)[5]]

    def turning(theta, y):
        return mean_torque - call(theta, omega, 0.0, 0.0)[5]

    run = _integrate(surplus, [0.0], model.breaks, events=[turning], atol=RTOL * scale)
    if run.status != 0:
        raise NoSteadySpeed(f"the energy surplus could not be integrated over the turn at constant speed (stopped at "
                            f"{math.degrees(run.stop):.1f} deg)")
    # the extremes: where T_load = T_m (the events), or at a break, where T_load may jump across T_m
    at = np.concatenate([run.t_edges, run.t_events[0]])
    values = np.concatenate([run.y_edges[0], run.y_events[0][:, 0]])
    high, low = int(np.argmax(values)), int(np.argmin(values))
    return ConstantSpeedEnergy(omega, mean_torque, float(values[high] - values[low]), float(at[high]), float(at[low]),
                               mean_inertia)


def steady_speed(model: CrankModel, flywheel_inertia: float, omega_mean: float, crank: np.ndarray,
                 constant: ConstantSpeedEnergy | None = None) -> SteadySpeed:
    """The periodic crank speed whose time mean over a turn is ``omega_mean`` (rad/s, negative: clockwise) with the
    flywheel ``flywheel_inertia`` (kg m^2, 0 allowed when the linkage's own inertia carries the turn), sampled at
    ``crank`` (rad, in [0, 2 pi)).  Raises :class:`NoSteadySpeed` when none is found."""
    from scipy.optimize import root

    call = model.evaluator()
    constant = constant or constant_speed_energy(model, omega_mean)
    sign = math.copysign(1.0, omega_mean)
    stall = STALL_FRACTION * abs(omega_mean)
    # the state is u = omega - omega(0), not omega: with a large flywheel the swing is 1e-5 of omega or less, and a
    # tolerance relative to omega itself would not resolve it; u's scale is the first-order swing
    swing = abs(omega_mean) * min(1.0, constant.energy_swing / max((flywheel_inertia + constant.mean_inertia)
                                                                   * omega_mean ** 2, 1.0e-300))
    atol = [RTOL * max(swing, 1.0e-9 * abs(omega_mean)), RTOL * TWO_PI / abs(omega_mean),
            RTOL * max(abs(constant.mean_load_torque), constant.energy_swing, 1.0e-12)]

    def turn(omega0: float, motor: float, events=None, t_eval=None):
        def rhs(theta, y):
            return call(theta, omega0 + y[0], motor, flywheel_inertia)[:3]

        def stalled(theta, y):
            return sign * (omega0 + y[0]) - stall

        stalled.terminal = True  # type: ignore[attr-defined]
        return _integrate(rhs, [0.0, 0.0, 0.0], model.breaks, events=[stalled] + (events or []), t_eval=t_eval,
                          atol=atol)

    stalls = []

    def residuals(x):
        omega0 = omega_mean * x[0]
        motor = constant.mean_load_torque if model.speed_independent_loads else x[1] * torque_scale
        run = turn(omega0, motor)
        if run.status == 1:                      # stalled: no turn from this start
            stalls.append(run.t_end)
            return [math.nan] * len(x)
        mean = TWO_PI / run.y_end[1]
        out = [mean / omega_mean - 1.0]
        if not model.speed_independent_loads:
            out.append(run.y_end[0] / omega_mean)
        return out

    torque_scale = max(abs(constant.mean_load_torque), constant.energy_swing / TWO_PI, 1.0e-9)
    x0 = [1.0] if model.speed_independent_loads else [1.0, constant.mean_load_torque / torque_scale]
    found = root(residuals, x0, method="hybr", options={"xtol": 1.0e-12})
    if not found.success or not np.all(np.isfinite(found.fun)) or np.abs(found.fun).max() > 1.0e-8:
        why = (f"the crank all but stops within the turn (below {STALL_FRACTION:.1%} of the mean speed): the inertia "
               f"turning with it cannot carry it through the turn's energy swing at this speed" if stalls
               else "scipy's root: " + " ".join(found.message.split()))
        raise NoSteadySpeed(f"no periodic crank speed with mean {omega_mean:.6g} rad/s and flywheel "
                            f"{flywheel_inertia:.6g} kg m^2: {why}")
    omega0 = omega_mean * float(found.x[0])
    motor = constant.mean_load_torque if model.speed_independent_loads else float(found.x[1]) * torque_scale

    def turning(theta, y):
        return call(theta, omega0 + y[0], motor, flywheel_inertia)[3]

    samples = np.asarray(crank, float)
    run = turn(omega0, motor, events=[turning], t_eval=np.append(samples, TWO_PI))
    if run.status != 0:
        raise NoSteadySpeed(f"the crank stalls within a turn at mean {omega_mean:.6g} rad/s with flywheel "
                            f"{flywheel_inertia:.6g} kg m^2")
    omega = omega0 + run.y_eval[0, :-1]
    alpha = np.array([call(t, w, motor, flywheel_inertia)[3] for t, w in zip(samples, omega)])
    # the extremes: where alpha = 0 (the events), or at a break, where alpha may jump across 0
    at = np.concatenate([run.t_edges, run.t_events[1]])
    values = omega0 + np.concatenate([run.y_edges[0], run.y_events[1][:, 0]])
    speeds = sign * values
    high, low = int(np.argmax(speeds)), int(np.argmin(speeds))
    return SteadySpeed(
        flywheel_inertia=float(flywheel_inertia), omega_mean=float(omega_mean), motor_torque=float(motor),
        crank=samples, omega=omega, alpha=alpha,
        omega_min=float(values[low]), omega_min_at=float(at[low] % TWO_PI),
        omega_max=float(values[high]), omega_max_at=float(at[high] % TWO_PI),
        coefficient=float((speeds[high] - speeds[low]) / abs(omega_mean)),
        periodicity_residual=float(run.y_end[0]), turn_time=float(abs(run.y_end[1])),
        load_work=float(run.y_end[2] * sign))


def flywheel_for(model: CrankModel, coefficient: float, omega_mean: float, crank: np.ndarray,
                 constant: ConstantSpeedEnergy | None = None) -> FlywheelSizing:
    """The flywheel for the coefficient of speed fluctuation ``coefficient`` by the classic formula, J_f =
    Delta E_max / (delta omega_n^2) - J_m_mean (none, 0, when the linkage's own inertia is enough), and the
    periodic speed the ODE gives with it."""
    constant = constant or constant_speed_energy(model, omega_mean)
    formula = constant.energy_swing / (coefficient * omega_mean ** 2) - constant.mean_inertia
    inertia = max(formula, 0.0)
    return FlywheelSizing(coefficient, inertia, formula, steady_speed(model, inertia, omega_mean, crank, constant))


def speed_fluctuation_facts(linkage, crank: np.ndarray, drive, joint_names: tuple[str, ...] = JOINTS) -> dict:
    """result.json's ``facts.dynamics.speed_fluctuation`` of a ``[dynamics] drive`` (:class:`synthesis.spec.dynamics.
    Drive`): the periodic speed with the given flywheel (or, given only a coefficient, with the flywheel sized for
    it), the shaft's torque on the crank and the shaking force at that speed at the samples ``crank`` (rad, the
    dynamics' own), and the flywheel for ``drive.speed_fluctuation``.  ``linkage``: a
    :class:`synthesis.dynamics.linkage.FourbarDynamics` on numbers at the nominal crank speed; ``joint_names``: the
    kind's names of its joints, in :data:`synthesis.dynamics.fourbar.JOINTS`' order."""
    omega_mean = float(linkage.omega)
    model = CrankModel(linkage)
    constant = constant_speed_energy(model, omega_mean)
    out: dict = {"model": "constant motor torque; the flywheel and the linkage's generalized inertia turn with the "
                          "crank; the periodic speed whose mean is the nominal crank speed",
                 "mean": MEAN, "mean_crank_speed_radps": omega_mean,
                 "constant_speed": {"motor_torque_Nm": constant.mean_load_torque,
                                    "energy_swing_J": constant.energy_swing,
                                    "surplus_max_at_crank_deg": math.degrees(constant.surplus_max_at),
                                    "surplus_min_at_crank_deg": math.degrees(constant.surplus_min_at),
                                    "linkage_mean_inertia_kgm2": constant.mean_inertia}}
    sizing = None
    try:
        if drive.speed_fluctuation is not None:
            sizing = flywheel_for(model, drive.speed_fluctuation, omega_mean, crank, constant)
            out["flywheel_for_coefficient"] = {
                "coefficient": sizing.coefficient, "inertia_kgm2": sizing.inertia,
                "formula": "Delta E_max / (coefficient omega^2) - linkage_mean_inertia (0 when negative)",
                "formula_inertia_kgm2": sizing.formula_inertia,
                "achieved_coefficient": sizing.achieved.coefficient, "relative_error": sizing.relative_error}
        if drive.flywheel_inertia is not None:
            speed = steady_speed(model, drive.flywheel_inertia, omega_mean, crank, constant)
            given = "drive.flywheel_inertia"
        else:
            assert sizing is not None               # Drive requires one of the two
            speed, given = sizing.achieved, "sized for drive.speed_fluctuation"
    except NoSteadySpeed as exc:
        return {**out, "found": False, "why": str(exc)}
    at_speed = replace(linkage, omega=speed.omega, alpha=speed.alpha).over_turn(crank)
    torque, force = at_speed["torque"], at_speed["shaking_force"]
    # the shared Function counts minus the crank's torque as its driver's reaction on the frame; here the driver is
    # the shaft with its flywheel, and the frame holds only the motor's stator: -T_m = -(shaft torque) - J_f alpha
    moment = at_speed["shaking_moment"] - speed.flywheel_inertia * speed.alpha
    return {**out, "found": True,
            "flywheel_inertia_kgm2": speed.flywheel_inertia, "flywheel_inertia_from": given,
            "motor_torque_Nm": speed.motor_torque,
            "crank_speed_radps": speed.omega.tolist(), "crank_acceleration_radps2": speed.alpha.tolist(),
            "coefficient": speed.coefficient,
            "omega_min_radps": speed.omega_min, "omega_min_at_crank_deg": math.degrees(speed.omega_min_at),
            "omega_max_radps": speed.omega_max, "omega_max_at_crank_deg": math.degrees(speed.omega_max_at),
            "periodicity_residual_radps": speed.periodicity_residual, "turn_time_s": speed.turn_time,
            "shaft_torque_Nm": torque.tolist(), "shaking_force_N": force.T.tolist(),
            "shaking_moment_Nm": moment.tolist(),
            "summary": {"shaft_torque_Nm": peaks(torque, crank),
                        "shaking_force_N": peaks(np.hypot(force[0], force[1]), crank),
                        "shaking_moment_Nm": peaks(moment, crank),
                        "joints_N": {name: peaks(np.hypot(*at_speed["reactions"][:, k, :]), crank)
                                     for k, name in enumerate(joint_names)}}}
