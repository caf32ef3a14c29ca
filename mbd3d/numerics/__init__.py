"""The numerics: linear algebra with named diagnostics (:mod:`.linalg`), rotations
(:mod:`.rotations`: Rodrigues parameters, quaternions) and the compiled core
(:mod:`.compiled`: the kernels and the integrator loop, Numba)."""
