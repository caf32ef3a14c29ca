"""The gallery: every script of ``examples/`` run as the build starts, a page each with its
text, its code, what it printed and plots of the recordings it wrote.

Each script runs as a user runs it (``python examples/NAME.py``, no arguments) in a folder of
its own under the build's doctree folder, so that nothing is written beside the sources; its
``.rrd`` recordings are read back with :func:`mbd3d.viewer.read_component` and drawn with
matplotlib, a figure per recording with the panels the viewer's tabs show (the kinematic
screen, the force screen, the checks). A script that fails, or prints to stderr a traceback,
fails the build. A run is kept while neither the script nor the package changes.
"""

from __future__ import annotations

import hashlib
import os
import pathlib
import shutil
import subprocess
import sys

import numpy as np

#: the viewer's plot groups, by tab: (panel title, entity prefix under /plots)
PANELS = {
    "kinematic screen": [("joint coordinates", "joints"), ("positions", "position"),
                         ("angles", "angle"), ("velocities", "velocity"),
                         ("accelerations", "acceleration")],
    "force screen": [("driver efforts", "efforts"), ("joint reactions", "reactions"),
                     ("contact forces", "contacts")],
    "checks": [("energy [J]", "energy"), ("constraint residuals", "residuals")],
}
#: lines drawn in one panel at most (a robot's joints: its first ones)
MAX_LINES = 12
#: seconds an example may run (the slowest take about a minute warm)
TIMEOUT = 900
#: instants of a still of the 3D view, and the triangles drawn in it at most (beyond them, the
#: last instant only)
INSTANTS, MAX_TRIANGLES = 5, 60000


def build(root: pathlib.Path, pages: pathlib.Path, runs: pathlib.Path, warn) -> list[str]:
    """Run every example of ``root/examples`` into ``runs`` (kept while unchanged) and write
    its page into ``pages`` (``NAME.md``, figures in ``pages/images/NAME``) and the gallery's
    index; returns the examples' names. ``warn(message)`` reports a failed example."""
    pages.mkdir(parents=True, exist_ok=True)
    package = _package_digest(root)
    names = []
    for script in sorted((root / "examples").glob("*.py")):
        name = script.stem
        folder = runs / name
        output = _run(script, folder, package, warn)
        if output is None:
            continue
        images = pages / "images" / name
        shutil.rmtree(images, ignore_errors=True)
        images.mkdir(parents=True)
        figures = []
        for rrd in sorted(folder.glob("*.rrd")):
            figures += [_still(rrd, images / f"{rrd.name}.still.png"),
                        _plot(rrd, images / f"{rrd.name}.png")]
        for image in sorted(folder.glob("*.png")):  # pictures the script drew itself
            shutil.copyfile(image, images / image.name)
            figures.append(image.name)
        _write(pages / f"{name}.md", _page(script, output, [f"images/{name}/{figure}"
                                                            for figure in figures if figure]))
        names.append(name)
    _write(pages / "index.md", _index(names))
    return names


def _package_digest(root: pathlib.Path) -> str:
    """A digest of every source file of the package: a run is repeated when any changes."""
    digest = hashlib.sha256()
    for folder in ("mbd3d", "joints", "planar", "viewer"):
        for path in sorted((root / folder).rglob("*.py")):
            digest.update(path.read_bytes())
    return digest.hexdigest()


def _run(script: pathlib.Path, folder: pathlib.Path, package: str, warn) -> str | None:
    """The printed output of ``script`` run in ``folder`` (from before if neither it nor the
    package changed); None, with a warning, if it failed."""
    key = hashlib.sha256(script.read_bytes() + package.encode()).hexdigest()
    stamp, kept = folder / ".key", folder / ".output"
    if stamp.exists() and stamp.read_text() == key and kept.exists():
        return kept.read_text()
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir(parents=True)
    env = dict(os.environ, MPLBACKEND="Agg", MBD3D_PROGRESS="0", PYTHONUNBUFFERED="1")
    try:
        done = subprocess.run([sys.executable, str(script)], cwd=folder, env=env,
                              capture_output=True, text=True, timeout=TIMEOUT)
    except subprocess.TimeoutExpired:
        warn(f"gallery: examples/{script.name} ran over {TIMEOUT} s")
        return None
    if done.returncode != 0 or "Traceback" in done.stderr:
        tail = "\n".join(done.stderr.strip().splitlines()[-15:])
        warn(f"gallery: examples/{script.name} failed (exit {done.returncode}):\n{tail}")
        return None
    # the files it wrote are named as a user who ran it there would see them
    output = done.stdout.replace(str(folder) + os.sep, "")
    kept.write_text(output)
    stamp.write_text(key)
    return output


def _plot(rrd: pathlib.Path, png: pathlib.Path) -> str | None:
    """Draw the plots of the recording ``rrd`` into ``png``: a row of panels per tab of the
    viewer, each panel the series of one group against simulated time; None if it has no
    plots (a recording of modes or of a still)."""
    import matplotlib.pyplot as plt

    from mbd3d.viewer import entity_paths, read_component

    paths = sorted(p for p in entity_paths(rrd) if p.startswith("/plots/"))
    panels = []
    for tab, groups in PANELS.items():
        for title, prefix in groups:
            entities = [p for p in paths if p == f"/plots/{prefix}"
                        or p.startswith(f"/plots/{prefix}/")]
            if entities:
                panels.append((f"{tab}: {title}", entities))
    if not panels:
        return None
    columns = 2
    rows = (len(panels) + columns - 1) // columns
    fig, axes = plt.subplots(rows, columns, figsize=(11, 2.8 * rows), squeeze=False)
    for ax, (title, entities) in zip(axes.flat, panels):
        drawn = 0
        for entity in entities:
            t, values = read_component(rrd, entity, "Scalars:scalars", timeline="sim_time")
            if t is None or not len(t):
                continue
            labels = _names(rrd, entity, values.shape[1])
            seconds = t.astype("timedelta64[ns]").astype(float) * 1e-9
            for k in range(values.shape[1]):
                if drawn < MAX_LINES:
                    ax.plot(seconds, values[:, k], label=labels[k], linewidth=1.2)
                    drawn += 1
        ax.set_title(title, fontsize=10)
        ax.set_xlabel("t [s]", fontsize=9)
        ax.tick_params(labelsize=8)
        ax.grid(alpha=0.3)
        if 0 < drawn <= 8:
            ax.legend(fontsize=7, loc="best")
    for ax in list(axes.flat)[len(panels):]:
        ax.set_visible(False)
    fig.suptitle(rrd.name, fontsize=11)
    fig.tight_layout()
    fig.savefig(png, dpi=80)
    plt.close(fig)
    return png.name


def _still(rrd: pathlib.Path, png: pathlib.Path) -> str | None:
    """A still of the recording's 3D view, drawn from what it logged (each body's shape and
    its poses over time): the bodies at a few instants, the latest the darkest; planar models
    seen from above their plane. None if it has no bodies (a recording of plots only)."""
    import matplotlib.pyplot as plt
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection
    from scipy.spatial.transform import Rotation

    from mbd3d.viewer import entity_paths, read_component

    paths = entity_paths(rrd)
    bodies = sorted(p[:-len("/shape")] for p in paths
                    if p.startswith("/world/bodies/") and p.endswith("/shape"))
    if not bodies:
        return None
    shapes, poses = [], []
    for body in bodies:
        _, vertices = read_component(rrd, f"{body}/shape", "Mesh3D:vertex_positions", None)
        _, faces = read_component(rrd, f"{body}/shape", "Mesh3D:triangle_indices", None)
        _, colour = read_component(rrd, f"{body}/shape", "Mesh3D:albedo_factor", None)
        _, position = read_component(rrd, body, "Transform3D:translation", "sim_time")
        _, quaternion = read_component(rrd, body, "Transform3D:quaternion", "sim_time")
        rgba = int(np.asarray(colour).reshape(-1)[0])
        shapes.append((vertices.reshape(-1, 3), faces.reshape(-1, 3),
                       [(rgba >> shift & 255) / 255 for shift in (24, 16, 8)]))
        poses.append((position.reshape(-1, 3), quaternion.reshape(-1, 4)))
    k = min(len(p[0]) for p in poses)
    triangles = sum(len(faces) for _, faces, _ in shapes)
    instants = INSTANTS if triangles * INSTANTS <= MAX_TRIANGLES else 1
    chosen = np.unique(np.linspace(0, k - 1, instants).round().astype(int))
    fig = plt.figure(figsize=(7, 5))
    ax = fig.add_subplot(projection="3d")
    every = []
    for order, i in enumerate(chosen):
        alpha = 0.25 + 0.75 * (order + 1) / len(chosen)
        for (vertices, faces, rgb), (position, quaternion) in zip(shapes, poses):
            moved = Rotation.from_quat(quaternion[i]).apply(vertices) + position[i]
            every.append(moved)
            ax.add_collection3d(Poly3DCollection(moved[faces], facecolors=(*rgb, alpha),
                                                 edgecolor="none", shade=True))
    points = np.vstack(every)
    low, high = points.min(axis=0), points.max(axis=0)
    centre, half = (low + high) / 2, max(float(np.max(high - low)) / 2, 1e-9)
    for axis, c in zip("xyz", centre):
        getattr(ax, f"set_{axis}lim")(c - half, c + half)
        getattr(ax, f"set_{axis}label")(f"{axis} [m]")
    ax.set_box_aspect((1, 1, 1))
    # a planar model's bodies turn about z and stay at z = 0: seen from above, x to the right
    planar = all(not np.any(position[:, 2]) and not np.any(quaternion[:, :2])
                 for position, quaternion in poses)
    if planar:
        ax.view_init(elev=90, azim=-90)
        ax.set_zticks([])
        ax.set_zlabel("")
    else:  # up as the viewer has it (its view coordinates: 1 is up)
        try:
            _, codes = read_component(rrd, "/world", "ViewCoordinates:xyz", None)
            up = "xyz"[list(np.asarray(codes).reshape(-1)).index(1)]
        except (KeyError, ValueError, IndexError):
            up = "z"
        ax.view_init(elev=20, azim=-60, vertical_axis=up)
    ax.set_title(f"{rrd.name}: the bodies at {len(chosen)} instants"
                 + (", seen from above the plane" if planar else ""), fontsize=10)
    fig.tight_layout()
    fig.savefig(png, dpi=80)
    plt.close(fig)
    return png.name


def _names(rrd: pathlib.Path, entity: str, count: int) -> list[str]:
    """The series' names the recording gives ``entity``, or its path's last part."""
    from mbd3d.viewer import read_component

    try:
        _, names = read_component(rrd, entity, "SeriesLines:names", timeline=None)
        names = [str(n) for n in names.reshape(-1)]
    except (KeyError, ValueError, IndexError):
        names = []
    if len(names) != count:
        leaf = entity.rsplit("/", 1)[-1]
        names = [leaf if count == 1 else f"{leaf} {k}" for k in range(count)]
    return names


def _page(script: pathlib.Path, output: str, figures: list[str]) -> str:
    """The gallery page of ``script``: its docstring, its code, what it printed, figures."""
    source = script.read_text()
    doc = source.split('"""', 2)[1].strip() if source.startswith('"""') else script.stem
    title, _, text = doc.partition("\n")
    # the docstrings are plain text: a bar is an absolute value, not a substitution
    text = text.strip().replace("|", "\\|")
    lines = [f"# {title.strip()}", "", "```{eval-rst}", text, "```", "",
             f"```{{literalinclude}} ../../examples/{script.name}", ":language: python", "```",
             "", "## What it prints", "", "```text", output.rstrip() or "(nothing)", "```", ""]
    if figures:
        lines += ["## The recordings", "",
                  "Each recording the script wrote, read back from its `.rrd` file: a still "
                  "of the viewer's 3D view (the bodies at a few instants, the latest the "
                  "darkest) and the plots of its tabs.", ""]
        lines += [f"![{pathlib.PurePath(figure).name}]({figure})" for figure in figures]
    return "\n".join(lines) + "\n"


def _index(names: list[str]) -> str:
    """The gallery's front page: one line per example, its title."""
    lines = ["# Gallery", "",
             "Every script of `examples/`, run as the documentation was built: its code, what it",
             "printed and the plots of the recordings it wrote.", "", "```{toctree}",
             ":maxdepth: 1", ""]
    lines += names
    lines += ["```", ""]
    return "\n".join(lines)


def _write(path: pathlib.Path, text: str) -> None:
    """Write ``text`` unless the file holds it already."""
    if not path.exists() or path.read_text() != text:
        path.write_text(text)
