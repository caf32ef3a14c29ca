"""Ready-made mechanisms, shared by the examples, the tests and the benchmarks.

Each factory returns a built :class:`mbd3d.Model` in SI units with bodies named as in the
docstring. Joint points are given in body frames, so the bodies' initial guesses may be rough.
"""

from __future__ import annotations

import math

import numpy as np

from mbd3d.errors import ModelError
from mbd3d.model.forces import Torque
from mbd3d.model.springs import RotationalSpringDamper
from mbd3d.model.builder import Model, ModelBuilder
from mbd3d.model.motion import Motion, Ramp
from mbd3d.numerics.rotations import frame_along

__all__ = ["slider_crank", "four_bar", "pendulum_chain", "driven_chain", "slider_crank_positions",
           "spatial_slider_crank", "spatial_four_bar", "spatial_chain", "newtons_cradle", "spheres_in_box",
           "frame_along"]


def slider_crank_positions(crank_angle: float, crank_length: float, rod_length: float
                           ) -> tuple[np.ndarray, float, np.ndarray]:
    """Pin A, rod angle and slider point B of an in-line slider-crank (B on the x axis, right).

    Parameters
    ----------
    crank_angle : float
        [rad] from the x axis.
    crank_length, rod_length : float
        O-A and A-B [m].
    """
    a = crank_length * np.array([math.cos(crank_angle), math.sin(crank_angle)])
    rod_angle = math.asin(-a[1] / rod_length)
    b = a + rod_length * np.array([math.cos(rod_angle), math.sin(rod_angle)])
    return a, rod_angle, b


def slider_crank(*, crank_length: float = 0.12, rod_length: float = 0.26,
                 crank_mass: float = 1.0, crank_inertia: float = 0.001,
                 rod_mass: float = 2.0, rod_inertia: float = 0.01,
                 slider_mass: float = 4.0, slider_inertia: float = 0.02,
                 crank_angle: float = math.radians(65.0), crank_speed: float | None = 2 * math.pi,
                 crank_motion: Motion | None = None, crank_torque: float | None = None,
                 gravity: float = 9.81) -> Model:
    """In-line slider-crank: crank O-A pinned to the ground at the origin, rod A-B, slider B on
    the global x axis (Nikravesh's data by default).

    Bodies ``crank``, ``rod``, ``slider`` (centres of mass at the link mid-points and at B);
    joints ``O``, ``A``, ``B`` (revolutes) and ``rail`` (prismatic along x).

    Parameters
    ----------
    crank_length, rod_length : float
        O-A and A-B [m], positive.
    crank_mass, rod_mass, slider_mass : float
        [kg].
    crank_inertia, rod_inertia, slider_inertia : float
        About the centres of mass [kg m^2].
    crank_angle : float
        Crank angle at t = 0 [rad]; the bodies' guesses are the assembled drawing there.
    crank_speed : float or None
        Constant crank speed [rad/s] of the driver ``motor`` (a :class:`~mbd3d.Ramp`). None for
        no driver (forward dynamics).
    crank_motion : Motion, optional
        Any other prescribed crank angle ``f(t)`` for the driver (overrides ``crank_speed``).
    crank_torque : float, optional
        Constant torque [N m] on the crank (force element ``torque``).
    gravity : float
        [m/s^2] along -y.
    """
    from mbd3d.joints import Prismatic, Revolute, RotationDriver

    L1, L2 = crank_length, rod_length
    if not (L1 > 0 and L2 > 0):
        raise ModelError(f"slider_crank: crank_length and rod_length must be positive [m], got "
                         f"{L1!r} and {L2!r}")
    if abs(L1 * math.sin(crank_angle)) > L2:
        raise ModelError(f"slider_crank: a rod of {L2:g} m cannot reach the slider's line from "
                         f"the crank pin, {abs(L1 * math.sin(crank_angle)):.4g} m away at the "
                         f"crank angle {math.degrees(crank_angle):.4g} deg; give a longer rod "
                         "or another crank_angle")
    a, rod_angle, b_point = slider_crank_positions(crank_angle, L1, L2)
    b = ModelBuilder(dim=2, gravity=(0.0, -gravity), name="slider-crank")
    crank = b.add_body("crank", mass=crank_mass, inertia=crank_inertia, position=a / 2,
                       angle=crank_angle)
    rod = b.add_body("rod", mass=rod_mass, inertia=rod_inertia, position=(a + b_point) / 2,
                     angle=rod_angle)
    slider = b.add_body("slider", mass=slider_mass, inertia=slider_inertia, position=b_point)
    pin_o = b.add(Revolute("O", b.ground, crank, point_i=(0.0, 0.0), point_j=(-L1 / 2, 0.0)))
    b.add(Revolute("A", crank, rod, point_i=(L1 / 2, 0.0), point_j=(-L2 / 2, 0.0)))
    b.add(Revolute("B", rod, slider, point_i=(L2 / 2, 0.0), point_j=(0.0, 0.0)))
    b.add(Prismatic("rail", b.ground, slider, axis=(1.0, 0.0), point_i=(0.0, 0.0),
                    point_j=(0.0, 0.0)))
    if crank_motion is not None or crank_speed is not None:
        motion = crank_motion if crank_motion is not None else Ramp(crank_angle, crank_speed)
        b.add(RotationDriver("motor", pin_o, motion=motion))
    if crank_torque is not None:
        b.add(Torque("torque", crank, crank_torque))
    return b.build()


def four_bar(*, ground_length: float = 0.30, crank_length: float = 0.10,
             coupler_length: float = 0.35, rocker_length: float = 0.30,
             mass_per_length: float = 2.0, crank_angle: float = math.radians(60.0),
             crank_speed: float | None = 2 * math.pi, crank_torque: float | None = None,
             gravity: float = 9.81, shaft_stiffness: float | None = None) -> Model:
    """Crank-rocker four-bar: ground pivots O2 = (0, 0) and O4 = (ground_length, 0).

    Bodies ``crank`` (O2-A), ``coupler`` (A-B), ``rocker`` (O4-B), slender uniform bars
    (``m = mass_per_length L``, ``J = m L^2 / 12``); revolutes ``O2``, ``A``, ``B``, ``O4``;
    driver ``motor`` at constant crank speed [rad/s] (None: no driver); optional constant
    ``crank_torque`` [N m] (force element ``torque``). Assembled with the open configuration
    (B above the line O4-A).

    With ``shaft_stiffness`` [N m/rad] the motor drives a ``shaft`` (a small disc on its own
    revolute ``S`` at O2) that turns the crank through an elastic coupling, the rotational
    spring ``coupling``, relaxed in the drawing: the mechanism keeps one degree of freedom,
    the crank's twist against the shaft.

    Parameters
    ----------
    ground_length, crank_length, coupler_length, rocker_length : float
        O2-O4, O2-A, A-B and O4-B [m].
    mass_per_length : float
        Of the bars [kg/m].
    crank_angle : float
        At t = 0 [rad].
    crank_speed : float or None
        Of the driver ``motor`` [rad/s]; None: no driver.
    crank_torque : float, optional
        [N m] on the crank.
    gravity : float
        [m/s^2] along -y.
    shaft_stiffness : float, optional
        Of the coupling between the motor's shaft and the crank [N m/rad].
    """
    from mbd3d.joints import Revolute, RotationDriver

    a = crank_length * np.array([math.cos(crank_angle), math.sin(crank_angle)])
    o4 = np.array([ground_length, 0.0])
    # B: intersection of the circles |B - A| = coupler and |B - O4| = rocker, upper branch
    d_vec = o4 - a
    d = float(np.linalg.norm(d_vec))
    along = (coupler_length**2 - rocker_length**2 + d * d) / (2 * d)
    across = math.sqrt(max(coupler_length**2 - along**2, 0.0))
    e = d_vec / d
    # the branch to the left of the direction A -> O4: B above that line, the open four-bar
    b_point = a + along * e + across * np.array([-e[1], e[0]])

    def bar(name, p, q_point):
        length = float(np.linalg.norm(q_point - p))
        angle = math.atan2(*(q_point - p)[::-1])
        m = mass_per_length * length
        return builder.add_body(name, mass=m, inertia=m * length**2 / 12, position=(p + q_point) / 2,
                                angle=angle), length

    builder = ModelBuilder(dim=2, gravity=(0.0, -gravity), name="four-bar")
    crank, L1 = bar("crank", np.zeros(2), a)
    coupler, L2 = bar("coupler", a, b_point)
    rocker, L3 = bar("rocker", o4, b_point)
    o2 = builder.add(Revolute("O2", builder.ground, crank, point_i=(0, 0), point_j=(-L1 / 2, 0)))
    builder.add(Revolute("A", crank, coupler, point_i=(L1 / 2, 0), point_j=(-L2 / 2, 0)))
    builder.add(Revolute("B", coupler, rocker, point_i=(L2 / 2, 0), point_j=(L3 / 2, 0)))
    builder.add(Revolute("O4", builder.ground, rocker, point_i=o4, point_j=(-L3 / 2, 0)))
    driven = o2
    if shaft_stiffness is not None:
        shaft = builder.add_body("shaft", mass=0.1, inertia=0.1 * (0.2 * L1) ** 2 / 2,
                                 position=(0.0, 0.0), angle=crank_angle)
        driven = builder.add(Revolute("S", builder.ground, shaft, at=(0.0, 0.0)))
        builder.add(RotationalSpringDamper("coupling", body_i=shaft, body_j=crank,
                                           stiffness=shaft_stiffness))
    if crank_speed is not None:
        builder.add(RotationDriver("motor", driven, motion=Ramp(crank_angle, crank_speed)))
    if crank_torque is not None:
        builder.add(Torque("torque", crank, crank_torque))
    return builder.build()


def _chain(n_links: int, L: float, m: float, angle: float, gravity: float, name: str
           ) -> tuple[ModelBuilder, list]:
    """The builder of :func:`pendulum_chain` and its pins."""
    from mbd3d.joints import Revolute

    b = ModelBuilder(dim=2, gravity=(0.0, -gravity), name=name)
    direction = np.array([math.cos(angle), math.sin(angle)])
    previous, pins = b.ground, []
    for k in range(n_links):
        body = b.add_body(f"link{k + 1}", mass=m, inertia=m * L * L / 12,
                          position=(k + 0.5) * L * direction, angle=angle)
        point_i = (0.0, 0.0) if k == 0 else (L / 2, 0.0)
        pins.append(b.add(Revolute(f"pin{k + 1}", previous, body, point_i=point_i,
                                   point_j=(-L / 2, 0.0))))
        previous = body
    return b, pins


def pendulum_chain(n_links: int, *, link_length: float = 1.0, link_mass: float = 1.0,
                   angle: float = 0.0, gravity: float = 9.81, sparse: bool | None = None) -> Model:
    """A chain of ``n_links`` uniform bars pinned end to end, the first to the ground at the
    origin, laid out at ``angle`` [rad] from the x axis (0: horizontal, -pi/2: hanging).

    Bodies ``link1`` ... ``linkN``; revolutes ``pin1`` (ground) ... ``pinN``.

    Parameters
    ----------
    n_links : int
    link_length : float
        [m].
    link_mass : float
        [kg].
    angle : float
        Of the chain from the x axis in the drawing [rad].
    gravity : float
        [m/s^2] along -y.
    sparse : bool, optional
        Sparse linear algebra (default by the model's size).
    """
    b, _ = _chain(n_links, link_length, link_mass, angle, gravity, f"{n_links}-link chain")
    return b.build(sparse=sparse)


def driven_chain(n_links: int, *, amplitude: float = 0.2, frequency: float = 1.0,
                 frequency_step: float = 0.1) -> Model:
    """A hanging chain of ``n_links`` 1 m, 1 kg bars (as :func:`pendulum_chain` at ``angle =
    -pi/2``) with every pin driven: a fully driven mechanism of any size, for kinematics and
    inverse dynamics.

    Pin ``k`` (1-based) turns its link relative to the one above by ``amplitude sin((frequency
    + (k - 1) frequency_step) t)`` [rad, rad/s]. Bodies ``link1`` ... ``linkN``; revolutes
    ``pin1`` ... ``pinN``; drivers ``drive1`` ... ``driveN``.

    Parameters
    ----------
    n_links : int
    amplitude : float
        Of each pin's turn [rad].
    frequency : float
        Of the first pin [rad/s].
    frequency_step : float
        Added for each pin below it [rad/s].
    """
    from mbd3d.joints import RotationDriver
    from mbd3d.model.motion import Harmonic

    b, pins = _chain(n_links, 1.0, 1.0, -math.pi / 2, 9.81, f"driven {n_links}-link chain")
    for k, pin in enumerate(pins):
        b.add(RotationDriver(f"drive{k + 1}", pin,
                             motion=Harmonic(amplitude, frequency + frequency_step * k)))
    return b.build()


def spatial_slider_crank(*, crank_length: float = 0.10, rod_length: float = 0.30,
                         offset_y: float = 0.04, offset_z: float = 0.06,
                         crank_angle: float = 0.0, crank_speed: float | None = 2 * math.pi,
                         gravity: float = 9.81) -> Model:
    """Spatial slider-crank: the crank turns about the global z axis at the origin, the slider
    runs along a line parallel to x at ``y = offset_y``, ``z = offset_z`` (out of the crank's
    plane), and the rod joins them with a universal joint at the crank and a ball joint at the
    slider (an all-revolute or ball-ball rod would add a redundancy or an idle spin).

    Bodies ``crank``, ``rod``, ``slider`` (steel-like bars); joints ``O`` (revolute), ``A``
    (universal), ``B`` (spherical), ``rail`` (prismatic); driver ``motor`` at ``crank_speed``
    [rad/s] (None: none). Gravity along -z. Closed form of the slider position:
    ``x = r cos(phi) + sqrt(l^2 - e^2 - (d - r sin(phi))^2)``.

    Parameters
    ----------
    crank_length, rod_length : float
        ``r`` and ``l`` [m].
    offset_y, offset_z : float
        The rail's offsets ``d`` and ``e`` from the crank's axis [m].
    crank_angle : float
        At t = 0 [rad].
    crank_speed : float or None
        Of the driver ``motor`` [rad/s]; None: no driver.
    gravity : float
        [m/s^2] along -z.
    """
    from mbd3d.joints import Prismatic, Revolute, RotationDriver, Spherical, Universal

    r, l, d, e = crank_length, rod_length, offset_y, offset_z
    a = r * np.array([math.cos(crank_angle), math.sin(crank_angle), 0.0])
    x_b = a[0] + math.sqrt(l * l - e * e - (d - a[1]) ** 2)
    b_point = np.array([x_b, d, e])
    rod_dir = (b_point - a) / l
    z = np.array([0.0, 0.0, 1.0])
    builder = ModelBuilder(dim=3, gravity=(0.0, 0.0, -gravity), name="spatial slider-crank")

    def bar(length: float, mass: float) -> np.ndarray:
        return mass * np.array([1e-2 * length**2, length**2 / 12, length**2 / 12])

    crank = builder.add_body("crank", mass=0.5, inertia=bar(r, 0.5), position=a / 2,
                             orientation=frame_along(a))
    rod = builder.add_body("rod", mass=1.0, inertia=bar(l, 1.0), position=(a + b_point) / 2,
                           orientation=frame_along(rod_dir))
    slider = builder.add_body("slider", mass=2.0, inertia=(0.002, 0.002, 0.002), position=b_point)
    pin = builder.add(Revolute("O", builder.ground, crank, at=(0.0, 0.0, 0.0), axis=z))
    builder.add(Universal("A", crank, rod, at=a, axis_i=z,
                          axis_j=np.cross(rod_dir, z) / np.linalg.norm(np.cross(rod_dir, z))))
    builder.add(Spherical("B", rod, slider, at=b_point))
    builder.add(Prismatic("rail", builder.ground, slider, axis=(1.0, 0.0, 0.0)))
    if crank_speed is not None:
        builder.add(RotationDriver("motor", pin, motion=Ramp(crank_angle, crank_speed)))
    return builder.build()


def spatial_four_bar(*, all_revolute: bool = False, crank_speed: float | None = 2 * math.pi,
                     gravity: float = 9.81) -> Model:
    """RSUR spatial four-bar: crank O2-A turning about z at the origin, coupler A-B, rocker O4-B
    turning about the global y axis at O4 = (0.25, 0, 0.1).

    The coupler has a ball joint at A and a universal joint at B, which closes the loop with one
    degree of freedom. With ``all_revolute=True`` the same linkage is built with four revolutes
    (crank and rocker axes as above, coupler pins parallel to them): a spatial four-bar of
    revolutes only moves when its axes meet Bennett's conditions, so this one is rigid, and
    :func:`mbd3d.analyses.mobility` reports 0 degrees of freedom with 2 redundant rows.

    Parameters
    ----------
    all_revolute : bool
        Four revolutes instead of a revolute, a ball, a universal and a revolute.
    crank_speed : float or None
        Of the driver ``motor`` [rad/s]; None: no driver.
    gravity : float
        [m/s^2] along -z.
    """
    from mbd3d.joints import Revolute, RotationDriver, Spherical, Universal

    o4 = np.array([0.25, 0.0, 0.1])
    a = np.array([0.08, 0.0, 0.0])
    b_point = o4 + np.array([0.0, 0.0, 0.2])  # rocker straight up in the drawing
    z, y = np.array([0.0, 0.0, 1.0]), np.array([0.0, 1.0, 0.0])
    builder = ModelBuilder(dim=3, gravity=(0.0, 0.0, -gravity),
                           name="spatial four-bar, " + ("4 revolutes" if all_revolute else "RSUR"))

    def add_bar(name: str, p: np.ndarray, q: np.ndarray):
        length = float(np.linalg.norm(q - p))
        m = 2.0 * length
        return builder.add_body(name, mass=m, inertia=m * np.array([1e-2, 1.0, 1.0]) * length**2 / 12,
                                position=(p + q) / 2, orientation=frame_along(q - p))

    crank = add_bar("crank", np.zeros(3), a)
    coupler = add_bar("coupler", a, b_point)
    rocker = add_bar("rocker", o4, b_point)
    o2 = builder.add(Revolute("O2", builder.ground, crank, at=(0.0, 0.0, 0.0), axis=z))
    builder.add(Revolute("O4", builder.ground, rocker, at=o4, axis=y))
    if all_revolute:
        builder.add(Revolute("A", crank, coupler, at=a, axis=z))
        builder.add(Revolute("B", coupler, rocker, at=b_point, axis=y))
    else:
        builder.add(Spherical("A", crank, coupler, at=a))
        coupler_dir = (b_point - a) / np.linalg.norm(b_point - a)
        cross = np.cross(coupler_dir, y)
        builder.add(Universal("B", coupler, rocker, at=b_point, axis_i=cross / np.linalg.norm(cross),
                              axis_j=y))
    if crank_speed is not None:
        builder.add(RotationDriver("motor", o2, motion=Ramp(0.0, crank_speed)))
    return builder.build()


def spatial_chain(n_links: int, *, link_length: float = 1.0, link_mass: float = 1.0,
                  gravity: float = 9.81, sparse: bool | None = None) -> Model:
    """A chain of ``n_links`` uniform bars joined by ball joints, the first to the ground at the
    origin, laid along x; gravity along -z. Bodies ``link1`` ...; joints ``ball1`` ....

    Parameters
    ----------
    n_links : int
    link_length : float
        [m].
    link_mass : float
        [kg].
    gravity : float
        [m/s^2] along -z.
    sparse : bool, optional
        Sparse linear algebra (default by the model's size).
    """
    from mbd3d.joints import Spherical

    L, m = link_length, link_mass
    builder = ModelBuilder(dim=3, gravity=(0.0, 0.0, -gravity), name=f"{n_links}-link spatial chain")
    previous = builder.ground
    for k in range(n_links):
        body = builder.add_body(f"link{k + 1}", mass=m,
                                inertia=m * L * L * np.array([1e-2, 1 / 12, 1 / 12]),
                                position=((k + 0.5) * L, 0.0, 0.0))
        point_i = (0.0, 0.0, 0.0) if k == 0 else (L / 2, 0.0, 0.0)
        builder.add(Spherical(f"ball{k + 1}", previous, body, point_i=point_i,
                              point_j=(-L / 2, 0.0, 0.0)))
        previous = body
    return builder.build(sparse=sparse)


def newtons_cradle(n_balls: int = 5, *, radius: float = 0.015, string_length: float = 0.1,
                   gap: float = 0.2e-3, density: float = 7850.0, young_modulus: float = 210e9,
                   poisson_ratio: float = 0.3, restitution: float = 1.0,
                   release: float = math.radians(30.0), gravity: float = 9.81) -> Model:
    """Newton's cradle in the plane: ``n_balls`` balls of ``radius`` [m] and ``density``
    [kg/m^3], each hanging from a pin ``string_length`` [m] above its centre (a rigid
    string), in a row along x with ``gap`` [m] between neighbours at rest; the first is turned
    back by ``release`` [rad] about its pin. Neighbours touch by Hertz's law from the
    material (``young_modulus`` [Pa], ``poisson_ratio``), damped to ``restitution``; gravity
    -y.

    Bodies ``ball1`` ... (mass ``density 4/3 pi r^3``, inertia ``2/5 m r^2``); joints ``pin1``
    ... (pin k at ``((k - 1)(2 r + gap), string_length)``); contacts ``touch1`` ... between
    ball k and ball k + 1.

    Parameters
    ----------
    n_balls : int
    radius, string_length, gap : float
        [m].
    density : float
        [kg/m^3].
    young_modulus : float
        [Pa].
    poisson_ratio : float
    restitution : float
        Coefficient of restitution of the contacts, in (0, 1].
    release : float
        [rad].
    gravity : float
        [m/s^2] along -y.
    """
    from mbd3d.joints import Revolute
    from mbd3d.model.contact_laws import HertzContact
    from mbd3d.model.contacts import Contact, Sphere

    if n_balls < 1:
        raise ModelError(f"newtons_cradle: n_balls must be at least 1, got {n_balls!r}")
    mass = density * 4.0 / 3.0 * math.pi * radius ** 3
    law = HertzContact(young_modulus=young_modulus, poisson_ratio=poisson_ratio,
                       restitution=restitution)
    builder = ModelBuilder(dim=2, gravity=(0.0, -gravity), name="Newton's cradle")
    balls = []
    for k in range(n_balls):
        pivot = np.array([k * (2.0 * radius + gap), string_length])
        angle = -release if k == 0 else 0.0  # about the pin, from hanging straight down
        centre = pivot + string_length * np.array([math.sin(angle), -math.cos(angle)])
        ball = builder.add_body(f"ball{k + 1}", mass=mass, inertia=0.4 * mass * radius ** 2,
                                position=centre, angle=angle)
        builder.add(Revolute(f"pin{k + 1}", builder.ground, ball, at=pivot))
        if balls:
            builder.add(Contact(f"touch{k}", Sphere(balls[-1], radius), Sphere(ball, radius),
                                law=law))
        balls.append(ball)
    return builder.build()


def spheres_in_box(n_spheres: int = 1000, *, dim: int = 3, radius: float = 0.01,
                   spacing: float = 2.5, density: float = 1000.0, young_modulus: float = 1e7,
                   poisson_ratio: float = 0.3, restitution: float = 0.5, friction: float = 0.3,
                   speed: float = 0.5, seed: int = 0, gravity: float = 9.81) -> Model:
    """``n_spheres`` free spheres (``dim=2``: discs) of ``radius`` [m] and ``density``
    [kg/m^3] on a square (planar: row-by-row) lattice ``spacing`` radii apart, each moved
    by up to a tenth of a radius and thrown at up to ``speed`` [m/s] in a random direction
    (``seed``), above the floor of an open box whose walls stand half a spacing outside the
    lattice; gravity -z (planar: -y). Every two spheres and each sphere and wall touch by
    Hertz's law from the material (``young_modulus`` [Pa], ``poisson_ratio``), damped to
    ``restitution``, with Coulomb ``friction``: one :class:`~mbd3d.ContactGroup`, ``pile``.

    Bodies ``sphere0`` ... ; the lattice has ``ceil(n^(1/3))`` (planar: ``ceil(n^(1/2))``)
    spheres along each horizontal side, filled layer by layer from the floor.

    Parameters
    ----------
    n_spheres : int
    dim : {2, 3}
    radius : float
        [m].
    spacing : float
        Of the lattice, in radii.
    density : float
        [kg/m^3].
    young_modulus : float
        [Pa].
    poisson_ratio : float
    restitution : float
        In (0, 1].
    friction : float
        Coulomb's coefficient.
    speed : float
        The largest starting speed [m/s].
    seed : int
        Of the random moves and speeds.
    gravity : float
        [m/s^2].
    """
    from mbd3d.model.contact_laws import HertzContact
    from mbd3d.model.contacts import ContactGroup, Plane, Sphere

    if n_spheres < 1 or dim not in (2, 3):
        raise ModelError(f"spheres_in_box: give n_spheres >= 1 and dim 2 or 3, got "
                         f"{n_spheres!r} and {dim!r}")
    rng = np.random.default_rng(seed)
    side = math.ceil(n_spheres ** (1.0 / dim) - 1e-9)
    per_layer = side ** (dim - 1)
    step = spacing * radius
    mass = density * (4.0 / 3.0 * math.pi * radius ** 3 if dim == 3 else math.pi * radius ** 2)
    inertia = (0.4 if dim == 3 else 0.5) * mass * radius ** 2
    builder = ModelBuilder(dim=dim, gravity=(0.0,) * (dim - 1) + (-gravity,),
                           name=f"{n_spheres} spheres in a box")
    shapes = []
    for k in range(n_spheres):
        layer, place = divmod(k, per_layer)
        cell = [place % side, place // side][:dim - 1] + [layer]
        centre = (np.array(cell) + 0.5) * step + rng.uniform(-0.1, 0.1, dim) * radius
        direction = rng.normal(size=dim)
        body = builder.add_body(f"sphere{k}", mass=mass,
                                inertia=inertia if dim == 2 else (inertia,) * 3,
                                position=centre,
                                velocity=speed * rng.uniform() * direction
                                / np.linalg.norm(direction))
        shapes.append(Sphere(body, radius=radius))
    width = side * step
    for axis in range(dim):
        normal = np.eye(dim)[axis]
        shapes.append(Plane(builder.ground, normal=normal, at=np.zeros(dim)))
        if axis < dim - 1:  # the walls; the top is open
            shapes.append(Plane(builder.ground, normal=-normal, at=normal * width))
    law = HertzContact(young_modulus=young_modulus, poisson_ratio=poisson_ratio,
                       restitution=restitution)
    builder.add(ContactGroup("pile", shapes, law=law, friction=friction))
    return builder.build()
