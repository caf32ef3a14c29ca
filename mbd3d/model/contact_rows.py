"""The contacts, contact groups and joint stops of a model as the rows of the compiled core
(:mod:`mbd3d.numerics.compiled.contacts`): one force group, built from the elements'
``arrays`` (and a group's ``tables``), evaluated for all rows at once."""

from __future__ import annotations

import warnings
from typing import TYPE_CHECKING

import numpy as np

from mbd3d.errors import ContactWarning, ModelError, user_stacklevel
from mbd3d.model.forces import _CompiledForces, block_triplets
from mbd3d.numerics.compiled import contact_groups as groups, contacts as kernel
from mbd3d.numerics.compiled.contact_groups import empty_shapes

if TYPE_CHECKING:
    from mbd3d.model.builder import BuildContext

__all__ = ["_Contacts"]


def _curve_table(points: np.ndarray, curves: list) -> np.ndarray:
    """The cams' curves one after another (:mod:`mbd3d.numerics.compiled.curves`), each row's
    offset and interval count written into its ``points[r, 3]`` (see
    :mod:`mbd3d.numerics.compiled.contacts`)."""
    tables, offset = [], 0
    for r, curve in enumerate(curves):
        if curve is not None:
            points[r, 3, :2] = offset, (len(curve) - 1) // 5  # count + 1 knots, 4 count
            tables.append(curve)
            offset += len(curve)
    return np.ascontiguousarray(np.concatenate(tables) if tables else np.zeros(0))


class _Contacts(_CompiledForces):
    """The contacts, joint stops and contact groups of a model as rows of the compiled core
    (a group is one row, its shapes and laws tables of their own): ``owners[r]`` is the
    element of row ``r``; where a pair was given the other way round (``swapped``) the core's
    body i is the element's second body, and its reports are turned back."""

    def __init__(self, elements: list, ctx: "BuildContext"):
        self.elements = elements
        arrays = [e.arrays(ctx) for e in elements]
        self._points = np.ascontiguousarray(np.concatenate([a[0] for a in arrays]))
        self._curves = _curve_table(self._points, [a[5] for a in arrays for _ in a[2]])
        self._values = np.ascontiguousarray(np.concatenate([a[1] for a in arrays]))
        self.owners = [e for e, a in zip(elements, arrays) for _ in a[2]]
        self.names = [f"{e.name}[{label}]" if label else e.name
                      for e, a in zip(elements, arrays) for label in a[2]]
        self._swapped = np.concatenate([np.broadcast_to(np.asarray(a[3], dtype=bool), len(a[2]))
                                        for a in arrays])
        #: per row, the mass (a stop: the moment of inertia) its law is calibrated with
        self.masses = np.array([a[4] for a in arrays for _ in a[2]], dtype=float)
        #: per row, whether it is rigid (:class:`~mbd3d.RigidImpact`: no force, impacts),
        #: and its law's restitution and rest speed (rigid rows only, else nan)
        laws = [e.law for e in self.owners]
        self.rigid = np.array([law.rigid for law in laws], dtype=bool)
        self.restitution = np.array([law.restitution if law.rigid else np.nan for law in laws])
        self.rest_speed = np.array([law.rest_speed if law.rigid else np.nan for law in laws])
        #: per row, its friction coefficient (0 at a stop) and slip velocity [m/s]
        kinds = self._values[:, 0]
        stops = (kinds >= kernel.HINGE_STOP) & (kinds <= kernel.CONE_STOP)
        self.friction = np.where(stops, 0.0, self._values[:, 7])
        self.slip_velocity = np.where(stops, np.nan, self._values[:, 8])
        #: per row, its static friction coefficient (rigid rows: their law's, else the
        #: friction), checked to hold at least what the row rubs sliding
        self.static_friction = np.array([_static(e, law, mu, stop) for e, law, mu, stop
                                         in zip(self.owners, laws, self.friction, stops)])
        #: the contacts' shapes in their bodies' frames, for drawing
        self.outlines = [o for e in elements for o in e.outlines(ctx)]
        self._group_tables(ctx, elements)
        self._rows = None
        self._check_apart(ctx)

    def _group_tables(self, ctx: "BuildContext", elements: list) -> None:
        """The contact groups' shapes and laws as one table each, the group rows pointing
        into them (see :mod:`mbd3d.numerics.compiled.contact_groups`)."""
        points, values, laws = [], [], []
        self._shape_bodies, shapes, offset = [], 0, 0
        for e in elements:
            if not e.is_group:
                continue
            r = self.owners.index(e)
            self._points[r, 3, 0], self._points[r, 2, 0] = shapes, offset
            table = e.tables(ctx)
            points.append(table[0])
            values.append(table[1])
            laws.append(table[2])
            self._shape_bodies += [shape.body for shape in e.shapes]
            shapes, offset = shapes + len(table[0]), offset + len(table[2])
        empty = empty_shapes(ctx.dim)
        self._shape_tables = tuple(np.ascontiguousarray(np.concatenate(t) if t else blank)
                                   for t, blank in zip((points, values, laws), empty[1:]))
        self.groups = np.flatnonzero(self._values[:, 0] == kernel.GROUP)

    def _pairs(self, row) -> np.ndarray:
        """The core's ``(i, j)`` body indices per row, from ``row(body)`` (a group's row:
        zeros)."""
        pairs = np.array([[0, 0] if e.is_group else [row(e.body_i), row(e.body_j)]
                          for e in self.owners], dtype=np.int64).reshape(-1, 2)
        pairs[self._swapped] = pairs[self._swapped, ::-1]
        return pairs

    def _shapes(self, row) -> tuple:
        """The groups' shape table (see :mod:`mbd3d.numerics.compiled.contact_groups`) with
        the bodies' indices from ``row(body)``."""
        bodies = np.array([row(b) for b in self._shape_bodies], dtype=np.int64)
        return (bodies, *self._shape_tables)

    def _check_apart(self, ctx: "BuildContext") -> None:
        """Shapes that overlap in the drawing are reported with the depth (a
        :class:`~mbd3d.errors.ContactWarning`): an integration starts with that force."""
        fr = ctx.body_type.frames(ctx.frames.Q, np.zeros_like(ctx.frames.Q), charts=ctx.charts)
        report = self._report(fr, (self._pairs(ctx.row), self._shapes(ctx.row)))
        # rigid shapes drawn touching overlap by the rounding of their positions
        rounding = 1e-12 * (1.0 + float(np.max(np.abs(ctx.frames.Q), initial=0.0)))
        overlap = report[:, kernel.GAP] < np.where(self.rigid, -rounding, 0.0)
        for k in np.flatnonzero(overlap):
            e = self.owners[k]
            depth, force = -report[k, kernel.GAP], report[k, kernel.NORMAL_FORCE]
            where = e.overlap_words
            what = e.what.replace(f"'{e.name}'", f"'{self.names[k]}'")  # with the corner
            force = ("a rigid contact, which forward dynamics refuses to start inside"
                     if self.rigid[k] else f"with a force of {force:.6g} {e.units[1]}")
            warnings.warn(f"{what}: {where} {depth:.6g} {e.units[0]} in the drawing, "
                          f"{force}; place the bodies apart (or at the limit) unless that is "
                          "their static penetration", ContactWarning,
                          stacklevel=user_stacklevel())

    def _report(self, fr, tables: tuple, k: int = 1) -> np.ndarray:
        """A row of the core's report per contact row, normals and friction turned back to
        the element's order of shapes; of ``k`` states stacked time-major in ``fr`` (rows ``t *
        (n_bodies + 1) + b``), the rows of state ``t`` at ``t * r ... (t + 1) * r``."""
        (bodies, shapes), r, rows = tables, len(self.owners), len(fr.Q) // k
        if k > 1:
            bodies = (bodies[None] + rows * np.arange(k)[:, None, None]).reshape(k * r, 2)
        out = np.zeros_like(fr.Q)
        report = np.zeros((k * r, kernel.REPORT_COLUMNS))
        failed = kernel.contact_forces_into(fr.A, fr.axes, fr.omega3, fr.Q, fr.Qd, bodies,
                                            np.tile(self._points, (k, 1, 1)),
                                            np.tile(self._values, (k, 1)), self._curves, out,
                                            report, np.zeros(0))
        for t in range(k if len(self.groups) and failed < 0 else 0):
            # a group's shapes move with the state: its bodies' rows in the stacked frames
            failed = groups.groups_into(fr.A, fr.axes, fr.omega3, fr.Q, fr.Qd, self._points,
                                        self._values, self._curves,
                                        (shapes[0] + rows * t, *shapes[1:]), out,
                                        report[t * r:(t + 1) * r], np.zeros(0))
        if failed >= 0:
            raise ModelError(f"{self.owners[failed % r].what}: the shapes' cores meet; the "
                             "contact normal is undefined")
        swapped = np.tile(self._swapped, k)
        for columns in (slice(kernel.FRICTION, kernel.FRICTION + 3),
                        slice(kernel.NORMAL, kernel.NORMAL + 3)):
            report[swapped, columns] *= -1.0
        return report

    def _tables(self, model) -> tuple:
        """The rows' bodies and the groups' shapes with the model's body indices."""
        if self._rows is None:
            self._rows = (self._pairs(model.padded_index), self._shapes(model.padded_index))
        return self._rows

    def _bodies(self, model) -> np.ndarray:
        return self._tables(model)[0]

    def apply(self, model, t, fr, Q):
        failed = groups.all_contact_forces_into(fr.A, fr.axes, fr.omega3, fr.Q, fr.Qd,
                                                self._bodies(model), self._points,
                                                self._values, self._curves,
                                                self._tables(model)[1], Q,
                                                np.zeros((0, kernel.REPORT_COLUMNS)),
                                                np.zeros(0))
        if failed >= 0:
            raise ModelError(f"{self.owners[failed].what}: the shapes' cores meet at t = {t:g} "
                             "s; the contact normal is undefined")

    analytic_tangent = True

    def compiled_tangent(self, model):
        return True  # the table is always compiled (mbd3d.numerics.compiled.force_tangents)

    def tangent(self, model, t, fr, velocity_weight):
        """The laws' slopes through each pair's velocity Jacobian (see
        :func:`~mbd3d.numerics.compiled.contacts.contact_tangents_into`), as COO triplets over
        the padded coordinates; rows that do not push add zeros, a group's rows its pairs
        near each other."""
        bodies, nc = self._bodies(model), model.n_coords_per_body
        blocks = np.empty((len(bodies), 2 * nc, 2 * nc))
        kernel.contact_tangents_into(fr.A, fr.axes, fr.omega3, fr.Q, fr.Qd, bodies,
                                     self._points, self._values, self._curves, velocity_weight,
                                     blocks)
        for k in self.groups:
            pairs, more = groups.group_tangents(fr.A, fr.axes, fr.omega3, fr.Q, fr.Qd, k,
                                                self._points, self._curves,
                                                self._tables(model)[1], velocity_weight, nc)
            bodies, blocks = np.concatenate([bodies, pairs]), np.concatenate([blocks, more])
        return block_triplets(model, bodies, blocks)

    def switches(self, model, fr) -> np.ndarray:
        """Each row's switching function at the state of ``fr``: positive exactly while its law
        pushes (see :func:`~mbd3d.numerics.compiled.contacts.switches_into`)."""
        out = np.empty(len(self.owners))
        kernel.switches_into(fr.A, fr.omega3, fr.Q, fr.Qd, self._bodies(model), self._points,
                             self._values, self._curves, out)
        return out

    def table(self, model):
        shapes = self._tables(model)[1]
        return {"contact_bodies": self._bodies(model), "contact_points": self._points,
                "contact_values": self._values, "contact_curves": self._curves,
                "contact_shape_bodies": shapes[0], "contact_shape_points": shapes[1],
                "contact_shape_values": shapes[2], "contact_pair_laws": shapes[3]}

    def potential(self, model, fr) -> float:
        return float(np.sum(self._report(fr, self._tables(model))[:, kernel.POTENTIAL]))

    def states(self, model, fr, k: int = 1) -> np.ndarray:
        """The report of ``k`` states stacked in ``fr`` (see :meth:`_report`), (k * r, c)."""
        return self._report(fr, self._tables(model), k)


def _static(owner, law, mu: float, stop: bool) -> float:
    """The static friction coefficient of a row of ``owner`` whose law is ``law`` and kinetic
    coefficient ``mu`` (a :class:`~mbd3d.RigidImpact`'s ``static_friction``, else ``mu``)."""
    mu_s = getattr(law, "static_friction", None) if law.rigid else None
    if mu_s is None:
        return float(mu)
    what = getattr(owner, "what", f"'{owner.name}'")
    if stop and mu_s > 0.0:
        raise ModelError(f"{what}: a joint stop has no friction, so no static_friction "
                         f"({mu_s:g}); leave it out of its RigidImpact")
    if mu_s < mu:
        raise ModelError(f"{what}: static_friction {mu_s:g} is below its friction {mu:g}: "
                         "a contact sticks with at least what it rubs sliding; give "
                         "static_friction >= friction (the kinetic coefficient)")
    return float(mu_s)
