"""The optional ``[dynamics]`` table of a four-bar kind's spec: mass properties, gravity, crank speed, loads, limits.

Shared by the kinds whose mechanism is a planar four-bar driven at its crank (the crank-rocker drive and the
planting arm; docs/ARCHITECTURE.md "Dynamics").  Each moving link (crank, coupler, rocker) is given either as a
**bar** of a material density and a cross-section area (its mass and inertia then follow the link's length, and
change with it in the NLP) or as **lumped** mass properties (mass, centre of mass in the link frame, inertia about
the centre of mass).

The link frame of each link: origin at its first joint (crank: the crank pivot; coupler: the crank pin; rocker: the
rocker pivot), x towards its second joint (the crank pin; the coupler-rocker joint; the coupler-rocker joint), y
90 deg counter-clockwise from x.  Units: kg, kg/m^3, mm^2, mm, kg m^2, m/s^2, N, N m, r/min.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from synthesis.spec.common import StrictModel, Variable, value_of

#: the moving links of a four-bar, in the order the dynamics reads them
LINKS = ("crank", "coupler", "rocker")


class BarLink(StrictModel):
    """A straight bar of uniform section along the link's joints: mass = density x area x length, inertia m L^2 / 12."""

    density: float = Field(gt=0.0, le=25000.0, description="material density, kg/m^3 (steel 7850, aluminium 2700)")
    area: float = Field(gt=0.0, le=1.0e5, description="cross-section area of the bar, mm^2")


class LumpedLink(StrictModel):
    """A link's mass properties as given: they stay the same when a length changes."""

    mass: float = Field(ge=0.0, le=1000.0, description="link mass, kg")
    com: tuple[float, float] = Field(description="centre of mass in the link frame, mm")
    inertia: float = Field(ge=0.0, le=1000.0, description="moment of inertia about the centre of mass, kg m^2")


class PointMass(StrictModel):
    """A mass carried by a link (a claw, a seedling, a counterweight), its own inertia neglected."""

    link: Literal["crank", "coupler", "rocker"] = Field(description="the link that carries it")
    mass: float = Field(gt=0.0, le=1000.0, description="mass, kg")
    at: tuple[float, float] | Literal["tip"] = Field(
        description="position in the link frame, mm; or \"tip\": the kind's traced point on that link, which "
                    "moves with the design (the planting arm's: the claw tip C on the coupler)")
    note: str = Field("", description="what it is and where its value comes from")


class ExternalLoad(StrictModel):
    """A constant force (machine frame) acting at a point fixed on a link, e.g. soil resistance on the claw."""

    link: Literal["crank", "coupler", "rocker"] = Field(description="the link it acts on")
    force: tuple[float, float] = Field(description="force on the link, machine frame, N")
    at: tuple[float, float] = Field(description="point of application in the link frame, mm")
    note: str = Field("", description="where the value comes from (an assumption unless a paper gives it)")


class Counterweight(StrictModel):
    """A mass on the crank opposite its pin (at -radius along the crank), or on the rocker opposite the
    coupler-rocker joint, to balance the shaking force; a number fixes a value, ``{init, bounds}`` frees it (the
    planting arm's design variables ``counterweight_mass``, ``counterweight_radius`` and, on the rocker,
    ``rocker_counterweight_mass``, ``rocker_counterweight_radius``)."""

    mass: Variable = Field(description="counterweight mass, kg")
    radius: Variable = Field(description="its distance from the link's pivot (crank: the crank pivot, opposite the "
                                         "crank pin; rocker: the rocker pivot, opposite the coupler-rocker joint), mm")

    @model_validator(mode="after")
    def _not_negative(self) -> "Counterweight":
        for name in ("mass", "radius"):
            v = getattr(self, name)
            low = v if isinstance(v, (int, float)) else v.bounds[0]
            if low < 0.0:
                raise ValueError(f"counterweight.{name}: expected >= 0, got {low:g}")
        return self

    def values(self) -> tuple[float, float]:
        """(mass kg, radius mm) at the given (or start) values."""
        return value_of(self.mass), value_of(self.radius)


class Drive(StrictModel):
    """The crank shaft's drive, for its speed fluctuation: the motor's torque is taken constant (the mean the turn
    needs), so the crank slows where the linkage takes energy and speeds up where it gives it back, the more so the
    smaller the inertia turning with the shaft.  Give the inertia to get the fluctuation, or a fluctuation to get the
    flywheel that keeps it (or both)."""

    flywheel_inertia: float | None = Field(None, gt=0.0, le=1.0e4,
                                           description="moment of inertia of everything turning with the crank shaft "
                                                       "(flywheel, gears and motor rotor reflected to it), kg m^2")
    speed_fluctuation: float | None = Field(None, gt=0.0, lt=1.0,
                                            description="a coefficient of speed fluctuation (omega_max - omega_min) / "
                                                        "omega_mean to size the flywheel for (0.02-0.05 is usual for "
                                                        "agricultural drives), dimensionless")

    @model_validator(mode="after")
    def _something_given(self) -> "Drive":
        if self.flywheel_inertia is None and self.speed_fluctuation is None:
            raise ValueError("drive: give flywheel_inertia (kg m^2), speed_fluctuation (a coefficient), or both")
        return self


class SoilForce(StrictModel):
    """The soil's resistance on a tool point while it is below the soil surface (depth d > 0, mm): a force of
    magnitude f0 + k d opposing the point's velocity relative to the soil (the machine travelling forward at
    ``[operation] forward_speed``, the soil at rest in the ground frame), zero above the surface.  Which point and
    where the surface lies are the kind's (the tillage linkage: the tool D below the ground line; the planting arm:
    the claw tip C below the ``[soil]`` surface)."""

    f0: float = Field(0.0, ge=0.0, le=1.0e5, description="the force at zero depth, N (a jump at soil entry and exit "
                                                          "when > 0)")
    k: float = Field(ge=0.0, le=1.0e4, description="its growth with depth, N/mm")
    source: str = Field(min_length=1, description="where f0 and k come from: a cited figure, or say that they are "
                                                  "an assumption and how they were estimated")


class DynamicsLimits(StrictModel):
    """Rules on the dynamics; a limit left out is no rule."""

    peak_input_torque: float | None = Field(None, gt=0.0, description="largest |input torque| over a turn, N m")
    peak_shaking_force: float | None = Field(None, gt=0.0,
                                             description="largest shaking force on the frame over a turn, N")
    peak_shaking_moment: float | None = Field(None, gt=0.0,
                                              description="largest |shaking moment| on the frame over a turn, about "
                                                          "the crank pivot, N m")

    def any_given(self) -> bool:
        """Whether any limit is given (each is a rule; none given, no dynamics rule)."""
        return any(v is not None for v in (self.peak_input_torque, self.peak_shaking_force, self.peak_shaking_moment))


class DynamicsSection(StrictModel):
    """Mass properties and loads for the inverse dynamics at constant crank speed (docs/ARCHITECTURE.md "Dynamics")."""

    crank: BarLink | LumpedLink = Field(description="the crank: a bar {density, area} or {mass, com, inertia}")
    coupler: BarLink | LumpedLink = Field(description="the coupler (the planting arm's: a bar is AB and the claw arm "
                                                      "AC of the same section): a bar or {mass, com, inertia}")
    rocker: BarLink | LumpedLink = Field(description="the rocker: a bar {density, area} or {mass, com, inertia}")
    point_masses: list[PointMass] = Field(default_factory=list, description="masses carried by the links")
    gravity: tuple[float, float] = Field((0.0, -9.81), description="gravity in the machine frame, m/s^2 (0 allowed)")
    crank_speed: float | None = Field(None, gt=0.0, le=5000.0,
                                      description="constant crank speed, r/min (counter-clockwise); a kind that "
                                                  "has its own crank speed reads that one")
    external_loads: list[ExternalLoad] = Field(default_factory=list,
                                               description="constant forces on the links (at most one per link)")
    counterweight: Counterweight | None = Field(None, description="a counterweight on the crank, opposite its pin")
    rocker_counterweight: Counterweight | None = Field(None, description="a counterweight on the rocker, opposite the "
                                                                         "coupler-rocker joint")
    drive: Drive | None = Field(None, description="the crank shaft's flywheel inertia and/or a speed fluctuation to "
                                                  "size it for: facts.dynamics then reports the crank's speed "
                                                  "fluctuation over a turn (the motor torque constant)")
    samples: int = Field(360, ge=8, le=3600, description="crank angles of result.json's facts.dynamics over a turn")
    limits: DynamicsLimits = Field(default_factory=DynamicsLimits)
    assumption: str = Field("", description="which values are ours, not a paper's")

    @model_validator(mode="after")
    def _one_load_per_link(self) -> "DynamicsSection":
        links = [load.link for load in self.external_loads]
        doubled = sorted({n for n in links if links.count(n) > 1})
        if doubled:
            raise ValueError(f"external_loads: give at most one load per link (their resultant); "
                             f"{', '.join(doubled)} has more")
        return self

    def has_rules(self) -> bool:
        return self.limits.any_given()
