"""The energy balance of a result's ``facts.dynamics``, re-checked from the file alone (every kind with dynamics)."""

from __future__ import annotations

import math

import numpy as np


def input_power(dyn: dict) -> np.ndarray:
    """The power put in at each sample, W: the drive's, the external loads' and the friction's where there is one."""
    power = np.array(dyn["power_W"])
    if dyn["external_loads"]:
        power = power + np.array(dyn["external_loads"]["external_power_W"])
    if "friction_power_W" in dyn:
        power = power + np.array(dyn["friction_power_W"])
    return power


def mechanical_energy(dyn: dict) -> np.ndarray:
    """Kinetic plus potential energy of the moving links at each sample, J, from their mass, inertia, centre of mass
    and velocities as the file gives them."""
    g = np.array(dyn["gravity_mps2"])
    energy = np.zeros(len(dyn["crank_deg"]))
    for link in dyn["links"]:
        v = np.array(link["com_velocity_mps"])
        energy += (0.5 * link["mass_kg"] * (v ** 2).sum(1)
                   + 0.5 * link["inertia_kgm2"] * np.array(link["angular_velocity_radps"]) ** 2
                   - link["mass_kg"] * (np.array(link["com_mm"]) / 1000.0) @ g)
    return energy


def energy_residuals(dyn: dict) -> tuple[np.ndarray, np.ndarray, float]:
    """Over a turn: per sample interval, the work put in (the periodic power integrated exactly by its Fourier
    series: spectral, no trapezoid error) and the change of mechanical energy; and the net work of the turn."""
    crank = np.radians(dyn["crank_deg"])
    omega = dyn["crank_speed_rpm"] * 2 * math.pi / 60
    power = input_power(dyn)
    n = power.size
    c = np.fft.rfft(power) / n
    k = np.arange(c.size)

    # antiderivative in theta of sum c_k e^{ik theta} (+ conjugates): c_0 theta + sum 2 Re(c_k e^{ik theta} / (ik))
    def antiderivative(theta):
        waves = np.exp(1j * np.outer(theta, k[1:])) / (1j * k[1:])
        weight = np.where(k[1:] == n // 2, 1.0, 2.0) if n % 2 == 0 else 2.0
        return c[0].real * theta + (waves * c[1:] * weight).real.sum(1)

    work = np.diff(antiderivative(np.append(crank, crank[0] + 2 * math.pi))) / omega
    energy = mechanical_energy(dyn)
    return work, np.diff(np.append(energy, energy[0])), c[0].real * 2 * math.pi / omega


def swing_energy_residuals(dyn: dict, order: int = 6) -> tuple[np.ndarray, np.ndarray]:
    """Over a swing that is not a whole turn: per sample interval, the work put in (the power integrated over the
    interval by the polynomial through the ``order`` nearest samples, exact to O(h^(order+1))) and the change of
    mechanical energy."""
    crank = np.radians(dyn["crank_deg"])
    omega = dyn["crank_speed_rpm"] * 2 * math.pi / 60
    power = input_power(dyn)
    n = power.size
    work = np.empty(n - 1)
    for i in range(n - 1):
        first = min(max(i - order // 2 + 1, 0), n - order)
        window = slice(first, first + order)
        h = crank[i + 1] - crank[i]
        x = (crank[window] - crank[i]) / h                        # the interval is [0, 1] in x
        antiderivative = np.polyint(np.polyfit(x, power[window], order - 1))
        work[i] = (np.polyval(antiderivative, 1.0) - np.polyval(antiderivative, 0.0)) * h / omega
    return work, np.diff(mechanical_energy(dyn))
