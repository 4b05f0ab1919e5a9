"""Mass properties of a link in its own frame, from bars and point masses, on floats and CasADi symbols alike.

Link frame (docs/ARCHITECTURE.md "Dynamics"): origin at the link's first joint, x towards its second joint.  A bar's
mass and inertia follow its length, so a length that is a decision variable moves them with it in the NLP.
Returned vectors are SI: kg, m, m, kg m^2.
"""

from __future__ import annotations

import casadi as ca

#: per link, in the order of :data:`synthesis.dynamics.fourbar.LINKS`: mass kg, centre of mass x, y (m), inertia about
#: the centre of mass kg m^2
MASS_FIELDS = ("mass", "com_x", "com_y", "inertia")
#: per link: a constant force (N, machine frame) and its point of application in the link frame (m)
LOAD_FIELDS = ("force_x", "force_y", "at_x", "at_y")


def bar(density: float, area_mm2: float, start_mm, end_mm) -> tuple:
    """A slender bar of uniform section from ``start_mm`` to ``end_mm`` (link frame, mm): (kg, m, m, kg m^2)."""
    dx, dy = (end_mm[0] - start_mm[0]) / 1000.0, (end_mm[1] - start_mm[1]) / 1000.0
    length = ca.sqrt(dx * dx + dy * dy)
    mass = density * area_mm2 * 1e-6 * length
    return (mass, (start_mm[0] + end_mm[0]) / 2000.0, (start_mm[1] + end_mm[1]) / 2000.0, mass * length * length / 12.0)


def point(mass: float, at_mm) -> tuple:
    """A point mass at ``at_mm`` (link frame, mm)."""
    return (mass, at_mm[0] / 1000.0, at_mm[1] / 1000.0, 0.0)


def combine(parts: list[tuple]) -> tuple:
    """One rigid body of the parts (mass, com_x, com_y, inertia about each part's own centre): parallel-axis sum."""
    total = sum(p[0] for p in parts)
    if isinstance(total, (int, float)) and total == 0.0:
        return (0.0, 0.0, 0.0, 0.0)
    cx = sum(p[0] * p[1] for p in parts) / total
    cy = sum(p[0] * p[2] for p in parts) / total
    inertia = sum(p[3] + p[0] * ((p[1] - cx) ** 2 + (p[2] - cy) ** 2) for p in parts)
    return (total, cx, cy, inertia)


def link_properties(section, bars: list[tuple], point_masses, tip=None) -> tuple:
    """A link's (mass, com_x, com_y, inertia): a bar section (``density``, ``area``) over the link's ``bars``
    ((start, end) in mm, link frame), or lumped values (``mass``, ``com`` mm, ``inertia``), plus its point masses
    (one ``at = "tip"`` sits at ``tip``, the kind's traced point in the link frame, mm)."""
    if hasattr(section, "density"):
        parts = [bar(section.density, section.area, a, b) for a, b in bars]
    else:
        parts = [(section.mass, section.com[0] / 1000.0, section.com[1] / 1000.0, section.inertia)]
    for pm in point_masses:
        if pm.at == "tip" and tip is None:
            raise ValueError(f"a point mass at the tip of the {pm.link}, which has no traced point")
        parts.append(point(pm.mass, tip if pm.at == "tip" else pm.at))
    return combine(parts)


def mass_vector(dynamics, bars: dict[str, list[tuple]], links: tuple[str, ...], tips: dict | None = None,
                counterweight: tuple | None = None, rocker_counterweight: tuple | None = None) -> list:
    """The 12 mass parameters (:data:`MASS_FIELDS` per link) of a ``[dynamics]`` table; ``bars``: link -> its bars
    (start, end) in mm in the link frame, read when the link is given as a bar; ``tips``: link -> its traced point;
    ``counterweight``: (mass kg, radius mm) on the crank (the first link) opposite its pin, ``rocker_counterweight``
    the same on the rocker (the last link) opposite the coupler-rocker joint: a point mass at (-radius, 0) in the
    link's frame, added by the parallel-axis sum; floats or symbols."""
    out: list = []
    weights = {links[0]: counterweight, links[-1]: rocker_counterweight}
    for name in links:
        carried = [pm for pm in dynamics.point_masses if pm.link == name]
        props = link_properties(getattr(dynamics, name), bars[name], carried, (tips or {}).get(name))
        weight = weights.get(name)
        if weight is not None:
            props = combine([props, point(weight[0], (-weight[1], 0.0))])
        out += list(props)
    return out


def load_vector(dynamics, links: tuple[str, ...]) -> list[float]:
    """The 12 load parameters (:data:`LOAD_FIELDS` per link) of a ``[dynamics]`` table (zero where none acts)."""
    out: list[float] = []
    for name in links:
        load = next((x for x in dynamics.external_loads if x.link == name), None)
        out += [0.0] * 4 if load is None else [load.force[0], load.force[1], load.at[0] / 1000.0, load.at[1] / 1000.0]
    return out
