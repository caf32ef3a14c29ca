"""mbd3d: kinematic and dynamic analysis of planar and spatial mechanisms in absolute coordinates.

Build a model with :class:`ModelBuilder` (bodies here, joints and drivers from
:mod:`mbd3d.joints`, forces from here), then run an analysis; every analysis returns a
:class:`Results`.

>>> import numpy as np
>>> import mbd3d as mb
>>> from mbd3d.joints import Revolute, RotationDriver
>>> b = mb.ModelBuilder(dim=2)
>>> crank = b.add_body("crank", mass=1.0, inertia=0.01, position=(0.05, 0.0))
>>> pin = b.add(Revolute("O", b.ground, crank, at=(0.0, 0.0)))
>>> _ = b.add(RotationDriver("motor", pin, motion=mb.Ramp(0.0, 2 * np.pi)))
>>> res = mb.inverse_dynamics(b.build(), np.linspace(0.0, 1.0, 5))
>>> float(np.round(res.body("crank").angle[-1], 6))
6.283185
"""

from mbd3d._checkout import map_siblings as _map_siblings

_map_siblings(__path__[0])

from mbd3d.numerics import rotations  # noqa: E402 (the sub-packages are found from here on)
from mbd3d.model.body import Body
from mbd3d.analyses.dynamics import METHODS, forward_accelerations, forward_dynamics, project_state
from mbd3d.analyses.driver import Event
from mbd3d.model.equations import kinetic_energy, potential_energy
from mbd3d.errors import (AnalysisError, AssemblyError, IntegrationError, MBDError, ModelError,
                          NotFullyDrivenError, OverDrivenError, SingularJacobianError,
                          AccuracyWarning, ContactWarning, LiftOffWarning, StiffnessWarning)
from mbd3d.model.forces import ForceState, PointForce, Torque
from mbd3d.model.springs import RotationalSpringDamper, SpringDamper
from mbd3d.model.friction import JointFriction
from mbd3d.model.contacts import (Box, Cam, Capsule, Contact, ContactGroup, ContactStates, Hole,
                                  JointLimit, Plane, Sphere, contact_states)
from mbd3d.model.contact_laws import (HertzContact, HuntCrossley, ImpactFunction, LinearContact,
                                      RigidImpact)
from mbd3d.analyses.kinematics import (inverse_dynamics, kinematic_analysis, solve_acceleration,
                                       solve_velocity)
from mbd3d.analyses.mobility import MobilityReport, mobility
from mbd3d.io.observers import Observer, ProgressBar
from mbd3d.model.builder import Model, ModelBuilder
from mbd3d.model.motion import Constant, Function, Harmonic, Motion, Polynomial, Ramp, SmoothStep
from mbd3d.analyses.position import solve_position
from mbd3d.analyses.initial import InitialStateWarning
from mbd3d.analyses.linearization import LinearModel, linearize
from mbd3d.analyses.modes import Modes, ModesAlong, vibration_modes, vibration_modes_along
from mbd3d.analyses.statics import static_equilibrium
from mbd3d.analyses.sensitivities import sensitivities
from mbd3d.analyses.forward_sensitivities import forward_sensitivities
from mbd3d.analyses.states import (driven_coordinates, forward_dynamics_at,
                                  inverse_dynamics_at, joint_space_dynamics_at)
from mbd3d.io.results import Results, format_table, read_results
from mbd3d.io.sensitivity_results import ModeSensitivities, Sensitivities
from mbd3d.io.model_file import load
from mbd3d.io.model_writer import save
from mbd3d.io.parameters import ModelVariants, parameters, with_parameters
from mbd3d.io.urdf import UrdfWarning, load_urdf, urdf_builder
from mbd3d.io.mjcf import MjcfWarning, load_mjcf, mjcf_builder

__version__ = "0.1.0"

__all__ = [
    "ModelBuilder", "Model", "Body", "rotations",
    "Motion", "Constant", "Ramp", "Harmonic", "Polynomial", "SmoothStep", "Function",
    "PointForce", "Torque", "SpringDamper", "RotationalSpringDamper", "ForceState",
    "JointFriction",
    "ContactWarning", "Contact", "ContactGroup", "JointLimit", "Sphere", "Plane",
    "Capsule", "Box", "Hole", "Cam", "LinearContact", "HertzContact", "HuntCrossley",
    "ImpactFunction", "RigidImpact",
    "contact_states", "ContactStates",
    "solve_position", "solve_velocity", "solve_acceleration", "kinematic_analysis",
    "inverse_dynamics", "inverse_dynamics_at", "joint_space_dynamics_at", "driven_coordinates",
    "forward_dynamics_at",
    "static_equilibrium", "vibration_modes", "Modes",
    "vibration_modes_along", "ModesAlong", "linearize",
    "LinearModel", "forward_dynamics", "Event",
    "forward_accelerations",
    "project_state", "METHODS",
    "mobility", "MobilityReport", "Results", "read_results", "load", "save", "parameters", "with_parameters",
    "sensitivities", "forward_sensitivities", "Sensitivities", "ModeSensitivities",
    "ModelVariants",
    "load_urdf", "urdf_builder",
    "UrdfWarning", "load_mjcf", "mjcf_builder", "MjcfWarning",
    "format_table", "kinetic_energy", "potential_energy",
    "Observer", "ProgressBar",
    "MBDError", "ModelError", "NotFullyDrivenError", "OverDrivenError", "AnalysisError",
    "AssemblyError",
    "SingularJacobianError", "IntegrationError", "StiffnessWarning", "LiftOffWarning", "AccuracyWarning", "InitialStateWarning",
]
