"""What a recording of one model holds, and the layout it opens with.

A :class:`Scene` is made once per recording from the model: it decides what is drawn and
plotted, logs the static part (shapes, joint points, plot styles, layout), and turns each block
of new time points into a few columnar ``send_columns`` calls (one per entity and block, never
one call per time point, which is what makes recording cheap).
"""

from __future__ import annotations

from typing import Any, Mapping, Sequence

import numpy as np
import trimesh

from mbd3d.joints import (CamFollower, CoordinateDriver, FlatFaceFollower, GearPair, Prismatic,
                          RackPinion, RollingDisc, RollingDiscOnPlane, RotationDriver,
                          TranslationDriver)
from mbd3d.errors import ModelError
from mbd3d.model.springs import SpringDamper
from mbd3d.io.results import Results
from mbd3d.model.contacts import Contact, contact_group
from mbd3d.model.mass_properties import load_mesh
from mbd3d.viewer.contact_events import log_contact_events
from mbd3d.viewer.timeline import SIM_TIME, STEP, _rerun, sim_time_column
from mbd3d.viewer.joint_plots import JointPlots
from mbd3d.viewer.shapes import (GROUND_COLOR, attachment_points, body_shape, color_of,
                                 cam_outlines, contact_parts, curve_polyline, pitch_curves,
                                 initial_points, model_size)

__all__ = ["Scene"]

#: default detail limits: above these, plots and reaction arrows only for what is asked
#: (above 6 bodies and 8 joints a time plot of every one holds 20 lines and more, whose
#: legend covers the curves: a robot's joint coordinates are the readable plot)
MAX_PLOTTED_BODIES, MAX_RECORDED_JOINTS, MAX_JOINT_PLOTS = 6, 8, 24
#: longest arrow, as a fraction of the mechanism's size
ARROW_FRACTION = 0.3

FORCE_COLOR, TORQUE_COLOR = [255, 90, 60, 255], [255, 210, 40, 255]
JOINT_COLOR, SPRING_COLOR = [235, 235, 235, 255], [120, 220, 160, 255]


def _part(name: str) -> str:
    """An entity path part for a body or joint name (spaces and slashes escaped)."""
    return _rerun().escape_entity_path_part(name)


def _lift(v: np.ndarray) -> np.ndarray:
    """(..., d) -> (..., 3): planar vectors lie in z = 0."""
    out = np.zeros(v.shape[:-1] + (3,))
    out[..., :v.shape[-1]] = v
    return out


class _Block:
    """A block of results whose body histories are computed once however often asked for."""

    def __init__(self, results: Results):
        self.results = results
        self._bodies: dict[str, Any] = {}

    def body(self, name: str):
        if name not in self._bodies:
            self._bodies[name] = self.results.body(name)
        return self._bodies[name]

    def point_position(self, body, u: np.ndarray) -> np.ndarray:
        """(k, 3) global positions [m] of the body-frame point ``u`` (global for the ground)."""
        if body.is_ground:
            return np.broadcast_to(_lift(np.asarray(u)), (len(self.results), 3))
        history = self.body(body.name)
        return _lift(history.position + np.einsum("kab,b->ka", history.rotation, u))



class Scene:
    """The content of a recording of ``model`` (see :mod:`viewer.recorder` for the entities).

    Parameters
    ----------
    model : Model
    analysis : str
        "kinematic analysis", "inverse dynamics", "forward dynamics", "static equilibrium",
        "vibration mode" (one mode's animation: positions only) or "vibration modes" (the
        modes along a motion: adds their panel).
    plots, points, reactions, shapes
        As for :class:`viewer.Recorder`.
    """

    def __init__(self, model, analysis: str, *, plots: Sequence[str] | None = None,
                 points: Mapping[str, tuple[str, Sequence[float]]] | None = None,
                 reactions: Sequence[str] | None = None, shapes: Mapping[str, Any] | None = None):
        self.model = model
        self.analysis = analysis
        # analyses without multipliers draw no forces
        self.dynamic = analysis not in ("kinematic analysis", "vibration mode")
        self.joined = attachment_points(model)
        names = [b.name for b in model.bodies]
        unknown = sorted(set(shapes or {}) - set(names))
        if unknown:
            raise ModelError(f"shapes= names no body of '{model.name}': {', '.join(unknown)}")
        # meshes the user gave count in the mechanism's size, which sizes everything else
        given = {b.name: (load_mesh(shapes[b.name], f"viewer shape of body '{b.name}'")
                          if b.name in (shapes or {}) else b.shape)
                 for b in model.bodies if b.name in (shapes or {}) or b.shape is not None}
        self.size = model_size(model, self.joined, given)
        self._meshes = given
        if plots is None:
            plots = names if len(names) <= MAX_PLOTTED_BODIES else []
        self.plotted = [model.body(name).name for name in plots]
        self.points = {}
        for label, spec in (points or {}).items():
            try:
                body, u = spec
            except (TypeError, ValueError):
                raise ModelError(f"point '{label}': give (body name, point in the body frame), "
                                 f"got {spec!r}") from None
            u = np.asarray(u, dtype=float).reshape(-1)
            if u.size != model.dim or not np.all(np.isfinite(u)):
                raise ModelError(f"point '{label}' of body '{body}' must be {model.dim} finite "
                                 f"numbers [m], got {spec[1]!r}")
            if str(label) in names:
                raise ModelError(f"point label '{label}' is the name of a body, whose plots it "
                                 "would share; choose another label")
            self.points[str(label)] = (model.body(body).name, u)
        joints = [e for e in model.joints if not e.is_driver]
        if reactions is None:
            reactions = [e.name for e in joints] if len(joints) <= MAX_RECORDED_JOINTS else []
        for name in reactions:
            if model.joint(name).is_driver:
                raise ModelError(f"'{name}' is a driver: its effort is always recorded; "
                                 "reactions= takes joints")
        self.reactions = list(reactions) if self.dynamic else []
        self.drivers = [e for e in model.joints if e.is_driver] if self.dynamic else []
        self.springs = [f for f in model.forces if isinstance(f, SpringDamper)]
        self.joint_plots = JointPlots(model, MAX_JOINT_PLOTS)
        group = contact_group(model, required=False)
        #: contacts and stops (their forces plotted), whether a contact's (drawn as an arrow)
        self.contacts = [] if group is None or not self.dynamic else [
            (name, isinstance(owner, Contact)) for name, owner in zip(group.names, group.owners)]
        #: whether any contact is rigid (its impacts are listed)
        self.rigid = self.dynamic and group is not None and bool(np.any(group.rigid))
        self.shapes = {b.name: given[b.name] if b.name in given
                       else body_shape(model, b, self.joined[b.name], self.size)
                       for b in model.bodies}
        self.force_scale: float | None = None
        self.torque_scale: float | None = None
        self._moments: dict[str, bool] = {}

    # -- static content --------------------------------------------------------------------------
    def blueprint(self):
        """The default layout: the mechanism on the left; kinematics, forces and checks on the
        right, as tabs, so both screens of the original program are in view at once."""
        import rerun.blueprint as rrb  # noqa: PLC0415

        trails = rrb.VisibleTimeRanges([rrb.VisibleTimeRange(
            SIM_TIME, start=rrb.TimeRangeBoundary.infinite(),
            end=rrb.TimeRangeBoundary.cursor_relative())])
        centre, eye, up = self._eye()
        space = rrb.Spatial3DView(
            name="Mechanism", origin="/world",
            eye_controls=rrb.EyeControls3D(position=eye, look_target=centre, eye_up=up),
            # the grid lies in the horizontal plane: seen edge-on across a planar mechanism
            line_grid=rrb.LineGrid3D(visible=self.model.dim == 3),
            overrides={f"/world/trails/{_part(label)}": trails for label in self.points})
        kinematic = [rrb.TimeSeriesView(name="Joint coordinates [rad, m]",
                                        origin="/plots/joints")] if self.joint_plots.items else []
        kinematic.append(rrb.TimeSeriesView(name="Positions [m]", origin="/plots/position"))
        if self.model.dim == 2:
            kinematic.append(rrb.TimeSeriesView(name="Angles [rad]", origin="/plots/angle"))
        else:
            kinematic.append(rrb.TimeSeriesView(name="Angular velocities [rad/s]",
                                                origin="/plots/angular_velocity"))
        kinematic += [rrb.TimeSeriesView(name="Velocities [m/s]", origin="/plots/velocity"),
                      rrb.TimeSeriesView(name="Accelerations [m/s²]",
                                         origin="/plots/acceleration")]
        panels = [rrb.Tabs(*kinematic, name="Kinematic analysis")]
        if self.dynamic:
            forces = []
            if self.drivers:
                forces.append(rrb.TimeSeriesView(name="Driver efforts [N m, N]",
                                                 origin="/plots/efforts"))
            if self.reactions:
                forces.append(rrb.TimeSeriesView(name="Joint reactions [N, N m]",
                                                 origin="/plots/reactions"))
            if self._meshes_plotted():
                forces.append(rrb.TimeSeriesView(name="Gear mesh forces [N]",
                                                 origin="/plots/meshes"))
            if self.contacts:
                forces.append(rrb.TimeSeriesView(name="Contact forces [N, N m]",
                                                 origin="/plots/contacts"))
            if forces:
                panels.append(rrb.Tabs(*forces, name="Force analysis"))
        if self.analysis == "vibration modes":
            panels.insert(0, rrb.Tabs(
                rrb.TimeSeriesView(name="Natural frequencies [Hz]", origin="/plots/modes"),
                rrb.Spatial2DView(name="Frequencies against position", origin="/modes"),
                name="Vibration modes"))
        checks = [rrb.TimeSeriesView(name="Energy [J]", origin="/plots/energy"),
                  rrb.TimeSeriesView(name="Constraint residuals", origin="/plots/residuals"),
                  rrb.TextDocumentView(name="Run", origin="/info")]
        if self.rigid:
            checks.append(rrb.TextLogView(name="Impacts and rests", origin="/impacts"))
        panels.append(rrb.Tabs(*checks, name="Checks"))
        return rrb.Blueprint(rrb.Horizontal(space, rrb.Vertical(*panels), column_shares=[3, 2]),
                             rrb.TimePanel(timeline=SIM_TIME), collapse_panels=True)

    def _eye(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Where the 3D view looks from: down on the plane of a planar mechanism (a little
        tilted, so torques along the normal show), else obliquely with gravity pointing down."""
        cloud = initial_points(self.model, self.joined, self._meshes)
        centre = 0.5 * (cloud.min(axis=0) + cloud.max(axis=0))
        d = 2.0 * self.size
        if self.model.dim == 2:
            up = np.array([0.0, 1.0, 0.0])
            return centre, centre + d * np.array([0.0, -0.3, 1.0]), up
        gravity = _lift(self.model.gravity)
        norm = np.linalg.norm(gravity)
        up = -gravity / norm if norm > 0 else np.array([0.0, 0.0, 1.0])
        side = np.eye(3)[int(np.argmin(np.abs(up)))]
        side -= (side @ up) * up
        side /= np.linalg.norm(side)
        other = np.cross(up, side)
        return centre, centre + d * (0.75 * side - 0.45 * other + 0.5 * up), up

    def _up_coordinates(self):
        rr = _rerun()
        if self.model.dim == 2:
            return rr.ViewCoordinates.RIGHT_HAND_Y_UP
        g = self.model.gravity
        if np.any(g) and abs(g[1]) > max(abs(g[0]), abs(g[2])) and g[1] < 0:
            return rr.ViewCoordinates.RIGHT_HAND_Y_UP
        return rr.ViewCoordinates.RIGHT_HAND_Z_UP

    def log_static(self, stream, times: np.ndarray) -> None:
        """Log what does not change with time: shapes, joint points, ground, plot styles."""
        rr = _rerun()
        stream.log("world", self._up_coordinates(), static=True)
        radius = 0.035 * self.size
        for body in self.model.bodies:
            path = f"world/bodies/{_part(body.name)}"
            mesh = self.shapes[body.name]
            stream.log(f"{path}/shape", rr.Mesh3D(
                vertex_positions=mesh.vertices, triangle_indices=mesh.faces,
                vertex_normals=mesh.vertex_normals, albedo_factor=color_of(body)), static=True)
            joined = self.joined[body.name]
            if joined:
                stream.log(f"{path}/joints", rr.Points3D(
                    [u for _, u in joined], radii=radius, colors=JOINT_COLOR,
                    labels=[name for name, _ in joined], show_labels=False), static=True)
        ground_shapes = contact_parts(self.model, self.model.ground, self.size)
        if ground_shapes:
            mesh = trimesh.util.concatenate(ground_shapes)
            stream.log("world/ground/contacts", rr.Mesh3D(
                vertex_positions=mesh.vertices, triangle_indices=mesh.faces,
                vertex_normals=mesh.vertex_normals, albedo_factor=GROUND_COLOR), static=True)
        ground = self.joined["ground"]
        if ground:
            stream.log("world/ground/joints", rr.Points3D(
                [u for _, u in ground], radii=1.3 * radius, colors=GROUND_COLOR,
                labels=[name for name, _ in ground], show_labels=False), static=True)
        rails = self._rails() + self._planes()
        if rails:
            stream.log("world/ground/rails", rr.LineStrips3D(rails, radii=0.3 * radius,
                                                             colors=GROUND_COLOR), static=True)
        gears = pitch_curves(self.model)["ground"]
        if gears:
            stream.log("world/ground/gears", rr.LineStrips3D(
                [curve_polyline(c, self.size) for c in gears], radii=0.3 * radius,
                colors=GROUND_COLOR), static=True)
        cams = cam_outlines(self.model)["ground"]
        if cams:
            stream.log("world/ground/cams", rr.LineStrips3D(cams, radii=0.3 * radius,
                                                            colors=GROUND_COLOR), static=True)
        self._log_styles(stream)
        self.log_info(stream, None, times)

    def _planes(self) -> list[np.ndarray]:
        """Outlines of the planes discs roll on: squares about the drawing's contact points,
        as wide as the mechanism is big."""
        outlines = []
        for element in self.model.joints:
            if isinstance(element, RollingDiscOnPlane):
                _, _, axes = self.model.reaction_frame(element.name)
                first, second, normal = axes.T
                q0 = self.model.q0[self.model.coordinates_of(element.body_j)]
                offset = self.model.c0[self.model.rows_of(element.name)[0]]
                # below the disc's centre in the drawing, on the plane
                centre = q0[:3] - (q0[:3] @ normal - offset) * normal
                corners = [centre + self.size * (a * first + b * second)
                           for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1), (-1, -1))]
                outlines.append(np.array(corners))
        return outlines

    def _rails(self) -> list[np.ndarray]:
        """Lines along which bodies slide on the ground, as long as the mechanism is big."""
        rails = []
        for element in self.model.joints:
            if isinstance(element, Prismatic) and element.body_i.is_ground:
                u_i, _, axes = self.model.reaction_frame(element.name)
                p, h = _lift(u_i), _lift(axes[:, 0])
                rails.append(np.array([p - self.size * h, p + self.size * h]))
        return rails

    def _log_styles(self, stream) -> None:
        rr = _rerun()
        axes = "xyz"[:self.model.dim]
        for name in self.plotted + list(self.points):
            color = (color_of(self.model.body(name)) if name in self.plotted
                     else color_of(self.model.body(self.points[name][0])))
            shades = [np.clip(color[:3] * f, 0, 255).astype(np.uint8) for f in (1.0, 0.7, 0.45)]
            part = _part(name)
            for quantity in ("position", "velocity", "acceleration"):
                stream.log(f"plots/{quantity}/{part}", rr.SeriesLines(
                    names=[f"{name} {a}" for a in axes], colors=shades[:len(axes)]), static=True)
            if name in self.plotted and self.model.dim == 2:
                stream.log(f"plots/angle/{part}", rr.SeriesLines(names=f"{name} angle",
                                                                 colors=shades[0]), static=True)
            elif name in self.plotted:
                stream.log(f"plots/angular_velocity/{part}", rr.SeriesLines(
                    names=[f"{name} ω{a}" for a in "xyz"], colors=shades), static=True)
        self.joint_plots.log_styles(stream, rr, _part)
        for driver in self.drivers:
            unit = "N m" if self._effort_kind(driver)[0] == "torque" else "N"
            stream.log(f"plots/efforts/{_part(driver.name)}",
                       rr.SeriesLines(names=f"{driver.name} [{unit}]"), static=True)
        for name in self.reactions:
            stream.log(f"plots/reactions/{_part(name)}/force",
                       rr.SeriesLines(names=[f"{name} F{a}" for a in axes]), static=True)
        for name in self._meshes_plotted():
            stream.log(f"plots/meshes/{_part(name)}", rr.SeriesLines(
                names=[f"{name} tangential", f"{name} tooth"]), static=True)
        energies = [("kinetic", [76, 144, 226]), ("potential", [240, 140, 50]),
                    ("dissipated", [200, 80, 80]), ("lost in impacts", [150, 110, 200]),
                    ("total", [235, 235, 235])]
        if not self.contacts:
            energies = [energies[0], energies[1], energies[4]]
        stream.log("plots/energy", rr.SeriesLines(names=[name for name, _ in energies],
                                                  colors=[color for _, color in energies]),
                   static=True)
        stream.log("plots/residuals/position", rr.SeriesLines(names="max |C| [m, rad]"),
                   static=True)
        stream.log("plots/residuals/velocity", rr.SeriesLines(
            names="max |Cq qd + Ct| [m/s, rad/s]"), static=True)

    def log_info(self, stream, results: Results | None, times: np.ndarray | None = None) -> None:
        """The text shown under "Run": the model, the analysis and how it ended."""
        rr = _rerun()
        model = self.model
        if results is None:
            span = f"{times[0]:g} to {times[-1]:g} s" if times is not None and len(times) else ""
            status = f"running ({span})"
        else:
            span = f"{results.t[0]:g} to {results.t[-1]:g} s" if len(results) else "no time points"
            status = f"{results.status}, {len(results)} time points, {span}"
            if results.message:
                status += f"\n\n> {results.message}"
        lines = [f"# {model.name}: {self.analysis}", "", f"{model!r}", "",
                 f"**Status:** {status}", ""]
        if self.force_scale is not None:
            lines.append(f"Force arrows: 1 m per {1.0 / self.force_scale:.4g} N.")
        if self.torque_scale is not None:
            lines.append(f"Torque arrows (right-hand rule): 1 m per "
                         f"{1.0 / self.torque_scale:.4g} N m.")
        lines += ["", "Reactions are the forces the joints exert on their moving body (the "
                  "second body unless it is the ground), drawn at the joint; a gear mesh's "
                  "is the tooth force on its second body, drawn at the pitch point, and a "
                  "cam's the contact force on its follower, at the contact point."]
        stream.log("info", rr.TextDocument("\n".join(lines), media_type="text/markdown"),
                   static=True)

    def log_impacts(self, stream, results: Results) -> None:
        """The rigid contacts' impacts, rests and releases as events on the simulated time
        line (:func:`viewer.contact_events.log_contact_events`)."""
        log_contact_events(stream, results, self.size)

    # -- time series -----------------------------------------------------------------------------
    def log_block(self, stream, block: Results, first_step: int) -> None:
        """Send the time points of ``block`` (the ``first_step``-th and on) as columns."""
        rr = _rerun()
        k = len(block)
        times = [sim_time_column(block.t),
                 rr.TimeColumn(STEP, sequence=np.arange(first_step, first_step + k))]
        send = stream.send_columns
        view = _Block(block)
        position, quaternion = block.poses()
        xyzw = quaternion[..., [1, 2, 3, 0]]
        for n, body in enumerate(self.model.bodies):
            send(f"world/bodies/{_part(body.name)}", indexes=times,
                 columns=rr.Transform3D.columns(translation=position[:, n],
                                                quaternion=xyzw[:, n]))

        def send_motion(part: str, history) -> None:
            for quantity in ("position", "velocity", "acceleration"):
                send(f"plots/{quantity}/{part}", indexes=times,
                     columns=rr.Scalars.columns(scalars=getattr(history, quantity)))

        for name in self.plotted:
            history = view.body(name)
            part = _part(name)
            send_motion(part, history)
            if self.model.dim == 2:
                send(f"plots/angle/{part}", indexes=times,
                     columns=rr.Scalars.columns(scalars=history.angle))
            else:
                send(f"plots/angular_velocity/{part}", indexes=times,
                     columns=rr.Scalars.columns(scalars=history.angular_velocity))
        for label, (body, u) in self.points.items():
            history = block.point(body, u)
            part = _part(label)
            send_motion(part, history)
            send(f"world/trails/{part}", indexes=times, columns=rr.Points3D.columns(
                positions=_lift(history.position), radii=np.full(k, 0.006 * self.size),
                colors=np.tile(color_of(self.model.body(body)), (k, 1))))
        self.joint_plots.send(stream, rr, _part, block, times)
        for spring in self.springs:
            ends = self._spring_ends(view, spring)
            send(f"world/springs/{_part(spring.name)}", indexes=times,
                 columns=rr.LineStrips3D.columns(strips=ends, colors=np.tile(SPRING_COLOR, (k, 1)),
                                                 radii=np.full(k, 0.008 * self.size)))
        if self.dynamic:
            self._log_forces(stream, view, times)
        # with contacts the total is the energy balance's: what they dissipated and what their
        # impacts took added back, so that it stays level where nothing else does work
        balance = block.energy_balance()
        parts = ["kinetic", "potential"] + (["dissipated", "lost_in_impacts"]
                                            if self.contacts else []) + ["total"]
        send("plots/energy", indexes=times, columns=rr.Scalars.columns(
            scalars=np.column_stack([balance[part] for part in parts])))
        send("plots/residuals/position", indexes=times,
             columns=rr.Scalars.columns(scalars=block.position_residual))
        send("plots/residuals/velocity", indexes=times,
             columns=rr.Scalars.columns(scalars=block.velocity_residual))

    def _meshes_plotted(self) -> list[str]:
        """The gear meshes among the joints whose reactions are drawn."""
        return [name for name in self.reactions
                if isinstance(self.model.joint(name), (GearPair, RackPinion))
                and not isinstance(self.model.joint(name), RollingDisc)]

    def _spring_ends(self, view: _Block, spring: SpringDamper) -> np.ndarray:
        """(k, 2, 3) global positions of a spring's two ends."""
        group = next(g for g in self.model.force_groups if spring in getattr(g, "elements", ()))
        n = group.elements.index(spring)
        return np.stack([view.point_position(spring.body_i, group.u_i[n]),
                         view.point_position(spring.body_j, group.u_j[n])], axis=1)

    def _moving_side(self, element) -> tuple[Any, np.ndarray]:
        """The body a joint's reaction is drawn on (body j unless it is the ground) and the
        joint's point on it (body frame)."""
        u_i, u_j, _ = self.model.reaction_frame(element.name)
        if element.body_j.is_ground:
            return element.body_i, u_i
        return element.body_j, u_j

    def _effort_kind(self, driver) -> tuple[str, Any, np.ndarray]:
        """``(kind, body, axis)``: "torque" or "force" along ``axis`` given in the frame of
        ``body`` (the ground: global axes)."""
        model = self.model
        _, _, axes = model.reaction_frame(driver.name)
        if isinstance(driver, RotationDriver):
            if model.dim == 2:
                return "torque", model.ground, np.array([0.0, 0.0, 1.0])
            return "torque", driver.body_i, axes[:, 2]
        if isinstance(driver, TranslationDriver):
            return "force", driver.body_i, _lift(axes[:, 0])
        if isinstance(driver, CoordinateDriver):
            names = model.body_type.coordinate_names
            c = driver.coordinate
            index = names.index(c) if isinstance(c, str) else int(c)
            if index < model.dim:
                return "force", model.ground, np.eye(3)[index]
            return "torque", model.ground, np.array([0.0, 0.0, 1.0])
        return "force", model.ground, np.zeros(3)  # an unknown driver type: no arrow

    def _global(self, view: _Block, body, vector: np.ndarray) -> np.ndarray:
        """(k, 3): a vector fixed in ``body`` in global components over the block."""
        k = len(view.results)
        if body.is_ground:
            return np.broadcast_to(vector, (k, 3))
        rotation = view.body(body.name).rotation
        if self.model.dim == 2:
            lifted = np.zeros((k, 3))
            lifted[:, :2] = np.einsum("kab,b->ka", rotation, vector[:2])
            lifted[:, 2] = vector[2]
            return lifted
        return np.einsum("kab,b->ka", rotation, vector)

    def _contact_forces(self, stream, block: Results, times: list) -> list:
        """Plot every contact's and stop's normal force; the arrows of the contacts' forces
        on their second shapes, at the contact points (none where they are apart)."""
        if not self.contacts:
            return []
        rr, states, arrows = _rerun(), block.contacts(), []
        for r, (name, is_contact) in enumerate(self.contacts):
            part = _part(name)
            stream.send_columns(f"plots/contacts/{part}", indexes=times,
                                columns=rr.Scalars.columns(scalars=states.normal_force[:, r]))
            if is_contact:
                force = (states.normal_force[:, r, None] * states.normal[:, r]
                         + states.friction_force[:, r])
                arrows.append((f"world/contacts/{part}", states.point[:, r], force, "force"))
        return arrows

    def _log_forces(self, stream, view: _Block, times: list) -> None:
        rr = _rerun()
        block = view.results
        send, k = stream.send_columns, len(block)
        arrows = []  # (entity, origins, vectors, kind)
        for name in self.reactions:
            element = self.model.joint(name)
            body, u = self._moving_side(element)
            reaction = block.joint(name).reaction(on=body.name)
            force = _lift(reaction.force)
            part = _part(name)
            send(f"plots/reactions/{part}/force", indexes=times,
                 columns=rr.Scalars.columns(scalars=reaction.force))
            moment = np.reshape(reaction.moment, (k, -1))
            if name not in self._moments:
                # a joint that carries a moment (prismatic, weld) gets a moment plot; decided
                # on the first block so the plot does not appear half way
                scale = np.max(np.abs(reaction.force), initial=0.0) * self.size
                self._moments[name] = bool(np.max(np.abs(moment), initial=0.0) > 1e-9 * scale)
                if self._moments[name]:
                    stream.log(f"plots/reactions/{part}/moment", rr.SeriesLines(
                        names=[f"{name} M{a}" for a in ("z" if moment.shape[1] == 1 else "xyz")]),
                        static=True)
            if self._moments[name]:
                send(f"plots/reactions/{part}/moment", indexes=times,
                     columns=rr.Scalars.columns(scalars=moment))
            if isinstance(element, RollingDisc):
                # the track's whole force on the disc, at the contact point
                point, normal = block.joint(name).contact()
                history = block.joint(name)
                along = np.column_stack([normal[:, 1], -normal[:, 0]])
                arrows.append((f"world/reactions/{part}", _lift(point), _lift(
                    history.contact_force[:, None] * normal
                    + history.traction[:, None] * along), "force"))
                continue
            if isinstance(element, (GearPair, RackPinion)):
                # a mesh: the tooth force along the line of action, at the pitch point
                mesh = block.joint(name).mesh_force
                send(f"plots/meshes/{part}", indexes=times, columns=rr.Scalars.columns(
                    scalars=np.column_stack([mesh.tangential, mesh.tooth])))
                arrows.append((f"world/reactions/{part}", _lift(mesh.point), _lift(mesh.force),
                               "force"))
                continue
            if isinstance(element, (CamFollower, FlatFaceFollower)):
                # a cam: the normal contact force on the follower, at the contact point
                point, normal = block.joint(name).contact()
                push = block.joint(name).contact_force
                arrows.append((f"world/reactions/{part}", _lift(point),
                               _lift(push[:, None] * normal), "force"))
                continue
            arrows.append((f"world/reactions/{part}", view.point_position(body, u), force,
                           "force"))
        arrows += self._contact_forces(stream, block, times)
        for driver in self.drivers:
            effort = block.driver(driver.name).effort
            send(f"plots/efforts/{_part(driver.name)}", indexes=times,
                 columns=rr.Scalars.columns(scalars=effort))
            kind, axis_body, axis = self._effort_kind(driver)
            body, u = self._moving_side(driver)
            origin = view.point_position(body, u)
            vectors = effort[:, None] * self._global(view, axis_body, axis)
            arrows.append((f"world/efforts/{_part(driver.name)}", origin, vectors, kind))
        # fixed on the first block that has forces: arrows of later blocks compare with them
        for kind, attribute in (("force", "force_scale"), ("torque", "torque_scale")):
            if getattr(self, attribute) is None:
                largest = max((np.max(np.linalg.norm(v, axis=1), initial=0.0)
                               for _, _, v, c in arrows if c == kind), default=0.0)
                if largest > 0:
                    setattr(self, attribute, ARROW_FRACTION * self.size / largest)
        for entity, origins, vectors, kind in arrows:
            scale = self.force_scale if kind == "force" else self.torque_scale
            color = FORCE_COLOR if kind == "force" else TORQUE_COLOR
            send(entity, indexes=times, columns=rr.Arrows3D.columns(
                origins=origins, vectors=vectors * (scale or 0.0),
                colors=np.tile(color, (k, 1)), radii=np.full(k, 0.008 * self.size)))
