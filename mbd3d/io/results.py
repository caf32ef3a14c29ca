"""One results object for every analysis: time histories, named access, reactions, export.

``Results`` holds ``t``, ``q``, ``qd``, ``qdd`` and, after inverse or forward dynamics, the
multipliers ``lam``. Everything else (body poses, point trajectories, joint reactions, driver
efforts, energies, residuals) is derived from them on request, through the same body kinematics
and constraint primitives the solvers use.

Sign conventions. With ``M qdd + Cq^T lam = Qe`` the constraint forces are ``-Cq^T lam``. The
reaction of a joint *on a body* is the force [N] and moment [N m] the joint exerts on that body,
the moment taken about the joint's point on that body. A driver's effort is the generalized force
it applies in the direction of its coordinate: ``-lam`` (a torque [N m] for a rotation driver, a
force [N] for a translation driver).
"""

from __future__ import annotations

import dataclasses
import os
from typing import Any, BinaryIO, Sequence

import numpy as np

from mbd3d.io import exports, history, results_file
from mbd3d.io.body_views import BodyHistory, PointHistory
from mbd3d.io.exports import format_table
from mbd3d.io.joint_views import JointHistory, MeshForce, Reaction
from mbd3d.model import constraints
from mbd3d.model.body import Body
from mbd3d.model.contacts import ContactStates
from mbd3d.model.primitives import evaluate_rows
from mbd3d.errors import MBDError, ModelError
from mbd3d.numerics.rotations import to_quaternion

__all__ = ["Results", "read_results", "BodyHistory", "PointHistory", "Reaction", "MeshForce",
           "JointHistory", "format_table"]


class Results:
    """Time histories of one analysis.

    Attributes
    ----------
    model : Model
    analysis : str
        "kinematic analysis", "inverse dynamics" or "forward dynamics".
    t : ndarray (k,)
        Times [s].
    q, qd, qdd : ndarray (k, n)
        Coordinates and their first and second time derivatives.
    lam : ndarray (k, m) or None
        Lagrange multipliers (dynamics only).
    status : str
        "complete", "failed" or "interrupted".
    message : str
        Why, when not complete.
    stats : dict
        Solver statistics (steps, right-hand side evaluations, projections, wall time [s]).
    charts : ndarray (k, n_bodies + 1, 3, 3) or None
        Spatial models: the reference rotations the coordinates of each time point are relative
        to. Use ``body(name).rotation`` or ``.quaternion`` for orientations, never raw ``q``.
    model_t : ndarray (k,)
        Times [s] at which the model's drivers and forces are evaluated for derived quantities
        (residuals, reactions): ``t``, except in a vibration mode's animation, whose time axis
        is the vibration's while the mechanism stays at the equilibrium's time.
    turns : ndarray (k, n_bodies + 1, 4) or None
        Spatial models: the charts as quaternions with signs that follow the motion, where
        the analysis tracked them.
    contact_forces : ndarray (k, contact rows) or None
        The normal forces [N; a turning stop's: N m] of the contact rows held closed as
        constraints (rigid contacts at rest), where a run held any.
    contact_friction : ndarray (k, contact rows, 3) or None
        The friction [N] on the second shape of those rows (rigid contacts at rest with a
        friction coefficient), global axes, where a run held any.
    contact_dissipation : ndarray (k, contact rows) or None
        The energy [J] each compliant contact row has dissipated since the start (its
        damper, its friction; :mod:`mbd3d.analyses.dissipation`), where forward dynamics ran
        a model with contacts.
    """

    def __init__(self, model, analysis: str, t: np.ndarray, q: np.ndarray, qd: np.ndarray,
                 qdd: np.ndarray, lam: np.ndarray | None = None, *, status: str = "complete",
                 message: str = "", stats: dict | None = None, charts: np.ndarray | None = None,
                 turns: np.ndarray | None = None,
                 model_t: np.ndarray | None = None, contact_forces: np.ndarray | None = None,
                 contact_dissipation: np.ndarray | None = None,
                 contact_friction: np.ndarray | None = None):
        self.model = model
        self.analysis = analysis
        self.t = np.asarray(t, dtype=float)
        self.model_t = self.t if model_t is None else np.asarray(model_t, dtype=float)
        self.q, self.qd, self.qdd = (np.asarray(a, dtype=float) for a in (q, qd, qdd))
        self.lam = None if lam is None else np.asarray(lam, dtype=float)
        self.status = status
        self.message = message
        self.stats = dict(stats or {})
        self.charts = charts
        self.turns = turns
        self.contact_forces = contact_forces
        self.contact_friction = contact_friction
        self.contact_dissipation = contact_dissipation
        self._residuals: tuple[np.ndarray, np.ndarray] | None = None
        self._energies: tuple[np.ndarray, np.ndarray] | None = None

    def __len__(self) -> int:
        return len(self.t)

    def __repr__(self) -> str:
        span = f"t = {self.t[0]:g}..{self.t[-1]:g} s" if len(self.t) else "no time points"
        return (f"Results({self.analysis} of '{self.model.name}': {len(self.t)} time points, "
                f"{span}, {self.status})")

    def subset(self, start: int, stop: int | None = None) -> "Results":
        """The time points ``start <= k < stop`` as results of their own (views, not copies).

        Parameters
        ----------
        start, stop : int
            Time point indices (``stop`` None: to the end).
        """
        sl = slice(start, stop)
        return Results(self.model, self.analysis, self.t[sl], self.q[sl], self.qd[sl],
                       self.qdd[sl], None if self.lam is None else self.lam[sl],
                       status=self.status, message=self.message, stats=self.stats,
                       charts=None if self.charts is None else self.charts[sl],
                       turns=None if self.turns is None else self.turns[sl],
                       model_t=self.model_t[sl],
                       contact_forces=None if self.contact_forces is None
                       else self.contact_forces[sl],
                       contact_dissipation=None if self.contact_dissipation is None
                       else self.contact_dissipation[sl],
                       contact_friction=None if self.contact_friction is None
                       else self.contact_friction[sl])

    # -- named access ----------------------------------------------------------------------------
    def _require_lam(self) -> np.ndarray:
        if self.lam is None:
            raise MBDError(f"{self.analysis} results carry no multipliers; run "
                           "mbd3d.inverse_dynamics or mbd3d.forward_dynamics for reactions and "
                           "driver efforts")
        return self.lam

    def _state(self, k: int) -> tuple[np.ndarray, np.ndarray | None]:
        """Coordinates of time point ``k`` and the charts they are relative to."""
        return self.q[k], None if self.charts is None else self.charts[k]

    def _body_charts(self, body: Body) -> np.ndarray | None:
        """The reference rotations of one body over all times (k, 3, 3), or None."""
        if self.charts is None:
            return None
        return self.charts[:, self.model.padded_index(body)]

    def _body_frames(self, body: Body):
        """Frames of one body over all times (k rows) and the matching coordinate arrays."""
        model = self.model
        sl = model.coordinates_of(body)
        fr = model.body_type.frames(self.q[:, sl], self.qd[:, sl], self._body_charts(body))
        return fr, self.qdd[:, sl]

    def _body(self, body: str | Body) -> Body:
        if isinstance(body, Body):
            return body
        if body == "ground":
            return self.model.ground
        return self.model.body(body)

    def body(self, name: str) -> BodyHistory:
        """Motion of body ``name``: centre of mass, orientation, angular velocity and
        acceleration.

        Parameters
        ----------
        name : str
            A body of the model.
        """
        b = self.model.body(name)
        bt = self.model.body_type
        fr, qdd = self._body_frames(b)
        idx = np.arange(len(self.t))
        d = self.model.dim
        sl = self.model.coordinates_of(b)
        turning = None
        if self.turns is not None:
            # the chart's tracked quaternion times that of g, (1, g) / sqrt(1 + g.g)
            g = self.q[:, sl.start + 3:sl.start + 6]
            local = (np.column_stack([np.ones(len(g)), g])
                     / np.sqrt(1.0 + np.sum(g * g, axis=1))[:, None])
            import quaternion  # noqa: PLC0415  (numpy-quaternion; imported when asked for)
            turning = quaternion.as_float_array(
                quaternion.as_quat_array(self.turns[:, self.model.padded_index(b)])
                * quaternion.as_quat_array(local))
        return BodyHistory(name, fr.R.copy(), fr.Rd.copy(), qdd[:, :d].copy(), fr.A,
                           bt.angular_velocity(fr, idx).copy(),
                           bt.angular_acceleration(fr, idx, qdd),
                           self.q[:, sl.start + 2].copy() if d == 2 else None, turning)

    def poses(self) -> tuple[np.ndarray, np.ndarray]:
        """Every body's pose at every time, as a 3D pose (what a viewer draws).

        Returns
        -------
        position : ndarray (k, n_bodies, 3)
            Centres of mass [m], global axes; planar bodies lie in the plane z = 0.
        quaternion : ndarray (k, n_bodies, 4)
            Orientations as unit quaternions ``(w, x, y, z)``; planar bodies turn about z.
        """
        model = self.model
        k, nb, nc, d = len(self.t), model.n_bodies, model.n_coords_per_body, model.dim
        Q = self.q.reshape(k, nb, nc)
        position = np.zeros((k, nb, 3))
        position[:, :, :d] = Q[:, :, :d]
        if d == 2:
            half = 0.5 * Q[:, :, 2]
            quaternion = np.zeros((k, nb, 4))
            quaternion[:, :, 0], quaternion[:, :, 3] = np.cos(half), np.sin(half)
            return position, quaternion
        charts = None if self.charts is None else self.charts[:, :nb].reshape(k * nb, 3, 3)
        A = model.body_type.frames(Q.reshape(k * nb, nc), None, charts).A
        return position, to_quaternion(A).reshape(k, nb, 4)

    def _global_point(self, body: Body, u: np.ndarray, vector: bool = False) -> np.ndarray:
        """(k, dim) global positions [m] of the body-frame point ``u`` of ``body`` (the
        ground's are global), or of the body vector ``u`` with ``vector``."""
        u = np.asarray(u, dtype=float)
        if body.is_ground:
            return np.tile(u, (len(self.t), 1))
        history = self.body(body.name)
        turned = np.einsum("kab,b->ka", history.rotation, u)
        return turned if vector else history.position + turned

    def point(self, body: str, point: Sequence[float]) -> PointHistory:
        """Trajectory of the point ``point`` [m] (body frame) of body ``body``: its global
        ``.position`` [m], ``.velocity`` [m/s] and ``.acceleration`` [m/s^2]; indexing the
        history indexes the positions.

        Parameters
        ----------
        body : str
            A body of the model.
        point : (dim,) array_like
            The point in the body's frame [m].
        """
        b = self.model.body(body)
        u = np.asarray(point, dtype=float).reshape(-1)
        if u.size != self.model.dim or not np.all(np.isfinite(u)):
            raise ModelError(f"point of body '{body}' must be {self.model.dim} finite numbers, "
                             f"got {point!r}")
        bt = self.model.body_type
        fr, qdd = self._body_frames(b)
        k = len(self.t)
        idx = np.arange(k)
        U = np.broadcast_to(u, (k, u.size))
        acc = (np.einsum("kdn,kn->kd", bt.point_jacobian(fr, idx, U), qdd)
               + bt.point_acceleration_term(fr, idx, U))
        return PointHistory(bt.point(fr, idx, U), bt.point_velocity(fr, idx, U), acc)

    def joint(self, name: str) -> JointHistory:
        """Multipliers, reactions and efforts of joint or driver ``name``.

        Parameters
        ----------
        name : str
            A joint or driver of the model.
        """
        return JointHistory(self, name)

    driver = joint

    @property
    def efforts(self) -> dict[str, np.ndarray]:
        """Effort of every driver, by name."""
        return {e.name: self.joint(e.name).effort for e in self.model.joints if e.is_driver}

    def friction(self, name: str) -> np.ndarray:
        """Friction of :class:`~mbd3d.JointFriction` ``name`` on its joint's body j, (k,): a
        torque [N m] about a revolute's axis, a force [N] along a prismatic joint's axis (the
        opposite acts on body i), from the results' multipliers.

        Parameters
        ----------
        name : str
            A :class:`~mbd3d.JointFriction` of the model.
        """
        group = self.model.friction
        if group is None or name not in group.names:
            known = group.names if group is not None else []
            raise ModelError(f"'{name}' is not a joint friction of '{self.model.name}' "
                             f"(its frictions: {known or 'none'})")
        lam = self._require_lam()
        index = group.names.index(name)
        Q = np.zeros((self.model.n_bodies + 1, self.model.n_coords_per_body))
        out = np.empty(len(self.t))
        for k in range(len(self.t)):
            q, chart = self._state(k)
            fr = constraints.frames(self.model, q, self.qd[k], chart)
            out[k] = group.apply(self.model, fr, lam[k], Q)[index]
        return out

    def contacts(self) -> ContactStates:
        """Every contact and joint stop at every time point: gap, gap rate, normal and
        friction force, point and normal, one column per contact row (a capsule's end, a
        box's corner), each array with a leading time axis (k, r, ...); see
        :class:`mbd3d.ContactStates`. A model without contacts is refused. A rigid contact
        held at rest carries the force that holds it, and its friction."""
        states = history.contact_history(self.model, self.q, self.qd, self.charts)
        if self.contact_forces is not None:
            states.normal_force[...] += self.contact_forces
        if self.contact_friction is not None:
            states.friction_force[...] += self.contact_friction
        if self.contact_dissipation is not None:
            states = dataclasses.replace(states, dissipated_energy=self.contact_dissipation)
        return states

    def _reaction(self, name: str, on: Any, frame: str) -> Reaction:
        model = self.model
        element = model.joint(name)
        lam = self._require_lam()
        body = element.body_j if on is None else self._body(on)
        if body is not element.body_i and body is not element.body_j:
            raise ModelError(f"joint '{name}' connects '{element.body_i.name}' and "
                             f"'{element.body_j.name}'; it exerts no reaction on '{body.name}'")
        if frame not in ("global", "joint"):
            raise ModelError(f"frame must be 'global' or 'joint', got {frame!r}")
        bt, nc, k = model.body_type, model.n_coords_per_body, len(self.t)
        # Evaluate the joint's primitives for all times at once: rows 2t and 2t+1 of a stacked
        # coordinate array hold bodies i and j at time t (zeros for the ground).
        Q = np.zeros((2 * k, nc))
        charts = None if self.charts is None else np.tile(np.eye(3), (2 * k, 1, 1))
        for side, b in enumerate((element.body_i, element.body_j)):
            if not b.is_ground:
                Q[side::2] = self.q[:, model.coordinates_of(b)]
                if charts is not None:
                    charts[side::2] = self._body_charts(b)
        fr = bt.frames(Q, charts=charts)
        # the joint's rows read body i from row 2t and body j from row 2t + 1 at time t
        body_map = np.full(model.n_bodies + 1, -1, dtype=np.int64)
        body_map[model.padded_index(element.body_i)] = 0
        body_map[model.padded_index(element.body_j)] = 1
        n_motions = len(model.rotation_motions)
        table = (model.row_table.subset(np.array(model._instances_of[name]))
                 .on_bodies(body_map).repeated(k, 2, n_motions))
        phi = (np.concatenate([constraints.motion_phases(model, tk) for tk in self.model_t])
               if n_motions else np.zeros((0, 3)))
        J = evaluate_rows(table, fr, phi, value=False)[1]  # (k * r, 2, nc)
        rows = model.rows_of(name)
        # constraint force on this body, -Cq^T lam, from the side of each row that is this
        # body (a primitive may take the joint's bodies in either order)
        target = body_map[model.padded_index(body)]
        bi, bj = table.row_bodies()
        J_body = (J[:, 0] * (bi % 2 == target)[:, None] + J[:, 1] * (bj % 2 == target)[:, None])
        generalized = -np.einsum("krn,kr->kn", J_body.reshape(k, len(rows), nc), lam[:, rows])
        side = 0 if body is element.body_i else 1
        idx = np.arange(k) * 2 + side
        force, moment_cm = bt.wrench(fr, idx, generalized)
        point_i, point_j, axes = model.reaction_frame(name)
        u = np.broadcast_to(point_i if side == 0 else point_j, (k, model.dim))
        arm = bt.point(fr, idx, u) - fr.Q[idx, :model.dim]
        moment = moment_cm - bt.cross(arm, force)
        if frame == "joint":
            A_axes = np.einsum("kab,bc->kac", fr.A[np.arange(k) * 2], axes)
            force = np.einsum("kab,ka->kb", A_axes, force)
            if model.dim == 3:
                moment = np.einsum("kab,ka->kb", A_axes, moment)
        return Reaction(body.name, frame, force, moment)

    # -- checks ----------------------------------------------------------------------------------
    def _compute_residuals(self) -> tuple[np.ndarray, np.ndarray]:
        if self._residuals is None:
            self._residuals = history.residuals(self.model, self.model_t, self.q, self.qd,
                                                 self.charts)
        return self._residuals

    def _compute_energies(self) -> tuple[np.ndarray, np.ndarray]:
        if self._energies is None:
            self._energies = history.energies(self.model, self.q, self.qd, self.charts)
        return self._energies

    @property
    def position_residual(self) -> np.ndarray:
        """``max |C|`` at every time point [m or rad]."""
        return self._compute_residuals()[0]

    @property
    def velocity_residual(self) -> np.ndarray:
        """``max |Cq qd + Ct|`` at every time point [m/s or rad/s]."""
        return self._compute_residuals()[1]

    @property
    def reactions_unique(self) -> bool:
        """False when the constraint rows were dependent at some time point (redundant
        constraints, a singular position): the multipliers there, hence the reactions and
        efforts, are one of many that balance the mechanism (the minimum-norm one).
        ``stats["singular_outputs"]`` lists those times [s]."""
        return not self.stats.get("singular_outputs")

    @property
    def singular_passages(self) -> list:
        """Singular positions the motion passed (generalized-alpha only; the explicit methods
        stop at one): a list of :class:`mbd3d.analyses.passages.SingularPassage`, each with the
        ``time`` [s] and the ``joints`` whose rows (nearly) depend on each other there."""
        return list(self.stats.get("singular_passages", []))

    @property
    def kinetic_energy(self) -> np.ndarray:
        """Kinetic energy [J] at every time point."""
        return self._compute_energies()[0]

    @property
    def potential_energy(self) -> np.ndarray:
        """Potential energy of gravity (zero at the global origin) and springs [J]."""
        return self._compute_energies()[1]

    def energy_balance(self) -> dict[str, np.ndarray]:
        """The mechanical energy [J] at every time point and where the rest went, as named
        arrays: ``kinetic``; ``potential`` (gravity, springs, the contacts' springs);
        ``dissipated`` by the compliant contacts and joint stops (their dampers and friction,
        all rows); ``lost_in_impacts`` at the rigid contacts (``stats["impacts"]``, and the
        bounces no longer made where they came to rest, ``stats["rests"]``); and ``total``,
        their sum, which stays at its start where nothing else does work (drivers,
        actuators, dampers and joint friction are not in it): to the tolerance with the
        explicit methods; with generalized-alpha to its second order, less what its own
        numerical damping takes (``rho_inf`` < 1).
        """
        kinetic, potential = self.kinetic_energy, self.potential_energy
        dissipated = (np.zeros(len(self.t)) if self.contact_dissipation is None
                      else self.contact_dissipation.sum(axis=1))
        losses = sorted((r["time"], r["energy_lost"]) for kind in ("impacts", "rests")
                        for r in self.stats.get(kind, []))
        times = np.array([te for te, _ in losses])
        total = np.concatenate([[0.0], np.cumsum([e for _, e in losses])])
        # an output at an impact's time holds the state before it
        lost = total[np.searchsorted(times, self.t, side="left")]
        return {"kinetic": kinetic, "potential": potential, "dissipated": dissipated,
                "lost_in_impacts": lost, "total": kinetic + potential + dissipated + lost}

    # -- tables and files (mbd3d.io.exports) ------------------------------------------------
    def columns(self) -> dict[str, np.ndarray]:
        """All time histories as named columns with their units, the layout of :meth:`to_csv`
        and :meth:`to_pandas`.

        ``t [s]``; for every body, the centre of mass ``body.x [m]``, its velocity
        ``body.vx [m/s]`` and acceleration ``body.ax [m/s^2]`` (global axes), and the
        orientation: planar ``body.angle [rad]``, ``body.omega [rad/s]``, ``body.alpha
        [rad/s^2]``; spatial the unit quaternion ``body.qw`` ... ``body.qz`` (sign kept
        continuous) and the angular velocity and acceleration in global axes. With multipliers
        (dynamics), every driver's ``effort`` [N m or N] and every joint's reaction as the
        printed tables show it: the force ``joint.Fx on body [N]`` and the moment ``joint.M on
        body [N m]`` (about the joint's point) that the joint exerts on its moving body, global
        axes. The raw coordinates and multipliers are in :meth:`to_npz`.

        Examples
        --------
        >>> import numpy as np, mbd3d as mb
        >>> from mbd3d.mechanisms import slider_crank
        >>> res = mb.inverse_dynamics(slider_crank(crank_speed=1.0), np.linspace(0.0, 0.1, 3))
        >>> [c for c in res.columns() if c.startswith(("slider.x", "O.F", "motor"))]
        ['slider.x [m]', 'O.Fx on crank [N]', 'O.Fy on crank [N]', 'motor.effort [N m]']
        """
        return exports.columns(self)

    def to_csv(self, path: str | os.PathLike, overwrite: bool = True) -> str:
        """Write :meth:`columns` to a CSV file: a header of names with units, then one row per
        time point, every number to full double precision.

        Names are quoted by the csv module where they hold commas, quotes or line breaks, so
        any body or joint name reads back. The file is checked before it is written and written
        atomically (see :mod:`mbd3d.io.files`). Returns the absolute path written.

        Parameters
        ----------
        path : str or path-like
            The CSV file.
        overwrite : bool
            Replace ``path`` where it exists.
        """
        return exports.to_csv(self, path, overwrite)

    def to_pandas(self):
        """The :meth:`columns` as a ``pandas.DataFrame`` indexed by time ``t [s]``.

        Column names carry their units, as in the CSV; ``df.attrs["units"]`` maps each column
        to its unit alone. Needs pandas (``pip install "mbd3d[pandas]"``).
        """
        return exports.to_pandas(self)

    def to_npz(self, path: str | os.PathLike | BinaryIO,
               overwrite: bool = True) -> str | None:
        """Write the raw arrays (``t``, ``q``, ``qd``, ``qdd``, ``lam``, ``charts``,
        ``chart_quaternions``, ``contact_forces``, ``contact_friction``), the labels of the coordinates and rows and
        the run's statistics (JSON) to a compressed NumPy ``.npz`` file: a path (checked, then
        written atomically; its absolute path is returned) or an open binary file.
        :func:`mbd3d.read_results` reads it back against the model.

        Parameters
        ----------
        path : str, path-like or binary file
            The ``.npz`` file, or an open binary file.
        overwrite : bool
            Replace ``path`` where it exists.
        """
        return results_file.to_npz(self, path, overwrite)


def read_results(path: str | os.PathLike, model) -> Results:
    """The :class:`Results` that :meth:`Results.to_npz` wrote to ``path``, against ``model``:
    the model the run was of, or one with the same coordinates and constraint rows (the
    file's labels are checked against the model's). Reading is bounded: no pickled objects,
    and no array larger than the file's time points make it.

    Parameters
    ----------
    path : str or path-like
        An NPZ file of :meth:`Results.to_npz`.
    model : Model

    Raises
    ------
    MBDError
        Naming the file: not an NPZ file of results, a missing or malformed array, or a model
        whose coordinates or rows are not the file's (the first that differs named).
    """
    return Results(model, **results_file.read_npz(path, model))
