"""The numerics, the lowest layer: linear algebra with named diagnostics (:mod:`.linalg`),
rotations (:mod:`.rotations`: Rodrigues parameters, quaternions), the validation of user
numbers (:mod:`.checks`) and the compiled core (:mod:`.compiled`: the kernels and the
integrator loop, Numba). Nothing here imports the model, the joints, input and output or the
analyses: what the compiled loop needs from them is handed to it (see
:class:`.compiled.callbacks.Run`)."""
