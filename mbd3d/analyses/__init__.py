"""The analyses: position (Newton-Raphson), velocity and acceleration analysis, kinematic
analysis and inverse dynamics, statics, forward dynamics, modes and linearisation, the mobility
report, and the watch for singular positions.

Forward dynamics takes one path (:mod:`.driver` has the diagram): :mod:`.dynamics` checks the
request and picks the integrator, :mod:`.driver` runs it (initial state, step loop, events,
outputs, observers), :mod:`.explicit` (the compiled Runge-Kutta pairs) and :mod:`.implicit`
(generalized-alpha) are the integrators, :mod:`.accelerations` the accelerations and multipliers
at a state, :mod:`.initial` the consistent initial state. The others: :mod:`.position`,
:mod:`.kinematics`, :mod:`.statics`, :mod:`.modes`, :mod:`.linearization`, :mod:`.mobility`
and :mod:`.passages`. What belongs here: an analysis of a model, taking ``(model, t, q, qd)``
and returning arrays or Results; not a model element (``mbd3d.model``) nor a file format
(``mbd3d.io``).
"""

from mbd3d.analyses.dynamics import forward_dynamics
from mbd3d.analyses.kinematics import inverse_dynamics, kinematic_analysis
from mbd3d.analyses.linearization import linearize_at
from mbd3d.analyses.modes import vibration_modes_along
from mbd3d.analyses.statics import static_equilibrium
from mbd3d.io import model_file

# the analyses a model file's analyses: section can ask for, by kind
model_file.ANALYSES.update(kinematic=kinematic_analysis, inverse=inverse_dynamics,
                           forward=forward_dynamics, equilibrium=static_equilibrium,
                           modes=vibration_modes_along, linearize=linearize_at)
