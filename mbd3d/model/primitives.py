"""Constraint primitives: what each one means, and the table that evaluates all of a model's.

Every constraint row of a model has the form ``C = c(q) - c0 - f(t)``: ``c`` one of the primitive
functions below, ``c0`` a constant of the row (a distance, a relative angle of the drawing) and
``f`` an optional prescribed motion (drivers). The formulas are written once, against body
vectors, in the compiled loop of :mod:`mbd3d.numerics.compiled.rows`, so the same code serves planar and
spatial bodies; the classes here describe each primitive to the model builder.

Conventions (Haug, *Computer-Aided Kinematics and Dynamics of Mechanical Systems*, 1989; verified
in Rodrigues coordinates by ``tests/test_spatial_primitives.py``): bodies ``i`` and ``j``,
``d = r_j - r_i``, ``a = A v`` body vectors, and ``gamma = -(Cq qd)_q qd`` is the
velocity-dependent right-hand side of the acceleration equation (drivers add ``f''`` separately).

Each primitive class gives its ``code`` in the compiled loop, its parameters, the rows per
instance (``rows(dim)``), whether its rows are lengths (``length_rows``: residuals are judged
relative to the model's length scale) and the body-frame vectors it needs, as
``(name, body "i" or "j", parameter)``; optionally ``planar_only`` or ``spatial_only``, and
``velocity_rows``: rows of each instance that constrain velocities only (nonholonomic, their
``c`` zero; see :class:`DiscOnPlane`). :class:`RowTable` stacks every instance of a model in
row order; one call of :func:`evaluate_rows` evaluates them all.
"""

from __future__ import annotations

import numpy as np

from mbd3d.numerics.compiled import rows as kernel

__all__ = ["PRIMITIVES", "PointCoincidence", "Dot1", "Dot2", "Distance", "Coordinate",
           "RelativeAngle", "Rotation", "Gear", "GearMesh", "DiscOnPlane", "Rack", "CamPoint", "CamFace", "RowTable",
           "evaluate_rows", "rows_along_vectors"]

#: the most body vectors and points one primitive instance reads (a spatial gear mesh's six)
MAX_VECTORS = 6

class PointCoincidence:
    """``c = r_i - r_j``: point ``u_i`` of body i coincides with point ``u_j`` of body j.

    A planar revolute joint; the point part of a spatial spherical/revolute/universal joint.
    Reaction: the force ``-lam`` acts on body i at its point and ``+lam`` on body j.
    """

    kind = "point"
    code = kernel.POINT
    #: whether the rows are lengths [m] (else dimensionless: cosines, angles [rad])
    length_rows = True
    params = ("u_i", "u_j")
    vectors = (("si", "i", "u_i"), ("sj", "j", "u_j"))

    @staticmethod
    def rows(dim: int) -> int:
        return dim


class Dot1:
    """``c = a_i . a_j``: body vectors kept perpendicular (Haug's dot-1).

    Axis alignment is written as perpendicularity, whose gradient does not vanish at the
    solution.
    """

    kind = "dot1"
    code = kernel.DOT1
    #: whether the rows are lengths [m] (else dimensionless: cosines, angles [rad])
    length_rows = False
    params = ("v_i", "v_j")
    vectors = (("ai", "i", "v_i"), ("aj", "j", "v_j"))

    @staticmethod
    def rows(dim: int) -> int:
        return 1


class Dot2:
    """``c = a_i . (r_j - r_i)``: point j stays on a plane (3D) or line (2D) of body i.

    With a motion ``f(t)`` it is a translation driver along ``a_i``.
    """

    kind = "dot2"
    code = kernel.DOT2
    #: whether the rows are lengths [m] (else dimensionless: cosines, angles [rad])
    length_rows = True
    params = ("v_i", "u_i", "u_j")
    vectors = (("ai", "i", "v_i"), ("si", "i", "u_i"), ("sj", "j", "u_j"))

    @staticmethod
    def rows(dim: int) -> int:
        return 1


class Distance:
    """``c = |r_j - r_i|``: with ``c0 = L`` a massless rigid link of length L.

    ``lam`` is then the compressive force in the link [N] (positive pushes the points apart).
    """

    kind = "distance"
    code = kernel.DISTANCE
    #: whether the rows are lengths [m] (else dimensionless: cosines, angles [rad])
    length_rows = True
    params = ("u_i", "u_j")
    vectors = (("si", "i", "u_i"), ("sj", "j", "u_j"))

    @staticmethod
    def rows(dim: int) -> int:
        return 1


class Coordinate:
    """``c = q_j[coordinate]``: one coordinate of body j (body i is the ground)."""

    kind = "coordinate"
    code = kernel.COORDINATE
    #: translation coordinates are lengths, a planar angle is not (see :meth:`row_is_length`)
    length_rows = None
    params = ("coordinate",)
    vectors = ()

    @staticmethod
    def row_is_length(params: dict, dim: int) -> bool:
        """Whether the row, of a coordinate of ``params`` in a ``dim``-dimensional model, is
        a length (a translation) rather than an angle."""
        return int(params["coordinate"]) < dim

    @staticmethod
    def rows(dim: int) -> int:
        return 1


class RelativeAngle:
    """``c = theta_j - theta_i``: rotation of body j relative to body i about the plane normal
    (planar bodies only)."""

    planar_only = True

    kind = "angle"
    code = kernel.ANGLE
    #: whether the rows are lengths [m] (else dimensionless: cosines, angles [rad])
    length_rows = False
    params = ()
    vectors = ()

    @staticmethod
    def rows(dim: int) -> int:
        return 1


class Rotation:
    """Spatial rotation driver across a hinge: ``C = f_j . (g_i cos(phi) - f_i sin(phi))``,
    ``phi = f(t)``.

    ``f_i, g_i`` span body i's plane normal to the hinge, ``f_j`` is body j's reference
    direction in that plane; with ``theta`` the angle from ``f_i`` to ``f_j`` about the hinge,
    ``C = sin(theta - phi)``: no turn counting, any number of revolutions, and ``lam`` is minus
    the driving torque about the hinge. The time dependence sits inside the row, so this class
    supplies its own ``-C_t`` and time terms of ``Qd`` from ``(f, f', f'')`` of its motion.
    With ``u = A_i (g cos(phi) - f sin(phi))`` and
    ``w = A_i (f cos(phi) + g sin(phi))``: ``-C_t = (f_j . w) phi'`` and
    ``Qd = gamma_dot1(u, f_j) + 2 phi' (f_j . (omega_i x w) + w . (omega_j x f_j))
    + (f_j . u) phi'^2 + (f_j . w) phi''``. ``u`` and ``w`` and everything derived from them
    are linear in ``f_i`` and ``g_i``, so they are combined from those two vectors' parts.
    """

    kind = "rotation"
    code = kernel.ROTATION
    #: whether the rows are lengths [m] (else dimensionless: cosines, angles [rad])
    length_rows = False
    params = ("f_i", "g_i", "f_j")
    vectors = (("fi", "i", "f_i"), ("gi", "i", "g_i"), ("fj", "j", "f_j"))
    time_dependent = True

    @staticmethod
    def rows(dim: int) -> int:
        return 1


class Gear:
    """Planar gear pair: the pitch circles of radii ``rho_i``, ``rho_j`` about points ``u_i``,
    ``u_j`` (the gear centres) roll on each other without slip.

    With ``phi`` the angle of the centre line ``d = r_j - r_i``, rolling is
    ``rho_i (theta_i - phi) + sigma rho_j (theta_j - phi) = const`` (Nikravesh, *Planar
    Multibody Dynamics*, 2008, sec. on gears; ``sigma = +1`` external mesh, ``-1`` internal:
    body j the ring). It holds whatever carries the centres (the ground or a turning arm), but
    ``phi`` has no turn count, so the row is written as ``C = kappa (d x e(psi))``, with ``e``
    the unit vector at ``psi = (rho_i theta_i + sigma rho_j theta_j - c)/D``,
    ``D = rho_i + sigma rho_j`` and ``kappa = sign(D)``: ``e`` must lie along ``d``. At the
    solution ``C_q`` is the rolling condition itself (``dC/dtheta_i = rho_i``,
    ``dC/dtheta_j = sigma rho_j``), so ``lam`` is the tangential force of the mesh [N]: the
    torque on gear i is ``-lam rho_i``. ``real = (rho_i/D, sigma rho_j/D, c/D, kappa)``. The row
    also vanishes where ``e`` points against ``d``, half a turn of ``psi`` away;
    :func:`mbd3d.model.constraints.branch_cosines` tells position analysis which is which.
    """

    kind = "gear"
    code = kernel.GEAR
    #: whether the rows are lengths [m] (else dimensionless: cosines, angles [rad])
    length_rows = True
    params = ("u_i", "u_j", "real")
    vectors = (("si", "i", "u_i"), ("sj", "j", "u_j"))
    planar_only = True

    @staticmethod
    def rows(dim: int) -> int:
        return 1


class GearMesh:
    """Spatial gear pair, spur or bevel: the gears turn about their hinges as their pitch
    circles (pitch cones) roll on each other.

    Each gear has unit vectors ``f``, ``g = h x f`` spanning its plane (``h`` its axis; slots
    0, 1 on body i and 2, 3 on body j) and a centre on its axis (``u_i``, ``u_j``); the line
    ``d = r_j - r_i`` joining the centres is fixed in whatever carries both hinges (the
    ground, an arm, a differential's cage), so each gear's angle relative to the carrier is,
    up to a constant, ``-beta`` with ``beta = atan2(d . g, d . f)``. Rolling is
    ``rho_i alpha_i + sigma rho_j alpha_j = const`` (parallel axes: both ``h`` the same way,
    ``sigma = -1`` for an internal mesh; bevel: both ``h`` pointing away from the apex,
    ``sigma = +1``). The angles are known modulo a turn, but the tooth counts ``z_i``, ``z_j``
    (coprime, ``z_i / z_j = rho_i / rho_j``) make the phase
    ``Phi = -(z_i beta_i + sigma z_j beta_j) - c`` a function of the configuration, and the
    row is ``C = size sin(Phi)``, ``size = rho_i / z_i``: at the solution
    ``dC/dalpha_i = rho_i``, ``dC/dalpha_j = sigma rho_j``, so ``lam`` is the tangential force
    of the mesh [N] as in :class:`Gear`. The row also vanishes at ``Phi = pi`` (the gears half
    a tooth ratio out of phase); :func:`mbd3d.model.constraints.branch_cosines` tells position
    analysis which is which. ``real = (z_i, sigma z_j, c, size)``.
    """

    kind = "gear_mesh"
    code = kernel.GEAR_MESH
    #: whether the rows are lengths [m] (else dimensionless: cosines, angles [rad])
    length_rows = True
    params = ("f_i", "g_i", "f_j", "g_j", "u_i", "u_j", "real")
    vectors = (("fi", "i", "f_i"), ("gi", "i", "g_i"), ("fj", "j", "f_j"), ("gj", "j", "g_j"),
               ("si", "i", "u_i"), ("sj", "j", "u_j"))

    @staticmethod
    def rows(dim: int) -> int:
        return 1


class DiscOnPlane:
    """A thin disc (body j) rolling without slipping on a fixed plane (body i, the ground):
    three rows, the first holonomic and the other two nonholonomic.

    Row 0 keeps the disc's lowest rim point on the plane, ``c = k . R_j - r |a x k|``
    (``k`` the plane's unit normal, ``a`` the disc's axis, ``c0`` the plane's offset
    ``k . P0``). Rows 1 and 2 hold the disc's material point at the contact still along the
    plane's axes ``t_1``, ``t_2 = k x t_1``: ``t . (R_j' + omega_j x w) = 0``, ``w`` the
    contact's offset from the centre. These constrain velocities only, no function of the
    positions has them as its derivative (a disc can roll to any position and heading), so
    their ``c`` is zero: position analysis and projection keep them as conditions on the
    step, velocity and acceleration analysis and the augmented equations as rows like any
    other, and the multipliers of the three rows are the contact force's normal and in-plane
    components (``-lam`` along ``k``, ``t_1``, ``t_2`` on the disc). ``real = (r,)``; body
    vectors: ``k``, ``t_1`` of the ground, the disc's axis and its three body axes (see
    :func:`mbd3d.numerics.compiled.rows._disc_on_plane`).
    """

    kind = "disc_on_plane"
    code = kernel.DISC_ON_PLANE
    #: whether the rows are lengths [m] (else dimensionless: cosines, angles [rad])
    length_rows = True
    params = ("k_i", "t_i", "a_j", "x_j", "y_j", "z_j", "real")
    vectors = (("k", "i", "k_i"), ("t", "i", "t_i"), ("a", "j", "a_j"), ("x", "j", "x_j"),
               ("y", "j", "y_j"), ("z", "j", "z_j"))
    spatial_only = True
    #: rows of each instance that constrain velocities only (nonholonomic)
    velocity_rows = (1, 2)

    @staticmethod
    def rows(dim: int) -> int:
        return 3


class Rack:
    """Planar rack (body i) and pinion (body j):
    ``c = a_i . (r_j - r_i) + rho (theta_j - theta_i)``, the pinion centre ``u_j`` advancing
    along the rack's direction ``v_i`` by ``-rho`` per radian it turns relative to the rack
    (the rack's pitch line to the right of ``v_i``). ``lam`` is the tangential force of the
    mesh [N]: the force ``-lam a_i`` on the pinion at its pitch point. ``real = (rho,)``.
    """

    kind = "rack"
    code = kernel.RACK
    #: whether the rows are lengths [m] (else dimensionless: cosines, angles [rad])
    length_rows = True
    params = ("v_i", "u_i", "u_j", "real")
    vectors = (("ai", "i", "v_i"), ("si", "i", "u_i"), ("sj", "j", "u_j"))
    planar_only = True

    @staticmethod
    def rows(dim: int) -> int:
        return 1


class CamPoint:
    """Planar disc cam (body i) and a point or roller follower (body j): the follower's point
    ``u_j`` stays on the cam's pitch curve ``r(phi)``, polar about the cam's centre ``u_i``
    with ``phi`` measured in the cam's frame: ``C = |d| - r(angle(d) - theta_i)``,
    ``d = r_j - r_i``. Its gradient in ``r_j`` is the pitch curve's outward normal
    ``u - r'(phi) w / |d|`` (``u`` along ``d``, ``w`` turned from it by 90 degrees), so the
    force on the follower is ``-lam`` times that: compressive while ``lam < 0``.
    ``real = (offset, intervals)`` of the curve in ``RowTable.curves``.
    """

    kind = "cam"
    code = kernel.CAM_POINT
    #: whether the rows are lengths [m] (else dimensionless: cosines, angles [rad])
    length_rows = True
    params = ("u_i", "u_j", "curve")
    vectors = (("si", "i", "u_i"), ("sj", "j", "u_j"))
    planar_only = True

    @staticmethod
    def rows(dim: int) -> int:
        return 1


class CamFace:
    """Planar disc cam (body i) and a flat-faced follower (body j): the face (point ``u_j``,
    unit normal ``v_j`` towards the cam) stays tangent to the cam whose support function is
    ``h(psi)``, the distance from the cam's centre ``u_i`` to its tangent with outward normal
    at ``psi`` in the cam's frame: ``C = n . (r_i - r_j) - h(theta_j - theta_i + psi_0)``,
    ``psi_0`` the angle of ``-v_j`` in body j's frame. The force on the follower is
    ``lam n``: compressive while ``lam < 0``. ``real = (offset, intervals, psi_0)``.
    """

    kind = "cam_face"
    code = kernel.CAM_FACE
    #: whether the rows are lengths [m] (else dimensionless: cosines, angles [rad])
    length_rows = True
    params = ("v_j", "u_j", "u_i", "curve", "real")
    vectors = (("nj", "j", "v_j"), ("sj", "j", "u_j"), ("si", "i", "u_i"))
    planar_only = True

    @staticmethod
    def rows(dim: int) -> int:
        return 1


#: every primitive class by its ``kind``, as the model file and the element specs name them
PRIMITIVES = {cls.kind: cls for cls in
              (PointCoincidence, Dot1, Dot2, Distance, Coordinate, RelativeAngle, Rotation, Gear,
               Rack, CamPoint, CamFace, GearMesh, DiscOnPlane)}


class RowTable:
    """Every primitive instance of a model in row order, as the arrays of the compiled loop.

    Attributes
    ----------
    code, bi, bj, first_row, coordinate, motion : ndarray (k,) of int
        Primitive code, bodies i and j (rows of the frames, the ground last), first row,
        coordinate of a :class:`Coordinate` and row of a :class:`Rotation`'s motion in
        ``phi`` (-1 for the others).
    real : ndarray (k, 4) of float
        Real-valued parameters of instances that need them inside their rows (the gear
        pair's ratios and phase, the rack's radius, a cam's curve: its offset and intervals
        in ``curves``); zero for the others.
    curves : ndarray
        The cams' periodic curves, one after the other (see
        :mod:`mbd3d.numerics.compiled.curves`).
    slots : ndarray (k, MAX_VECTORS) of int
        Rows of each instance's vectors (in the order of its class's ``vectors``) in the
        vector table ``vector_bodies`` (V,), ``vector_local`` (V, dim).
    n_rows : int
    """

    def __init__(self, code, bi, bj, first_row, slots, coordinate, motion, real, vector_bodies,
                 vector_local, n_rows: int, curves: np.ndarray | None = None):
        self.code, self.bi, self.bj, self.first_row = code, bi, bj, first_row
        self.slots, self.coordinate, self.motion, self.real = slots, coordinate, motion, real
        self.curves = np.zeros(1) if curves is None else curves
        self.vector_bodies, self.vector_local, self.n_rows = vector_bodies, vector_local, n_rows

    @classmethod
    def from_instances(cls, instances: list, dim: int) -> "RowTable":
        """``instances``: ``(primitive class, bi, bj, params, motion row)`` in row order."""
        k = len(instances)
        code, bi, bj, first_row, coordinate, motion = (np.zeros(k, dtype=np.int64)
                                                        for _ in range(6))
        slots = np.full((k, MAX_VECTORS), -1, dtype=np.int64)
        real = np.zeros((k, 4))
        bodies, local, curves = [], [], [np.zeros(1)]
        curve_start = 1
        row = 0
        for e, (prim, i, j, params, motion_row) in enumerate(instances):
            code[e], bi[e], bj[e], first_row[e], motion[e] = prim.code, i, j, row, motion_row
            coordinate[e] = int(params.get("coordinate", 0))
            if "real" in params:
                real[e, :len(params["real"])] = params["real"]
            if "curve" in params:
                # a cam's curve: its place in the table and its number of intervals
                table = np.asarray(params["curve"], dtype=float)
                real[e, 0], real[e, 1] = curve_start, (len(table) - 1) // 5
                curves.append(table)
                curve_start += len(table)
            for n, (_, side, key) in enumerate(prim.vectors):
                slots[e, n] = len(bodies)
                bodies.append(i if side == "i" else j)
                local.append(np.asarray(params[key], dtype=float))
            row += prim.rows(dim)
        return cls(code, bi, bj, first_row, slots, coordinate, motion, real,
                   np.array(bodies, dtype=np.int64), np.array(local).reshape(-1, dim), row,
                   np.concatenate(curves))

    def row_bodies(self) -> tuple[np.ndarray, np.ndarray]:
        """Bodies i and j of every row, (m,) each."""
        rows_per = np.diff(np.append(self.first_row, self.n_rows))
        return np.repeat(self.bi, rows_per), np.repeat(self.bj, rows_per)

    def subset(self, instances: np.ndarray) -> "RowTable":
        """The table of some instances only, their rows and vectors renumbered from 0."""
        rows_per = np.diff(np.append(self.first_row, self.n_rows))[instances]
        first = np.concatenate([[0], np.cumsum(rows_per)[:-1]]).astype(np.int64)
        slots = self.slots[instances]
        used = slots[slots >= 0]
        renumbered = np.full_like(slots, -1)
        renumbered[slots >= 0] = np.arange(len(used))
        return RowTable(self.code[instances], self.bi[instances], self.bj[instances], first,
                        renumbered, self.coordinate[instances], self.motion[instances],
                        self.real[instances],
                        self.vector_bodies[used], self.vector_local[used], int(rows_per.sum()),
                        self.curves)

    def on_bodies(self, body_map: np.ndarray) -> "RowTable":
        """The same rows read from other body rows: body ``b`` becomes ``body_map[b]``."""
        return RowTable(self.code, body_map[self.bi], body_map[self.bj], self.first_row,
                        self.slots, self.coordinate, self.motion, self.real,
                        body_map[self.vector_bodies],
                        self.vector_local, self.n_rows, self.curves)

    def repeated(self, copies: int, body_stride: int, motion_stride: int) -> "RowTable":
        """The table for ``copies`` states stacked one after the other: copy ``c`` reads bodies
        ``c * body_stride + b``, motions ``c * motion_stride + r`` and writes rows
        ``c * n_rows + r``."""
        offset = np.arange(copies)[:, None]
        tile = lambda a, stride: (a[None] + stride * offset).reshape(-1)  # noqa: E731
        n_vectors = len(self.vector_bodies)
        slots = np.where(self.slots[None] >= 0, self.slots[None] + n_vectors * offset[:, :, None],
                         -1).reshape(-1, MAX_VECTORS)
        return RowTable(np.tile(self.code, copies), tile(self.bi, body_stride),
                        tile(self.bj, body_stride), tile(self.first_row, self.n_rows), slots,
                        np.tile(self.coordinate, copies),
                        np.where(self.motion[None] >= 0, tile(self.motion, motion_stride)
                                 .reshape(copies, -1), -1).reshape(-1),
                        np.tile(self.real, (copies, 1)),
                        tile(self.vector_bodies, body_stride),
                        np.tile(self.vector_local, (copies, 1)), copies * self.n_rows,
                        self.curves)


def evaluate_rows(table: RowTable, fr, phi: np.ndarray, value: bool = True,
                  jacobian: bool = True, gamma: bool = False, rate: bool = False,
                  destination: np.ndarray | None = None, nnz: int | None = None):
    """``c(q)`` (m,), Jacobian values, ``gamma`` (m,) and ``-C_t`` (m,) of the table's rows at
    the frames ``fr`` (velocities needed for ``gamma``), ``None`` for the parts not asked for.

    The Jacobian values go to positions ``destination`` of an array of ``nnz`` (indexed by
    ``(2 row + side) n_coords + coordinate``, -1 for entries left out: the ground's); by
    default the full array (m, 2, n_coords) of derivatives with respect to bodies i and j.
    ``phi`` (k_motion, 3): ``(f, f', f'')`` of the motions of rotation drivers.
    """
    nc = fr.Q.shape[1]
    raw = destination is None
    if raw:
        nnz = table.n_rows * 2 * nc
        destination = np.arange(nnz)
    velocities = gamma and fr.Qd is not None
    if gamma and not velocities:
        raise ValueError("gamma needs frames with velocities")
    s, J, v, a = fr.vectors(table.vector_bodies, table.vector_local, velocities)
    C, data, G, nu = kernel.constraint_rows(
        table.code, table.bi, table.bj, table.first_row, table.slots, table.coordinate,
        table.motion, table.real, table.curves, phi, table.n_rows, fr.Q, fr.Qd if velocities else fr.Q, s, J, v, a,
        destination, nnz, value, jacobian, gamma, rate)
    if jacobian and raw:
        data = data.reshape(table.n_rows, 2, nc)
    return (C if value else None, data if jacobian else None, G if gamma else None,
            nu if rate else None)


def rows_along_vectors(table: RowTable, fr, phi: np.ndarray, change: np.ndarray) -> np.ndarray:
    """The change of every row's ``c(q)`` (m,) when the instances' body-frame vectors (the
    table's ``vector_local``) change by ``change`` (V, dim), to first order, at the frames
    ``fr``: ``sum over vectors of dc/ds . A dv``, exactly.

    Each row's Jacobian column of a body's (first) rotation coordinate is the chain rule
    ``dc/dtheta = (explicit) + sum over the body's vectors of dc/ds . ds/dtheta``, linear in
    the vectors' ``ds/dtheta`` (``J``): evaluated once with ``J`` replaced by the vectors'
    changes ``ds = A dv`` and once with ``J`` zero, the difference of the two columns (of both
    bodies, the ground's included) is the rows' change along ``dv``, through the same formulas
    that give the Jacobian (so none is written twice)."""
    s, J, v, a = fr.vectors(table.vector_bodies, table.vector_local, False)
    ds = fr.vectors(table.vector_bodies, change, False)[0]
    nc, dim = fr.Q.shape[1], s.shape[1]
    columns = []
    for along in (ds, np.zeros_like(ds)):
        J_along = np.zeros_like(J)
        J_along[:, :, 0] = along
        nnz = table.n_rows * 2 * nc
        data = kernel.constraint_rows(
            table.code, table.bi, table.bj, table.first_row, table.slots, table.coordinate,
            table.motion, table.real, table.curves, phi, table.n_rows, fr.Q, fr.Q, s, J_along,
            v, a, np.arange(nnz), nnz, False, True, False, False)[1]
        columns.append(data.reshape(table.n_rows, 2, nc)[:, :, dim].sum(axis=1))
    return columns[0] - columns[1]
