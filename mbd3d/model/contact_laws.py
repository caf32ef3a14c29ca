"""Normal force laws of compliant contacts, and their damping calibrated to a coefficient of
restitution.

Every law is ``F_n = max(0, K delta^n + D delta^p delta')`` [N] at penetration ``delta`` [m]
and penetration rate ``delta'`` [m/s], evaluated by :mod:`mbd3d.numerics.compiled.contacts`:

- :class:`LinearContact`: ``k delta + c delta'``;
- :class:`HertzContact`: ``K delta^(3/2) + alpha sqrt(m* K) delta^(1/4) delta'`` (Tsuji's
  damping);
- :class:`HuntCrossley`: ``K delta^n + K (chi / v0) delta^n delta'``;
- :class:`ImpactFunction`: MSC Adams' IMPACT, ``K delta^n + c_max S(delta / d) delta'``, its
  damping ramped in by the cubic step ``S(b) = b^2 (3 - 2 b)`` up to the penetration ``d``
  (``S = 1`` beyond).

:class:`RigidImpact` is no force law: a contact or stop with it is a rigid unilateral
constraint, whose touches forward dynamics resolves as impacts (:mod:`mbd3d.analyses.impacts`).

The first two dissipate a fraction of an impact's energy that does not depend on the impact
speed: their damping is calibrated exactly to the restitution asked for, the force never
pulling (the calibration solves the one-degree-of-freedom impact of the effective mass ``m*``
once, :func:`clipped_restitution`). In the Hunt-Crossley family the restitution falls with
the impact speed, as measured on real bodies; ``chi`` is calibrated at a stated impact speed
``v0`` by the exact relation ``chi (1 + e) = ln((1 + chi) / (1 - chi e))`` or by one of the
published approximations (Hunt-Crossley 1975, Lankarani-Nikravesh 1990, Flores et al. 2011,
Gonthier et al. 2004), which give other restitutions than the one they are given.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from mbd3d.errors import ModelError
from mbd3d.numerics.checks import finite_scalar

__all__ = ["ContactLaw", "LinearContact", "HertzContact", "HuntCrossley", "ImpactFunction",
           "RigidImpact", "clipped_restitution", "hertz_stiffness", "pair_mass"]


def _restitution(value: float, what: str) -> float:
    e = finite_scalar(value, what)
    if not 0.0 <= e <= 1.0:
        raise ModelError(f"{what} must lie in [0, 1], got {value!r}")
    if e == 0.0:
        raise ModelError(f"{what}: a compliant contact cannot stop an impact dead "
                         "(restitution 0 needs an infinite damping); give e > 0")
    return e


def _stiffness(value: float, what: str) -> float:
    k = finite_scalar(value, what)
    if not k > 0.0:
        raise ModelError(f"{what} must be > 0, got {value!r}")
    return k


class ContactLaw:
    """Base of the normal force laws: :meth:`constants` gives ``(K, n, D, p)``."""

    #: whether the law is a rigid contact's (no force: impacts, :class:`RigidImpact`)
    rigid = False

    def constants(self, effective_mass: float, radius: float, what: str
                  ) -> tuple[float, float, float, float]:
        """``(K, n, D, p)`` of the law for a pair of effective mass ``m*`` [kg] (inf: both
        bodies immovable) and effective radius ``R`` [m] (inf: plane on plane)."""
        raise NotImplementedError

    def damping_ramp(self, what: str) -> float:
        """The penetration ``d`` [m] over which the damping ramps in along a cubic step
        (:class:`ImpactFunction`), or 0: the damping ``D delta^p`` of :meth:`constants`."""
        return 0.0


@dataclass(frozen=True)
class LinearContact(ContactLaw):
    """A linear spring-damper normal to the surfaces: ``F_n = max(0, k delta + c delta')``.

    Parameters
    ----------
    stiffness : float, optional
        ``k`` [N/m], > 0. Or ``frequency``.
    frequency : float, optional
        [Hz] > 0: ``k = m* (2 pi frequency)^2``, the natural frequency of the pair's effective
        mass ``m*`` on the spring (of a joint limit's effective moment of inertia: ``k`` in
        N m/rad).
    damping : float, optional
        ``c`` [N s/m], >= 0. Give this or ``restitution``.
    restitution : float, optional
        Coefficient of restitution in (0, 1]: ``c`` is calibrated so that a free impact of the
        pair's effective mass ``m*`` rebounds with it (the force never pulling), whatever the
        impact speed.
    """

    stiffness: float | None = None
    damping: float | None = None
    restitution: float | None = None
    frequency: float | None = None

    def constants(self, effective_mass, radius, what):
        if (self.stiffness is None) == (self.frequency is None):
            raise ModelError(f"{what}: give the LinearContact a stiffness or a frequency, one "
                             "of them")
        if self.stiffness is not None:
            k = _stiffness(self.stiffness, f"{what}: stiffness")
        elif not math.isfinite(effective_mass):
            raise ModelError(f"{what}: a frequency needs a body that moves (the effective "
                             "mass is infinite)")
        else:
            k = effective_mass * (2 * math.pi * _stiffness(self.frequency,
                                                           f"{what}: frequency")) ** 2
        if (self.damping is None) == (self.restitution is None):
            raise ModelError(f"{what}: give the damping or the restitution of the "
                             f"LinearContact, one of them")
        if self.damping is not None:
            c = finite_scalar(self.damping, f"{what}: damping")
            if c < 0.0:
                raise ModelError(f"{what}: damping must be >= 0, got {self.damping!r}")
            return k, 1.0, c, 0.0
        e = _restitution(self.restitution, f"{what}: restitution")
        return k, 1.0, _calibrated(1.0, 0.0, e) * _mass_scale(effective_mass, k), 0.0


@dataclass(frozen=True)
class HertzContact(ContactLaw):
    """Hertz's law of two elastic spheres (or a sphere and a plane), with a damping that
    gives the restitution asked for: ``F_n = max(0, K delta^(3/2) + alpha sqrt(m* K)
    delta^(1/4) delta')`` (Tsuji et al. 1992).

    Parameters
    ----------
    stiffness : float, optional
        ``K`` [N/m^(3/2)]; default Hertz's ``(4/3) E* sqrt(R)`` from the materials and the
        effective radius ``1/R = 1/r_i + 1/r_j``.
    restitution : float
        In (0, 1]; ``alpha`` is calibrated for it on a free impact of the effective mass ``m*``
        (exact whatever the impact speed; 1: no damping).
    young_modulus, poisson_ratio : float or (float, float)
        ``E`` [Pa] and ``nu`` of both bodies, or of body i and body j:
        ``1/E* = (1 - nu_i^2)/E_i + (1 - nu_j^2)/E_j``.
    """

    stiffness: float | None = None
    restitution: float = 1.0
    young_modulus: float | tuple | None = None
    poisson_ratio: float | tuple = 0.3

    def constants(self, effective_mass, radius, what):
        if self.stiffness is not None:
            K = _stiffness(self.stiffness, f"{what}: stiffness")
        elif self.young_modulus is None:
            raise ModelError(f"{what}: give the HertzContact a stiffness or the bodies' "
                             "young_modulus (and poisson_ratio)")
        else:
            K = hertz_stiffness(self.young_modulus, self.poisson_ratio, radius, what)
        e = _restitution(self.restitution, f"{what}: restitution")
        return K, 1.5, _calibrated(1.5, 0.25, e) * _mass_scale(effective_mass, K), 0.25


@dataclass(frozen=True)
class RigidImpact(ContactLaw):
    """Rigid bodies: the shapes never overlap, and every touch is an impact resolved by
    Newton's law of restitution on the whole mechanism at once (the joints hold through it).

    At a touch the gap's rate ``v-`` (< 0) turns into ``-e v-``, on every contact that
    touches closing at that instant together (:mod:`mbd3d.analyses.impacts`), with a friction
    impulse where the contact has ``friction``: Coulomb's law on the slip after the impact;
    forward dynamics only (the other analyses see no force).

    Parameters
    ----------
    restitution : float
        Newton's coefficient ``e`` in [0, 1] (1: no energy lost).
    rest_speed : float
        [m/s; a stop of a turning coordinate: rad/s] > 0. A contact whose gap opens slower than
        this after an impact while its bodies still press together would bounce ever shorter
        (an infinity of impacts in a finite time): it has come to rest. The explicit
        integrators then hold it closed until its force would pull
        (:mod:`mbd3d.analyses.resting`), sticking or sliding with the contact's Coulomb
        friction (:mod:`mbd3d.analyses.sticking`); generalized-alpha stops the run there,
        naming it, with the results up to that time.
    static_friction : float, optional
        Coulomb's static coefficient ``mu_s``, at least the contact's ``friction`` (the
        kinetic one, with which it slides): the contact sticks, at rest and through an
        impact, while its friction stays within ``mu_s`` times its normal force (or
        impulse). Default: the contact's ``friction`` (one coefficient). A sticking contact
        that gives way then slides with less than held it: stick-slip.
    """

    restitution: float
    rest_speed: float = 1e-3
    static_friction: float | None = None

    rigid = True

    def constants(self, effective_mass, radius, what):
        e = finite_scalar(self.restitution, f"{what}: restitution")
        if not 0.0 <= e <= 1.0:
            raise ModelError(f"{what}: restitution must lie in [0, 1], got "
                             f"{self.restitution!r}")
        _stiffness(self.rest_speed, f"{what}: rest_speed")
        if self.static_friction is not None:
            mu_s = finite_scalar(self.static_friction, f"{what}: static_friction")
            if mu_s < 0.0:
                raise ModelError(f"{what}: static_friction must be >= 0, got "
                                 f"{self.static_friction!r}")
        return 0.0, 1.0, 0.0, 0.0


@dataclass(frozen=True)
class ImpactFunction(ContactLaw):
    """The IMPACT function of MSC Adams (and of the solvers that share its function library):
    ``F_n = max(0, K delta^n + c_max S(delta / d) delta')``, where the damping coefficient
    rises from zero at first touch to ``c_max`` at the penetration ``d`` along the cubic step
    ``S(b) = b^2 (3 - 2 b)`` (Adams' ``STEP(x, x1 - d, c_max, x1, 0)``; ``S = 1`` beyond
    ``d``), so that the force does not jump when the shapes touch.

    The restitution it gives depends on the impact speed and the mass; the constants are
    taken as Adams takes them, not calibrated.

    Parameters
    ----------
    stiffness : float
        ``K`` [N/m^n] > 0.
    damping : float
        ``c_max`` [N s/m] >= 0, the damping coefficient at penetrations of ``d`` and more.
    penetration : float
        ``d`` [m] > 0, the penetration at which the damping reaches ``c_max``.
    exponent : float
        ``n`` > 0 (3/2: Hertz; above 1 the spring stiffens).
    """

    stiffness: float
    damping: float
    penetration: float
    exponent: float = 1.5

    def constants(self, effective_mass, radius, what):
        K = _stiffness(self.stiffness, f"{what}: stiffness")
        n = _stiffness(self.exponent, f"{what}: exponent")
        c = finite_scalar(self.damping, f"{what}: damping")
        if c < 0.0:
            raise ModelError(f"{what}: damping must be >= 0, got {self.damping!r}")
        return K, n, c, 0.0

    def damping_ramp(self, what):
        return _stiffness(self.penetration, f"{what}: penetration")


#: chi of the published calibrations of the Hunt-Crossley family, from the restitution e
_CHI = {
    "hunt-crossley": lambda e: 1.5 * (1.0 - e),
    "lankarani-nikravesh": lambda e: 0.75 * (1.0 - e * e),
    "flores": lambda e: 1.6 * (1.0 - e) / e,
    "gonthier": lambda e: (1.0 - e * e) / e,
}


@dataclass(frozen=True)
class HuntCrossley(ContactLaw):
    """The Hunt-Crossley family: ``F_n = K delta^n (1 + chi delta' / v0)``.

    Parameters
    ----------
    stiffness : float
        ``K`` [N/m^n].
    restitution : float
        ``e`` in (0, 1] at the impact speed ``impact_speed``.
    impact_speed : float
        ``v0`` [m/s], > 0: the speed at which the pair rebounds with ``e``; slower impacts
        rebound more, faster ones less.
    exponent : float
        ``n`` (3/2: Hertz).
    calibration : str
        How ``chi`` follows from ``e``: ``"exact"`` (the restitution is ``e`` at ``v0``), or
        a published approximation: ``"hunt-crossley"`` (``3 (1 - e) / 2``),
        ``"lankarani-nikravesh"`` (``3 (1 - e^2) / 4``), ``"flores"`` (``8 (1 - e) / (5 e)``),
        ``"gonthier"`` (``(1 - e^2) / e``).
    """

    stiffness: float
    restitution: float
    impact_speed: float
    exponent: float = 1.5
    calibration: str = "exact"

    def constants(self, effective_mass, radius, what):
        K = _stiffness(self.stiffness, f"{what}: stiffness")
        e = _restitution(self.restitution, f"{what}: restitution")
        v0 = _stiffness(self.impact_speed, f"{what}: impact_speed")
        n = _stiffness(self.exponent, f"{what}: exponent")
        if self.calibration == "exact":
            chi = exact_chi(e)
        elif self.calibration in _CHI:
            chi = _CHI[self.calibration](e)
        else:
            raise ModelError(f"{what}: calibration must be 'exact' or one of "
                             f"{sorted(_CHI)}, got {self.calibration!r}")
        return K, n, K * chi / v0, n


def hertz_stiffness(young_modulus, poisson_ratio, radius: float, what: str) -> float:
    """Hertz's ``K = (4/3) E* sqrt(R)`` [N/m^(3/2)] of two bodies of the given materials
    (one value for both, or a pair) at effective radius ``R`` [m]."""
    E = np.broadcast_to(np.asarray(young_modulus, dtype=float), (2,))
    nu = np.broadcast_to(np.asarray(poisson_ratio, dtype=float), (2,))
    if not (np.all(np.isfinite(E)) and np.all(E > 0)):
        raise ModelError(f"{what}: young_modulus must be > 0, got {young_modulus!r}")
    if not (np.all(np.isfinite(nu)) and np.all((nu > -1.0) & (nu < 0.5))):
        raise ModelError(f"{what}: poisson_ratio must lie in (-1, 0.5), got {poisson_ratio!r}")
    if not (math.isfinite(radius) and radius > 0.0):
        raise ModelError(f"{what}: Hertz's stiffness needs a curved surface (a sphere, a "
                         "capsule, a box's rounded corners); give the stiffness instead")
    E_star = 1.0 / float(np.sum((1.0 - nu ** 2) / E))
    return 4.0 / 3.0 * E_star * math.sqrt(radius)


def _mass_scale(effective_mass: float, K: float) -> float:
    # D = alpha sqrt(m* K): an immovable pair (m* infinite) never moves, any damping will do
    return math.sqrt(effective_mass * K) if math.isfinite(effective_mass) else 0.0


def exact_chi(e: float) -> float:
    """The Hunt-Crossley ``chi`` that rebounds with ``e`` exactly: the root of ``chi (1 + e)
    = ln((1 + chi) / (1 - chi e))`` on ``(0, 1/e)`` (0 for ``e = 1``)."""
    from scipy.optimize import brentq  # noqa: PLC0415

    if e >= 1.0:
        return 0.0
    f = lambda chi: math.log1p(chi) - math.log1p(-chi * e) - chi * (1.0 + e)  # noqa: E731
    # f = (e^2 - 1) chi^2 / 2 + O(chi^3) < 0 near 0, and f -> +inf as chi -> 1/e
    return brentq(f, 1e-6, (1.0 - 1e-15) / e, xtol=1e-15, rtol=1e-15, maxiter=500)


def clipped_restitution(n: float, p: float, alpha: float) -> float:
    """The restitution of a free impact of unit mass at unit speed on the law ``F = max(0,
    delta^n + alpha delta^p delta')``: the speed at which the pair parts (where the force
    falls to zero, after which it would pull). The same for any mass, stiffness and speed
    when ``p = (n - 1) / 2`` (the linear law and Tsuji's)."""
    from scipy.integrate import solve_ivp  # noqa: PLC0415

    def rhs(_t, y):
        delta, rate = y
        return [rate, -(max(delta, 0.0) ** n + alpha * max(delta, 0.0) ** p * rate)]

    def parted(_t, y):  # the force falls to zero (after the deepest point)
        delta, rate = y
        return max(delta, 0.0) ** n + alpha * max(delta, 0.0) ** p * rate if rate < 0 else 1.0

    parted.terminal, parted.direction = True, -1
    solution = solve_ivp(rhs, (0.0, 1e3), [0.0, 1.0], method="DOP853", rtol=1e-13, atol=1e-15,
                         events=parted)
    if not solution.t_events[0].size:
        raise ModelError("the contact law's impact did not end (internal error)")
    return float(-solution.y_events[0][0][1])


@functools.lru_cache(maxsize=256)
def _calibrated(n: float, p: float, e: float) -> float:
    """``alpha`` of :func:`clipped_restitution` that rebounds with ``e`` in (0, 1] (0 for
    ``e = 1``)."""
    from scipy.optimize import brentq  # noqa: PLC0415

    if e >= 1.0:
        return 0.0
    upper = 1.0
    while clipped_restitution(n, p, upper) > e:
        upper *= 2.0
        if upper > 1e6:
            raise ModelError(f"restitution {e} is too small to calibrate; use 0 or more")
    return brentq(lambda alpha: clipped_restitution(n, p, alpha) - e, 0.0, upper,
                  xtol=1e-14, rtol=1e-13)


def pair_mass(masses: list) -> float:
    """The effective mass (or moment of inertia) ``1 / sum(1 / m)`` of a pair's moving bodies'
    ``masses`` [kg] that a law is calibrated with (inf: none moves)."""
    inverse = sum(1.0 / m for m in masses)
    return 1.0 / inverse if inverse > 0.0 else math.inf
