"""Sensitivities of kinematic analysis and inverse dynamics (``mb.sensitivities``): the
derivatives of positions, velocities, accelerations, efforts and reactions with respect to
parameters named as ``mb.parameters`` names them, against the slider-crank's closed forms and
against differences of analyses of models rebuilt with the parameter changed
(``mb.with_parameters``), planar and spatial, closed loops included."""

from __future__ import annotations

import pathlib

import numpy as np
import pytest

import mbd3d as mb
from mbd3d import mechanisms
from mbd3d.io.parameters import parameter_value
from mbd3d.joints import Prismatic, Revolute, RotationDriver, TranslationDriver
from mbd3d.model import constraints

TIMES = np.array([0.0, 0.13, 0.41])
EXAMPLES = pathlib.Path(__file__).parent.parent / "examples" / "models"
#: a fourth-order central difference: offsets in steps and weights
OFFSETS, WEIGHTS = (-2.0, -1.0, 1.0, 2.0), np.array([1.0, -8.0, 8.0, -1.0]) / 12.0


def slider_crank(a: float, l: float, theta: float):
    """Crank ``a`` about the origin, rod ``l``, slider on the x axis, crank at ``theta``."""
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81))
    crank = b.add_body("crank", mass=1.0, inertia=0.001, position=(0.05, 0.05), angle=theta)
    rod = b.add_body("rod", mass=2.0, inertia=0.01, position=(0.2, 0.05), angle=-0.3)
    slider = b.add_body("slider", mass=4.0, inertia=0.02, position=(0.35, 0.0))
    pin = b.add(Revolute("O", b.ground, crank, point_i=(0.0, 0.0), point_j=(-a / 2, 0.0)))
    b.add(Revolute("A", crank, rod, point_i=(a / 2, 0.0), point_j=(-l / 2, 0.0)))
    b.add(Revolute("B", rod, slider, point_i=(l / 2, 0.0), point_j=(0.0, 0.0)))
    b.add(Prismatic("rail", b.ground, slider, axis=(1.0, 0.0), point_i=(0.0, 0.0),
                    point_j=(0.0, 0.0)))
    b.add(RotationDriver("motor", pin, motion=mb.Ramp(theta, 2.0)))
    return b.build()


def test_slider_crank_closed_form():
    # x_B = a cos(theta) + r, r = sqrt(l^2 - a^2 sin^2(theta)): lengthening the crank at its
    # pin A (the pivot O stays) or the rod at its pin B (A stays)
    a, l, theta = 0.12, 0.30, 1.1
    r = np.sqrt(l**2 - a**2 * np.sin(theta) ** 2)
    sens = mb.sensitivities(mb.kinematic_analysis(slider_crank(a, l, theta), [0.0, 0.5]), [
        "joints.A.point_i[0]", "joints.B.point_i[0]", "joints.motor.motion.rate",
        "bodies.slider.mass", "gravity[1]"])
    d_a = sens.sensitivity("slider.x", "joints.A.point_i[0]")
    d_l = sens.sensitivity("slider.x", "joints.B.point_i[0]")
    assert d_a[0] == pytest.approx(np.cos(theta) - a * np.sin(theta) ** 2 / r, abs=1e-13)
    assert d_a[0] == pytest.approx(0.113556, abs=5e-7)  # the formula sheet's figures
    assert d_l[0] == pytest.approx(l / r, abs=1e-13)
    assert d_l[0] == pytest.approx(1.070318, abs=5e-7)
    # the crank's rate moves it by t at time t: dx/drate = dx/dtheta t
    dx_dtheta = -a * np.sin(theta) - a**2 * np.sin(theta) * np.cos(theta) / r
    rate = sens.sensitivity("slider.x", "joints.motor.motion.rate")
    assert rate[0] == 0.0
    th = theta + 2.0 * 0.5
    r1 = np.sqrt(l**2 - a**2 * np.sin(th) ** 2)
    assert rate[1] == pytest.approx(0.5 * (-a * np.sin(th) - a**2 * np.sin(th) * np.cos(th)
                                           / r1), abs=1e-13)
    assert dx_dtheta != 0.0
    # what the positions do not depend on: zeros
    assert not np.any(sens.sensitivity("slider.x", "bodies.slider.mass"))
    assert not np.any(sens.dq[:, :, 4])
    table = sens.to_pandas()
    assert table["d(slider.x)/d(joints.B.point_i[0])"].to_numpy() == pytest.approx(d_l)


def _differenced(model, name: str, measure, analysis=mb.kinematic_analysis) -> np.ndarray:
    """d measure(results)/d parameter by a fourth-order difference of tight analyses."""
    value, size = parameter_value(model, name)
    h = 1e-4 * (max(abs(value), size) or model.length_scale)
    values = np.array([measure(analysis(mb.with_parameters(model, {name: value + o * h}),
                                        TIMES, tol=1e-14)) for o in OFFSETS])
    return np.tensordot(WEIGHTS, values, axes=1) / h


def _agree(got: np.ndarray, model, name: str, measure, analysis=mb.kinematic_analysis,
           rtol: float = 1e-8) -> None:
    """``got`` against :func:`_differenced`, to ``rtol`` of the larger of the derivative and
    1, plus the difference's own rounding (15 times eps of the values over the step: a tiny
    parameter's changes are lost in the values' last digits)."""
    value, size = parameter_value(model, name)
    h = 1e-4 * (max(abs(value), size) or model.length_scale)
    reference = _differenced(model, name, measure, analysis)
    scale = np.max(np.abs(measure(analysis(model, TIMES, tol=1e-14))))
    bound = rtol * max(np.max(np.abs(reference)), 1.0) + 15 * np.finfo(float).eps * scale / h
    assert np.max(np.abs(got - reference)) <= bound, name


def _poses(model, q: np.ndarray, charts) -> np.ndarray:
    """Every body's position and rotation matrix at each time, flattened (k, ...)."""
    rows = []
    for k in range(len(q)):
        fr = constraints.frames(model, q[k], charts=None if charts is None else charts[k])
        rows.append(np.concatenate([fr.Q[:-1, :model.dim].ravel(), fr.A[:-1].ravel()]))
    return np.array(rows)


def _parameters(model, section: str = "") -> list[str]:
    """The model's numbers (of a section), those a file writes as whole numbers left out
    (``with_parameters`` keeps them whole)."""
    from mbd3d.io.parameters import _data, _fields

    fields = _fields(_data(model))
    return [name for name, (container, key) in fields.items()
            if name.startswith(section) and isinstance(container[key], float)]


def test_slider_crank_rates_closed_form():
    # x_B(theta) at theta = theta0 + w t: x' = x_theta w, x'' = x_thetatheta w^2 (w constant),
    # with r = sqrt(l^2 - a^2 sin^2): x_theta = -a sin - a^2 sin cos / r and x_thetatheta =
    # -a cos - a^2 (cos^2 - sin^2) / r - a^4 sin^2 cos^2 / r^3; the rod's length l enters
    # through r alone, r_l = l / r
    a, l, theta0, w, t = 0.12, 0.30, 1.1, 2.0, 0.35
    sens = mb.sensitivities(mb.kinematic_analysis(slider_crank(a, l, theta0), [t]),
                            ["joints.B.point_i[0]"])
    th = theta0 + w * t
    S, C = np.sin(th), np.cos(th)
    r = np.sqrt(l**2 - a**2 * S**2)
    r_l = l / r
    x_t = -a * S - a**2 * S * C / r
    x_t_l = a**2 * S * C / r**2 * r_l
    x_tt = -a * C - a**2 * (C**2 - S**2) / r - a**4 * S**2 * C**2 / r**3
    x_tt_l = a**2 * (C**2 - S**2) / r**2 * r_l + 3.0 * a**4 * S**2 * C**2 / r**4 * r_l
    assert x_t != 0.0 and x_tt != 0.0
    name = "joints.B.point_i[0]"
    assert sens.sensitivity("slider.x", name, of="qd")[0] == pytest.approx(x_t_l * w, abs=1e-11)
    assert sens.sensitivity("slider.x", name, of="qdd")[0] == pytest.approx(x_tt_l * w**2,
                                                                            abs=1e-10)


@pytest.mark.parametrize("make", [mechanisms.slider_crank, mechanisms.four_bar],
                         ids=["slider-crank", "four-bar"])
def test_planar_against_differences(make):
    model = make()
    names = _parameters(model)
    sens = mb.sensitivities(mb.kinematic_analysis(model, TIMES, tol=1e-14), names)
    for j, name in enumerate(names):
        for got, of in ((sens.dq, "q"), (sens.dqd, "qd"), (sens.dqdd, "qdd")):
            _agree(got[:, :, j], model, name, lambda res: getattr(res, of))


@pytest.mark.parametrize("flat", [False, True], ids=["roller", "flat face"])
def test_cam_positions_against_differences(flat):
    # a cam's positions follow its spline profile, smooth to its second derivative: their
    # derivatives (the profile's slope) agree with differences like any joint's. Rates and
    # accelerations take the profile's second and third derivatives, which at a knot of the
    # spline (t = 0 here) have a kink and a jump: the variants' differences, a thousandth of
    # the size apart, err there by that step times the jump (5e-6 of the rates measured)
    from test_cams import cam_and_follower

    model = cam_and_follower(flat=flat, spring=50.0)
    # the bodies' positions and the joints' points must agree with the drawn contact
    names = [n for n in _parameters(model) if not any(
        part in n for part in ("position", "axis", ".at", "profile"))]
    assert "joints.motor.motion.initial" in names
    sens = mb.sensitivities(mb.kinematic_analysis(model, TIMES, tol=1e-14), names)
    for j, name in enumerate(names):
        _agree(sens.dq[:, :, j], model, name, lambda res: res.q)


@pytest.mark.parametrize("make", [mechanisms.spatial_slider_crank, mechanisms.spatial_four_bar],
                         ids=["spatial slider-crank", "spatial four-bar"])
def test_spatial_against_differences(make):
    # orientations as rotation matrices (the results' charts differ from run to run);
    # the sensitivity's own change of poses by the same difference along dq, in the
    # results' charts
    model = make()
    names = []
    for name in _parameters(model):
        try:
            mb.sensitivities(mb.kinematic_analysis(model, [0.0]), [name])
        except mb.ModelError as exc:
            # a universal joint's axes, a rotation matrix: one number alone breaks them
            assert ("perpendicular" in str(exc) or "rotation matrix" in str(exc)) and (
                name in str(exc))
            continue
        names.append(name)
    assert len(names) >= 18
    sens = mb.sensitivities(mb.kinematic_analysis(model, TIMES, tol=1e-14), names)
    res = sens.results
    for j, name in enumerate(names):
        reference = _differenced(model, name, lambda r: _poses(r.model, r.q, r.charts))
        eps = 1e-3
        along = np.tensordot(WEIGHTS, np.array([
            _poses(model, res.q + o * eps * sens.dq[:, :, j], res.charts) for o in OFFSETS]),
            axes=1) / eps
        assert np.max(np.abs(along - reference)) <= 1e-8 * max(
            np.max(np.abs(reference)), 1.0), name
        # the centres' velocities and accelerations: global coordinates, whatever the chart;
        # the bound of _agree, with the difference's own rounding (a tiny inertia's step
        # leaves the accelerations' last digits as its quotient)
        centres = model.position_coordinates
        value, size = parameter_value(model, name)
        h = 1e-4 * (max(abs(value), size) or model.length_scale)
        for got, of in ((sens.dqd, "qd"), (sens.dqdd, "qdd")):
            reference = _differenced(model, name, lambda r: getattr(r, of)[:, centres])
            rounding = 15 * np.finfo(float).eps * np.max(np.abs(getattr(res, of))) / h
            assert np.max(np.abs(got[:, centres, j] - reference)) <= 1e-8 * max(
                np.max(np.abs(reference)), 1.0) + rounding, (name, of)


def test_inverse_dynamics_closed_form():
    # the slider's mass adds m x_B'' to the force along the rail, which the crank's torque
    # carries through x_B's lever: dT/dm = x_B'' dx_B/dtheta (the formula sheet's 4.1 check)
    a, l, theta0, w, t = 0.12, 0.30, 1.1, 2.0, 0.35
    res = mb.inverse_dynamics(slider_crank(a, l, theta0), [t])
    sens = mb.sensitivities(res, ["bodies.slider.mass", "bodies.crank.mass"])
    th = theta0 + w * t
    S, C = np.sin(th), np.cos(th)
    r = np.sqrt(l**2 - a**2 * S**2)
    x_t = -a * S - a**2 * S * C / r
    x_tt = -a * C - a**2 * (C**2 - S**2) / r - a**4 * S**2 * C**2 / r**3
    assert sens.effort("motor", "bodies.slider.mass")[0] == pytest.approx(
        x_tt * w**2 * x_t, abs=1e-12)
    # the crank turns steadily about its pivot: its mass adds its weight's moment only
    # (its centre at a / 2 from the pivot)
    assert sens.effort("motor", "bodies.crank.mass")[0] == pytest.approx(
        9.81 * a / 2 * C, abs=1e-12)
    # nothing moves with a mass
    assert not np.any(sens.dq) and not np.any(sens.dqd) and not np.any(sens.dqdd)


@pytest.mark.parametrize("make", [mechanisms.slider_crank, mechanisms.spatial_slider_crank],
                         ids=["slider-crank", "spatial slider-crank"])
def test_inverse_dynamics_against_differences(make):
    # every number of the bodies and joints: efforts, and a pin's reaction through
    # Sensitivities.derivative
    model = make()
    names = [n for n in _parameters(model)
             if not n.startswith("joints.A.axis") and ".orientation" not in n]
    res = mb.inverse_dynamics(model, TIMES, tol=1e-14)
    sens = mb.sensitivities(res, names)
    driver = next(e.name for e in model.joints if e.is_driver)
    pin = "B"
    reaction = lambda r: r.joint(pin).reaction(on="slider").force  # noqa: E731
    derived = sens.derivative(reaction)
    for j, name in enumerate(names):
        _agree(sens.effort(driver, name), model, name, lambda r: r.joint(driver).effort,
               mb.inverse_dynamics)
        _agree(derived[..., j], model, name, reaction, mb.inverse_dynamics)


def _driven_block(slope: float, mu: float, stiction: float, m: float, motion):
    """A block driven along a rail down a slope, with friction in the rail."""
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81), name="driven block")
    down = np.array([np.cos(slope), -np.sin(slope)])
    block = b.add_body("block", mass=m, inertia=0.1, position=(0.0, 0.0), angle=-slope)
    rail = b.add(Prismatic("rail", b.ground, block, axis=down, at=(0.0, 0.0)))
    b.add(TranslationDriver("push", rail, motion=motion))
    b.add(mb.JointFriction("friction", rail, mu, stiction_velocity=stiction))
    return b.build()


def test_inverse_dynamics_with_joint_friction_closed_form():
    # along the rail m s'' = F + m g sin(a) - mu m g cos(a) tanh(s' / v_s): the push F and
    # its derivatives in the friction's coefficient and stiction speed and in the mass
    slope, mu, v_s, m, g = 0.4, 0.3, 0.05, 2.0, 9.81
    motion = mb.Harmonic(0.1, 3.0, phase=0.2)
    res = mb.inverse_dynamics(_driven_block(slope, mu, v_s, m, motion), TIMES, tol=1e-14)
    names = ["forces.friction.coefficient", "forces.friction.stiction_velocity",
             "bodies.block.mass"]
    sens = mb.sensitivities(res, names)
    _, v, acc = np.array([motion.evaluate(t) for t in TIMES]).T
    normal, th = g * np.cos(slope), np.tanh(v / v_s)
    assert np.all(np.abs(v / v_s) > 0.3)  # on the law's slope, not its ends
    np.testing.assert_allclose(res.joint("push").effort,
                               m * acc - m * g * np.sin(slope) + mu * m * normal * th,
                               rtol=1e-12)
    expected = [m * normal * th, -mu * m * normal * (1 - th**2) * v / v_s**2,
                acc - g * np.sin(slope) + mu * normal * th]
    for name, value in zip(names, expected):
        # the stiction speed's to the differences' accuracy (3e-10 measured: tanh is steep)
        np.testing.assert_allclose(sens.effort("push", name), value, rtol=1e-8, atol=1e-12)
    # held at rest the regularised friction is zero, and so are its derivatives
    rest = mb.static_equilibrium(res.model)
    held = mb.sensitivities(rest, names)
    assert held.effort("push", names[0])[0] == 0.0
    assert held.effort("push", names[2])[0] == pytest.approx(-g * np.sin(slope), rel=1e-12)


def test_inverse_dynamics_with_joint_friction_against_differences():
    # a slider-crank with friction in its pins and rail: the frictions follow the reactions
    # they change, so each parameter moves both; efforts and a pin's reaction
    a, rod_angle, pin_b = mechanisms.slider_crank_positions(1.1, 0.12, 0.26)
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81), name="slider-crank with friction")
    crank = b.add_body("crank", mass=1.0, inertia=0.001, position=a / 2, angle=1.1)
    rod = b.add_body("rod", mass=2.0, inertia=0.01, position=(a + pin_b) / 2, angle=rod_angle)
    slider = b.add_body("slider", mass=4.0, inertia=0.02, position=pin_b)
    pins = [b.add(Revolute("O", b.ground, crank, at=(0.0, 0.0))),
            b.add(Revolute("A", crank, rod, at=a)),
            b.add(Revolute("B", rod, slider, at=pin_b))]
    rail = b.add(Prismatic("rail", b.ground, slider, axis=(1.0, 0.0)))
    b.add(RotationDriver("motor", pins[0], motion=mb.Ramp(1.1, 3.0)))
    for pin, mu in zip(pins, (0.1, 0.2, 0.15)):
        b.add(mb.JointFriction(f"{pin.name} friction", pin, mu, pin_radius=0.01,
                               stiction_velocity=0.02))
    b.add(mb.JointFriction("rail friction", rail, 0.25, stiction_velocity=0.5))
    model = b.build()
    names = _parameters(model, "forces") + ["bodies.slider.mass", "joints.B.at[0]"]
    res = mb.inverse_dynamics(model, TIMES, tol=1e-14)
    sens = mb.sensitivities(res, names)
    reaction = lambda r: r.joint("B").reaction(on="slider").force  # noqa: E731
    derived = sens.derivative(reaction)
    for j, name in enumerate(names):
        _agree(sens.effort("motor", name), model, name, lambda r: r.joint("motor").effort,
               mb.inverse_dynamics)
        _agree(derived[..., j], model, name, reaction, mb.inverse_dynamics)


def test_bad_input():
    model = mechanisms.slider_crank()
    res = mb.kinematic_analysis(model, [0.0])
    with pytest.raises(mb.ModelError, match="did you mean 'joints.A.point_i"):
        mb.sensitivities(res, ["joints.A.piont_i[0]"])
    one = mb.sensitivities(res, "joints.A.point_i[0]")  # a name, not its letters
    assert one.parameters == ("joints.A.point_i[0]",)
    sens = mb.sensitivities(res, ["joints.A.point_i[0]", "bodies.crank.position[0]"])
    # the joints' points are given in the bodies' frames: where a body is drawn is only the
    # analysis' first guess
    assert not np.any(sens.dq[:, :, 1])
    with pytest.raises(mb.ModelError, match="did you mean 'slider.x'"):
        sens.sensitivity("slidr.x", "joints.A.point_i[0]")
    with pytest.raises(mb.ModelError, match="among those asked for"):
        sens.sensitivity("slider.x", "joints.B.point_i[0]")
    with pytest.raises(mb.ModelError, match="after inverse dynamics or a static"):
        sens.effort("motor", "joints.A.point_i[0]")
    free = mechanisms.slider_crank(crank_speed=None, crank_torque=1.0)
    with pytest.raises(mb.ModelError, match="mb.forward_sensitivities"):
        mb.sensitivities(mb.forward_dynamics(free, (0.0, 0.01)), ["bodies.rod.mass"])


def test_static_equilibrium_closed_form():
    # a bar of mass m, its centre c from its pin, on a rotational spring k (free at the
    # drawing's angle 0) rests where F = k theta + m g c cos(theta) = 0; implicitly
    # dtheta/dk = -theta / F_theta and dtheta/dm = -g c cos(theta) / F_theta, F_theta = k -
    # m g c sin(theta); the pin carries the weight: d(pin force)/dm = g
    model = mb.load(EXAMPLES / "pendulum_spring_equilibrium.yaml")
    res = mb.static_equilibrium(model, 0.0, release=True)
    sens = mb.sensitivities(res, ["forces.spring.stiffness", "bodies.bar.mass",
                                  "bodies.bar.inertia"])
    k, m, g, c = 10.0, 2.0, 9.81, 0.4
    theta = res.q[0, model.coordinate_index("bar.theta")]
    assert k * theta + m * g * c * np.cos(theta) == pytest.approx(0.0, abs=1e-9)
    F_theta = k - m * g * c * np.sin(theta)
    assert sens.sensitivity("bar.theta", "forces.spring.stiffness")[0] == pytest.approx(
        -theta / F_theta, abs=1e-11)
    assert sens.sensitivity("bar.theta", "bodies.bar.mass")[0] == pytest.approx(
        -g * c * np.cos(theta) / F_theta, abs=1e-11)
    assert not np.any(sens.dq[:, :, 2])  # the inertia: nothing at rest
    pin = sens.derivative(lambda r: r.joint("O").reaction(on="bar").force, "bodies.bar.mass")
    assert pin[0] == pytest.approx([0.0, g], abs=1e-9)


@pytest.mark.parametrize("release", [True, False], ids=["released", "held"])
def test_static_equilibrium_against_differences(release):
    model = mb.load(EXAMPLES / "pendulum_spring_equilibrium.yaml")
    times = [0.0, 0.5]
    analysis = lambda m, _, tol: mb.static_equilibrium(  # noqa: E731
        m, times, release=release, tol=1e-13)
    res = analysis(model, None, None)
    names = _parameters(model)
    sens = mb.sensitivities(res, names)
    for j, name in enumerate(names):
        _agree(sens.dq[:, :, j], model, name, lambda r: r.q, analysis)
        _agree(sens.dlam[:, :, j], model, name, lambda r: r.lam, analysis)


def mass_on_rail(slope: float, k_x: float = 40.0, k_y: float = 90.0, m: float = 2.5):
    """A puck of mass ``m`` on a rail along ``(1, slope)`` through the origin, held there by
    two springs at their free length, one along x (stiffness ``k_x``), one along y: no
    gravity. Small motions along the rail at the angle ``alpha = atan(slope)`` see the
    stiffness ``k_x cos^2 + k_y sin^2``."""
    b = mb.ModelBuilder(dim=2, gravity=(0.0, 0.0))
    puck = b.add_body("puck", mass=m, inertia=0.01, position=(0.0, 0.0))
    b.add(Prismatic("rail", b.ground, puck, axis=(1.0, slope), point_i=(0.0, 0.0),
                    point_j=(0.0, 0.0)))
    b.add(mb.SpringDamper("x", b.ground, puck, point_i=(-1.0, 0.0), point_j=(0.0, 0.0),
                          stiffness=k_x, free_length=1.0))
    b.add(mb.SpringDamper("y", b.ground, puck, point_i=(0.0, -1.0), point_j=(0.0, 0.0),
                          stiffness=k_y, free_length=1.0))
    return b.build()


def test_mode_frequency_closed_form():
    # w^2 = (k_x cos^2 a + k_y sin^2 a) / m; the rail's slope s = tan(a) turns it, all of
    # whose effect comes through the constraint (the formula sheet's 5.2 check):
    # dw^2/ds = (k_y - k_x) sin(2 a) / m / (1 + s^2)
    s, k_x, k_y, m = 0.4, 40.0, 90.0, 2.5
    modes = mb.vibration_modes(mass_on_rail(s, k_x, k_y, m))
    a = np.arctan(s)
    w2 = (k_x * np.cos(a) ** 2 + k_y * np.sin(a) ** 2) / m
    assert modes.frequencies[0] == pytest.approx(np.sqrt(w2) / (2 * np.pi), rel=1e-11)
    sens = mb.sensitivities(modes, ["joints.rail.axis[1]", "forces.x.stiffness",
                                    "bodies.puck.mass"])
    hz = lambda dw2: dw2 / (2 * np.sqrt(w2)) / (2 * np.pi)  # noqa: E731
    assert sens.frequency(0, "joints.rail.axis[1]") == pytest.approx(
        hz((k_y - k_x) * np.sin(2 * a) / m / (1 + s**2)), rel=1e-9)
    assert sens.frequency(0, "forces.x.stiffness") == pytest.approx(
        hz(np.cos(a) ** 2 / m), rel=1e-9)
    assert sens.frequency(0, "bodies.puck.mass") == pytest.approx(hz(-w2 / m), rel=1e-9)
    assert sens.damping_ratios[0] == pytest.approx([0.0, 0.0, 0.0], abs=1e-12)


def test_modes_along_a_motion_against_differences():
    # the four-bar on its elastic shaft, its frequency against every number
    model = mechanisms.four_bar(shaft_stiffness=50.0, gravity=0.0)
    times = [0.0, 0.3]
    along = mb.vibration_modes_along(model, times)
    names = _parameters(model)
    sens = mb.sensitivities(along, names)
    for j, name in enumerate(names):
        value, size = parameter_value(model, name)
        h = 1e-4 * (max(abs(value), size) or model.length_scale)
        values = np.array([mb.vibration_modes_along(mb.with_parameters(
            model, {name: value + o * h}), times).frequencies for o in OFFSETS])
        reference = np.tensordot(WEIGHTS, values, axes=1) / h
        noise = 15 * np.finfo(float).eps * np.max(np.abs(along.frequencies)) / h
        assert np.max(np.abs(sens.frequencies[..., j] - reference)) <= 1e-8 * max(
            np.max(np.abs(reference)), 1.0) + noise, name


def test_redundant_constraints():
    # a planar four-bar of four spatial revolutes: 3 redundant rows. Its positions follow a
    # hinge moved in its plane (against differences), not a hinge's axis tilted out of it
    # (four hinges whose axes are not parallel lock up); its multipliers are the
    # minimum-norm ones, whose derivatives are not the model's
    import math

    from test_spatial_dynamics import spatial_four_bar_in_plane

    planar = mb.inverse_dynamics(mechanisms.four_bar(crank_speed=2 * math.pi), TIMES)
    model = spatial_four_bar_in_plane(planar, driven=True, revolutes_only=True)
    res = mb.kinematic_analysis(model, TIMES, tol=1e-14)
    name = "joints.A.at[0]"
    sens = mb.sensitivities(res, [name])
    centres = model.position_coordinates
    _agree(sens.dq[:, centres, 0], model, name, lambda r: r.q[:, centres])
    with pytest.raises(mb.ModelError, match="moves its redundant constraints apart"):
        mb.sensitivities(res, ["joints.A.axis[0]"])
    with pytest.raises(mb.ModelError, match="minimum-norm"):
        mb.sensitivities(mb.inverse_dynamics(model, TIMES), [name])


def test_rows_whose_own_numbers_change():
    # a rack's pitch radius is a number of its row itself (not a body vector, a constant or
    # a motion): its rows are differenced along the model's variants
    from test_gears import rack_and_pinion

    model = rack_and_pinion()
    name = "joints.mesh.radius"
    sens = mb.sensitivities(mb.inverse_dynamics(model, TIMES, tol=1e-14), [name])
    assert sens.tangents[0]._rows_own
    for got, of in ((sens.dq, "q"), (sens.dqd, "qd"), (sens.dqdd, "qdd"), (sens.dlam, "lam")):
        _agree(got[:, :, 0], model, name, lambda r: getattr(r, of), mb.inverse_dynamics)
    assert np.max(np.abs(sens.dq)) > 0.1


def test_a_rows_constant():
    # the slider-crank with its rod a massless Distance joint from the crank pin to the slider:
    # the rod's length is the row's constant c0, and x_B = a cos(theta) + r as before, so
    # dx_B/dl = l / r
    from mbd3d.joints import Distance

    a, l, theta = 0.12, 0.30, 1.1
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81))
    crank = b.add_body("crank", mass=1.0, inertia=0.001, position=(0.05, 0.05), angle=theta)
    slider = b.add_body("slider", mass=4.0, inertia=0.02, position=(0.35, 0.0))
    pin = b.add(Revolute("O", b.ground, crank, point_i=(0.0, 0.0), point_j=(-a / 2, 0.0)))
    b.add(Distance("rod", crank, slider, point_i=(a / 2, 0.0), point_j=(0.0, 0.0), length=l))
    b.add(Prismatic("rail", b.ground, slider, axis=(1.0, 0.0), point_i=(0.0, 0.0),
                    point_j=(0.0, 0.0)))
    b.add(RotationDriver("motor", pin, motion=mb.Ramp(theta, 2.0)))
    sens = mb.sensitivities(mb.kinematic_analysis(b.build(), [0.0]), "joints.rod.length")
    r = np.sqrt(l**2 - a**2 * np.sin(theta) ** 2)
    assert sens.sensitivity("slider.x", "joints.rod.length")[0] == pytest.approx(l / r,
                                                                                abs=1e-12)
