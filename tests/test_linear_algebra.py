"""The layouts of the augmented and iteration matrices (dense, banded, SuperLU, and the
range-space solve through ``Cq M^-1 Cq^T``) solve the same equations: checked by the residual
of the equations themselves and against each other."""

import warnings

import numpy as np
import pytest

import mbd3d as mb
from mbd3d.model import constraints
from mbd3d.numerics import linalg, patterns
from mbd3d.model.equations import generalized_forces, mass_matrix
from mbd3d.mechanisms import pendulum_chain, spatial_chain


def _build(factory, n_links, layout, monkeypatch):
    """The chain with its linear algebra forced to ``layout``."""
    with monkeypatch.context() as patch:
        if layout == "sparse":
            patch.setattr(patterns, "BANDED_WORK_LIMIT", -1)
        if layout == "banded":
            patch.setattr(patterns, "RANGE_SPACE_WORK_LIMIT", -1)
        # masses and lengths other than 1, so that no scaling by them can be left out unseen
        model = factory(n_links, sparse=layout != "dense", link_mass=2.7, link_length=0.8)
    assert model._augmented_pattern.layout == layout
    return model


@pytest.mark.parametrize("factory, n_links", [(pendulum_chain, 30), (spatial_chain, 12)])
def test_every_layout_solves_the_augmented_equations(factory, n_links, monkeypatch):
    rng = np.random.default_rng(7)
    models = {layout: _build(factory, n_links, layout, monkeypatch)
              for layout in ("dense", "banded", "sparse", "range")}
    model = models["dense"]
    q = mb.solve_position(model, model.q0 + 0.05 * rng.normal(size=model.n_coordinates))
    qd = mb.solve_velocity(model, q, qd_guess=rng.normal(size=model.n_coordinates))
    fr = constraints.frames(model, q, qd)
    M = mass_matrix(model, fr)
    M = M.toarray() if hasattr(M, "toarray") else M
    Cq = constraints.jacobian(model, 0.0, q, fr, sparse=False)
    Qe = generalized_forces(model, 0.0, fr)
    Qd = constraints.acceleration_rhs(model, 0.0, q, qd, fr)
    solutions = {}
    for layout, each in models.items():
        qdd, lam = mb.forward_accelerations(each, 0.0, q, qd)
        scale = np.abs(Qe).max() + np.abs(M @ qdd).max()
        assert np.abs(M @ qdd + Cq.T @ lam - Qe).max() < 1e-12 * scale, layout
        assert np.abs(Cq @ qdd - Qd).max() < 1e-12 * (np.abs(Qd).max() + 1.0), layout
        solutions[layout] = np.concatenate([qdd, lam])
    for layout in ("banded", "sparse", "range"):
        np.testing.assert_allclose(solutions[layout], solutions["dense"], rtol=0,
                                   atol=1e-10 * np.abs(solutions["dense"]).max())
    # the factors kept for several right-hand sides (the projections of forward dynamics)
    blocks = model.body_type.mass_blocks(fr, model.mass, model.inertia)
    _, jac_data, _ = constraints.evaluate(model, 0.0, fr)
    rhs = rng.normal(size=(2, model.n_coordinates + model.n_constraints))
    K = linalg.augmented_matrix(M, Cq)
    for layout, each in models.items():
        factors = linalg.factor_model_augmented(each, blocks, jac_data)
        for b in rhs:
            np.testing.assert_allclose(K @ factors.solve(b), b, rtol=0,
                                       atol=1e-10 * np.abs(b).max(), err_msg=layout)
            # and solved in one call, as a Python right-hand side does
            once = linalg.solve_model_augmented(each, blocks, jac_data, b)
            np.testing.assert_allclose(K @ once, b, rtol=0, atol=1e-10 * np.abs(b).max(),
                                       err_msg=layout)


def test_banded_factors_give_the_determinant_and_refuse_singular_matrices():
    rng = np.random.default_rng(3)
    size, kl, ku = 40, 3, 2
    A = np.zeros((size, size))
    for offset in range(-kl, ku + 1):
        A += np.diag(rng.normal(size=size - abs(offset)), offset)
    ab = np.zeros((2 * kl + ku + 1, size), order="F")
    for i, j in zip(*np.nonzero(A)):
        ab[kl + ku + i - j, j] = A[i, j]
    lu = linalg.BandedFactorization(ab.copy(order="F"), kl, ku)
    b = rng.normal(size=size)
    np.testing.assert_allclose(A @ lu.solve(b), b, rtol=0, atol=1e-10)
    np.testing.assert_allclose(A.T @ lu.solve(b, transpose=True), b, rtol=0, atol=1e-10)
    assert lu.log_abs_determinant == pytest.approx(np.linalg.slogdet(A)[1], rel=1e-12)
    ab[kl + ku, :] = 0.0  # a zero diagonal in a lower triangular band...
    ab[kl + ku + 1:, :] = 0.0
    ab[:kl + ku, :] = 0.0
    ab[kl + ku, 5] = 1.0
    with pytest.raises(linalg.SingularMatrix):
        linalg.BandedFactorization(ab, kl, ku)
    # a zero diagonal whose only pivots lie on the band's lowest row (blocks of a cyclic
    # permutation): the compiled factorization must search the whole band below
    from mbd3d.numerics.compiled.dense import band_factor, band_solve_into

    size, kl, ku = 30, 2, 2
    A = np.kron(np.eye(size // 3), np.array([[0.0, 2.0, 0.0], [0.0, 0.0, 3.0], [4.0, 0.0, 0.0]]))
    rows = 2 * kl + ku + 1
    flat = np.zeros(rows * size)
    for i, j in zip(*np.nonzero(A)):
        flat[j * rows + kl + ku + i - j] = A[i, j]
    piv, regular = band_factor(flat, size, kl, ku, 1e-12)
    assert regular
    x = b.copy()[:size]
    band_solve_into(flat, size, kl, ku, piv, x)
    np.testing.assert_allclose(A @ x, b[:size], rtol=0, atol=1e-12)


@pytest.mark.parametrize("across", ["spring", "contact group"])
def test_a_force_across_the_chain_gives_the_same_motion(across, monkeypatch):
    """A spring-damper from the first link of a 25-link chain to the last closes a loop: the
    iteration matrix's ordering folds the chain about it and its band holds the spring's
    tangent. A contact group's pairs change as its bodies move, so the band cannot be sized
    for them: two pressed spheres on the first and last links put their tangent far outside
    it, and the matrix goes to SuperLU while they press. Either way the motion equals the
    dense run's."""
    from mbd3d.joints import Revolute

    def chain(sparse):
        b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81) if across == "spring" else (0.0, 0.0))
        previous = first = b.ground
        for k in range(25):
            body = b.add_body(f"link{k + 1}", mass=1.0, inertia=1 / 12,
                              position=(k + 0.5, 0.0))
            b.add(Revolute(f"pin{k + 1}", previous, body,
                              point_i=(0.0, 0.0) if k == 0 else (0.5, 0.0),
                              point_j=(-0.5, 0.0)))
            previous = body
            first = first if k else body
        if across == "spring":
            b.add(mb.SpringDamper("tie", first, previous, point_i=(0.0, 0.0),
                                  point_j=(0.0, 0.0), stiffness=50.0, damping=2.0,
                                  free_length=20.0))
        else:  # overlapping by 1 cm in the drawing, softly: they part over several steps
            b.add(mb.ContactGroup("touch", [mb.Sphere(first, 0.1, at=(12.0, 3.0)),
                                            mb.Sphere(previous, 0.1, at=(12.0, 3.19))],
                                  law=mb.LinearContact(stiffness=5.0, damping=0.05)))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", mb.ContactWarning)
            return b.build(sparse=sparse)

    outcomes = []
    add_to_band = patterns._FixedPattern._add_to_band
    monkeypatch.setattr(patterns._FixedPattern, "_add_to_band",
                        lambda self, ab, extra: outcomes.append(add_to_band(self, ab, extra))
                        or outcomes[-1])
    runs = [mb.forward_dynamics(chain(sparse), np.linspace(0.0, 0.05, 6),
                                method="generalized-alpha", step=5e-3)
            for sparse in (False, True)]
    pattern = runs[1].model._penalty_pattern
    assert pattern.layout == "banded"
    if across == "spring":  # in the band, by the compiled tangent: no SuperLU
        assert not outcomes and pattern.kl < 3 * 25 // 2
    else:
        # the spheres are pushed apart at once: the steps while they press go to SuperLU
        assert False in outcomes and runs[0].contacts().normal_force[0, 0] > 0.01
    np.testing.assert_allclose(runs[1].q, runs[0].q, rtol=0, atol=1e-10)
    np.testing.assert_allclose(runs[1].lam, runs[0].lam, rtol=0,
                               atol=1e-8 * np.abs(runs[0].lam).max())


def _band_storage(S: np.ndarray, k: int) -> np.ndarray:
    """The lower band storage of mbd3d.numerics.compiled.range_space: ``S[i, j]`` at
    ``j (k+1) + i-j``."""
    m = S.shape[0]
    band = np.zeros((k + 1) * m)
    for j in range(m):
        for i in range(j, min(m, j + k + 1)):
            band[j * (k + 1) + i - j] = S[i, j]
    return band


def test_band_cholesky_solves_and_refuses_dependent_rows():
    """The banded Cholesky of Cq M^-1 Cq^T against NumPy's, and its local pivot test: a row
    that is a combination of the rows before it is refused, however small or large the
    matrix's other entries."""
    from mbd3d.numerics.compiled.range_space import band_cholesky, band_cholesky_solve

    rng = np.random.default_rng(11)
    m, k = 30, 3
    B = np.zeros((m, m + k))  # rows of two neighbouring entries: S = B B^T has bandwidth 1
    for i in range(m):
        B[i, i:i + 2] = rng.normal(size=2)
    S = B @ B.T
    band = _band_storage(S, k)
    assert band_cholesky(band, m, k, np.diag(S).copy(), 1e-12)
    b = rng.normal(size=m)
    x = b.copy()
    band_cholesky_solve(band, m, k, x)
    np.testing.assert_allclose(x, np.linalg.solve(S, b), rtol=1e-10)
    L = np.linalg.cholesky(S)
    np.testing.assert_allclose(band[::k + 1], np.diag(L), rtol=1e-12)

    # row 20 = row 19 (times 3): dependent; rows far away scaled by 1e8 do not hide it, nor
    # make the rest look singular
    B[20] = 3.0 * B[19]
    B[:5] *= 1e8
    S = B @ B.T
    assert not band_cholesky(_band_storage(S, k), m, k, np.diag(S).copy(), 1e-12)
    B[20, 21] += 1e-3  # independent again (by 1e-3 of its size; S's bandwidth now 2)
    S = B @ B.T
    assert band_cholesky(_band_storage(S, k), m, k, np.diag(S).copy(), 1e-12)
    # the test is relative to the row's own size: at any scale, a row 1e-7 of its size out
    # of the span of the row before (squared sine 1e-14 < 1e-12) is dependent, 1e-5 is not
    for scale in (1e-4, 1e4):
        for offset, regular in ((1e-7, False), (1e-5, True)):
            C = np.zeros((m, m + k))
            for i in range(m):
                C[i, i:i + 2] = rng.normal(size=2)
            C[20] = C[19]
            C[20, 21] += offset * np.linalg.norm(C[19])
            S = (scale * C) @ (scale * C).T
            assert band_cholesky(_band_storage(S, k), m, k, np.diag(S).copy(), 1e-12) == regular


def test_dense_pivot_test_is_relative_to_the_largest_pivot():
    from mbd3d.numerics.compiled.dense import lu_factor

    for scale in (1e-6, 1e6):
        for ratio, regular in ((1e-13, False), (1e-11, True)):
            A = np.diag([scale, 2.0 * scale, ratio * scale])
            assert lu_factor(A.copy(), 1e-12)[1] == regular


def test_a_long_chain_is_not_singular_for_its_length():
    """The range-space solve's pivot test compares each pivot with its own row's diagonal:
    a 3000-link spatial chain at rest (3 km long) is as regular as a 3-link one, and its
    accelerations satisfy the equations of motion."""
    model = spatial_chain(3000)
    assert model._augmented_pattern.layout == "range"
    q = model.q0
    qd = np.zeros(model.n_coordinates)
    qdd, lam = mb.forward_accelerations(model, 0.0, q, qd)
    fr = constraints.frames(model, q, qd)
    M = mass_matrix(model, fr)
    Cq = constraints.jacobian(model, 0.0, q, fr, sparse=True)
    Qe = generalized_forces(model, 0.0, fr)
    assert np.abs(M @ qdd + Cq.T @ lam - Qe).max() < 1e-10 * np.abs(Cq.T @ lam).max()
    assert np.abs(Cq @ qdd - constraints.acceleration_rhs(model, 0.0, q, qd, fr)).max() < 1e-10
    # released at rest, the chain would fall freely but for its pin, whose pull decays
    # geometrically along the chain: the far links start falling at g
    assert qdd[model.n_coordinates - 6 + 2] == pytest.approx(-9.81, rel=1e-9)


def test_generalized_alpha_steps_a_long_chain():
    """Generalized-alpha's iteration matrix ``beta' M + Cq^T p Cq`` has pivots that span the
    penalty ratio times the masses' spread, more with every link: its test is each pivot
    against its own column, so a 1000-link spatial chain (refused by a test against the
    largest pivot) steps; released at rest, its far link falls at g, which the method
    integrates exactly (a constant acceleration)."""
    model = spatial_chain(1000)
    assert model._penalty_pattern.layout == "banded"
    res = mb.forward_dynamics(model, [0.0, 0.001, 0.002], method="generalized-alpha",
                              step=1e-3)
    fall = res.q[:, -4] - res.q[0, -4]
    np.testing.assert_allclose(fall, -9.81 * res.t ** 2 / 2, rtol=1e-9, atol=0)


def test_springs_inside_the_band_are_factored_in_band_storage(monkeypatch):
    """Torsion springs at every pin of a chain give generalized-alpha a force tangent inside
    the band of the iteration matrix: it is factored in band storage by the compiled Newton
    iteration (Python's SuperLU is never called), and the motion equals the dense run's."""
    from mbd3d.joints import Revolute
    from mbd3d.numerics.compiled import callbacks

    def chain(sparse):
        b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81))
        previous = b.ground
        for k in range(25):
            body = b.add_body(f"link{k + 1}", mass=1.0, inertia=1 / 12,
                              position=(k + 0.5, 0.0))
            b.add(Revolute(f"pin{k + 1}", previous, body,
                           point_i=(0.0, 0.0) if k == 0 else (0.5, 0.0), point_j=(-0.5, 0.0)))
            b.add(mb.RotationalSpringDamper(f"torsion{k + 1}", body_i=previous, body_j=body,
                                            stiffness=200.0, damping=1.0))
            previous = body
        return b.build(sparse=sparse)

    called = []
    factor = callbacks.factor_penalty_and_solve
    monkeypatch.setattr(callbacks, "factor_penalty_and_solve",
                        lambda *args: called.append(1) or factor(*args))
    runs = [mb.forward_dynamics(chain(sparse), np.linspace(0.0, 0.05, 6),
                                method="generalized-alpha", step=5e-3)
            for sparse in (False, True)]
    assert runs[1].model._penalty_pattern.layout == "banded" and not called
    # the same matrix, tangent included, takes the same iterations
    assert runs[1].stats["newton_iterations"] == runs[0].stats["newton_iterations"]
    np.testing.assert_allclose(runs[1].q, runs[0].q, rtol=0, atol=1e-10)
    np.testing.assert_allclose(runs[1].lam, runs[0].lam, rtol=0,
                               atol=1e-8 * np.abs(runs[0].lam).max())
