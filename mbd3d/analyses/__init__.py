"""The analyses: position (Newton-Raphson), velocity and acceleration analysis, kinematic
analysis and inverse dynamics, forward dynamics with the explicit integrators and with
generalized-alpha, the mobility report, and the watch for singular positions.

Modules: :mod:`.position`, :mod:`.kinematics`, :mod:`.dynamics` (forward dynamics, the explicit
integrators' driver), :mod:`.implicit` (generalized-alpha), :mod:`.mobility` and
:mod:`.passages`.
"""
