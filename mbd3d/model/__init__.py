"""The model and its elements: bodies and their body types, joints' constraint primitives,
force elements, motions, and the equations they make.

Modules: :mod:`.builder` (:class:`ModelBuilder`), :mod:`.built` (the built :class:`Model`),
:mod:`.body` (bodies, the body-type interface, frames), :mod:`.spatial` (spatial bodies in Rodrigues
parameters; planar bodies are :mod:`mbd3d.planar`), :mod:`.element` and :mod:`.primitives`
(constraint elements and the primitives they are made of), :mod:`.constraints` (evaluating
``C``, ``Cq`` and the velocity and acceleration right-hand sides), :mod:`.equations` (mass
matrix, applied and quadratic velocity forces, energies, the augmented accelerations),
:mod:`.forces` (force elements), :mod:`.friction` (joint friction), :mod:`.motion` (prescribed
motions) and :mod:`.mass_properties` (bodies from meshes).

What belongs here: what a model is and the equations it makes, evaluated at a given state;
not how an analysis moves through states (:mod:`mbd3d.analyses`), nor files
(:mod:`mbd3d.io`). It imports only :mod:`mbd3d.numerics`, :mod:`mbd3d.errors` and the planar
body type (:mod:`mbd3d.planar`).
"""
