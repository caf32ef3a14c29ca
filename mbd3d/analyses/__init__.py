"""The analyses: position (Newton-Raphson), velocity and acceleration analysis, kinematic
analysis and inverse dynamics, forward dynamics with the explicit integrators and with
generalized-alpha, the mobility report, and the watch for singular positions.

Modules: :mod:`.position`, :mod:`.kinematics`, :mod:`.dynamics` (forward dynamics, the explicit
integrators' driver), :mod:`.implicit` (generalized-alpha), :mod:`.mobility` and
:mod:`.passages`.
"""

from mbd3d.analyses.dynamics import forward_dynamics
from mbd3d.analyses.kinematics import inverse_dynamics, kinematic_analysis
from mbd3d.analyses.statics import static_equilibrium
from mbd3d.io import model_file

# the analyses a model file's analyses: section can ask for, by kind
model_file.ANALYSES.update(kinematic=kinematic_analysis, inverse=inverse_dynamics,
                           forward=forward_dynamics, equilibrium=static_equilibrium)
