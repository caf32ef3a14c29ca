"""Independent one-degree-of-freedom model of the in-line slider-crank (for the tests only).

Everything follows from the closed-form geometry as functions of the crank angle ``phi``; the
derivatives of the generalized mass and of the potential are taken by complex step, which is
exact to rounding for these analytic functions. Nothing here uses mbd3d.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

STEP = 1e-30


class SliderCrankOracle:
    def __init__(self, r=0.12, l=0.26, m=(1.0, 2.0, 4.0), J=(0.001, 0.01, 0.02), g=9.81):
        self.r, self.l, self.m, self.J, self.g = r, l, m, J, g

    # closed-form kinematics
    def slider_x(self, phi):
        r, l = self.r, self.l
        return r * np.cos(phi) + np.sqrt(l * l - (r * np.sin(phi)) ** 2)

    def slider_x_derivatives(self, phi):
        """dx/dphi and d2x/dphi2, written out by hand."""
        r, l = self.r, self.l
        s, c = np.sin(phi), np.cos(phi)
        S = np.sqrt(l * l - r * r * s * s)
        d1 = -r * s - r * r * s * c / S
        d2 = -r * c - r * r * (c * c - s * s) / S - r**4 * s * s * c * c / S**3
        return d1, d2

    def rod_angle(self, phi):
        return np.arcsin(-self.r * np.sin(phi) / self.l)

    def _rates(self, phi):
        """Velocity of each centre of mass and angular velocity of each body per unit phi-dot."""
        r, l = self.r, self.l
        psi = self.rod_angle(phi)
        dpsi = -r * np.cos(phi) / (l * np.sqrt(1 - (r * np.sin(phi) / l) ** 2))
        g1 = 0.5 * r * np.array([-np.sin(phi), np.cos(phi)])
        g2 = r * np.array([-np.sin(phi), np.cos(phi)]) + 0.5 * l * dpsi * np.array(
            [-np.sin(psi), np.cos(psi)])
        g3 = np.array([self.slider_x_derivatives(phi)[0], 0.0 * phi])
        return (g1, g2, g3), (1.0 + 0.0 * phi, dpsi, 0.0 * phi)

    def generalized_mass(self, phi):
        vel, omega = self._rates(phi)
        return sum(m * (v @ v) + J * w * w for m, J, v, w in zip(self.m, self.J, vel, omega))

    def potential(self, phi):
        r, l = self.r, self.l
        psi = self.rod_angle(phi)
        y1 = 0.5 * r * np.sin(phi)
        y2 = r * np.sin(phi) + 0.5 * l * np.sin(psi)
        return self.g * (self.m[0] * y1 + self.m[1] * y2)

    def _complex_step(self, f, phi):
        return np.imag(f(phi + 1j * STEP)) / STEP

    def driving_torque(self, phi, phi_dot, phi_ddot=0.0):
        """Torque on the crank for a prescribed motion (Lagrange's equation solved for it)."""
        M = self.generalized_mass(phi)
        dM = self._complex_step(self.generalized_mass, phi)
        dV = self._complex_step(self.potential, phi)
        return M * phi_ddot + 0.5 * dM * phi_dot**2 + dV

    def simulate(self, torque, phi0, t_eval):
        """Crank angle and speed under a constant torque, from rest, DOP853 at 1e-12."""
        def rhs(t, y):
            phi, w = y
            M = self.generalized_mass(phi)
            dM = self._complex_step(self.generalized_mass, phi)
            dV = self._complex_step(self.potential, phi)
            return [w, (torque - dV - 0.5 * dM * w * w) / M]
        sol = solve_ivp(rhs, (t_eval[0], t_eval[-1]), [phi0, 0.0], method="DOP853",
                        t_eval=t_eval, rtol=1e-12, atol=1e-12)
        return sol.y
