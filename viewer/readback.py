"""Reading a recording back: what entities it holds and the values logged for them.

Uses Rerun's own reader (``rerun.chunk.RrdReader``), so what is read is what the viewer shows.
It also reads files without a footer (a process killed while recording, a live stream saved by
``rerun --save``).
"""

from __future__ import annotations

import os

import numpy as np

__all__ = ["entity_paths", "read_component"]


def _chunks(path: str | os.PathLike):
    import warnings

    from rerun.chunk import RrdReader

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the reader warns about footer-less files
        return list(RrdReader(os.fspath(path)).stream().to_chunks())


def entity_paths(path: str | os.PathLike) -> set[str]:
    """Entity paths holding data in the recording (leading ``/``, e.g. ``/world/bodies/crank``).

    Parameters
    ----------
    path : str or path-like
        The ``.rrd`` file.
    """
    return {chunk.entity_path for chunk in _chunks(path)}


def read_component(path: str | os.PathLike, entity: str, component: str,
                   timeline: str | None = "step") -> tuple[np.ndarray | None, np.ndarray]:
    """Values of one component of one entity, in time order.

    Parameters
    ----------
    path : str or path
        The ``.rrd`` file.
    entity : str
        Entity path, e.g. ``"/world/bodies/crank"``.
    component : str
        ``"Archetype:field"``, e.g. ``"Transform3D:translation"`` or ``"Scalars:scalars"``.
    timeline : str or None
        The timeline to order by (``"step"`` or ``"sim_time"``); None reads the static value.

    Returns
    -------
    times : ndarray (rows,) or None
        The timeline's values (int steps, or ``timedelta64[ns]`` simulated times); None for
        static data.
    values : ndarray (rows, instances, ...)
        The logged values (float32 for positions and quaternions, float64 for scalars).
    """
    import pyarrow as pa

    entity = entity if entity.startswith("/") else "/" + entity
    times, values = [], []
    for chunk in _chunks(path):
        if chunk.entity_path != entity or chunk.is_static != (timeline is None):
            continue
        batch = chunk.to_record_batch()
        if component not in batch.schema.names:
            continue
        if timeline is not None and timeline not in batch.schema.names:
            continue
        inner = batch.column(component).flatten()
        if pa.types.is_fixed_size_list(inner.type):
            size = inner.type.list_size
            array = inner.flatten().to_numpy(zero_copy_only=False).reshape(-1, size)
        elif pa.types.is_list(inner.type) or pa.types.is_large_list(inner.type):
            array = np.array(inner.to_pylist(), dtype=object)
        else:
            array = inner.to_numpy(zero_copy_only=False)
        values.append(array.reshape(len(batch), -1, *array.shape[1:]))
        if timeline is not None:
            times.append(batch.column(timeline).to_numpy())
    if not values:
        raise KeyError(f"no {component} of {entity} on "
                       f"{'the static store' if timeline is None else timeline} in {path}")
    value = np.concatenate(values)
    if timeline is None:
        return None, value[-1:]
    t = np.concatenate(times)
    order = np.argsort(t, kind="stable")
    return t[order], value[order]
