"""Lazy evaluation of rbm_nb's array functions on dask-backed data.

A public function that receives a dask-backed DataArray (or a dask array)
hands it here instead of converting it to NumPy. The work is cut along time
into one task per chunk; each task runs the ordinary eager function on its
chunk, read with enough neighbouring samples (the *halo*) that its result
equals the eager result on the whole array:

- transforms look the frames up at each sample's own time, so a chunk needs
  no neighbours (halo 0);
- finite differences need the next samples, the not-a-knot spline through
  quaternions about 30 (its influence decays by 2 - sqrt(3) per sample), and
  the Butterworth low-pass as many as its slowest pole needs to decay to
  1e-16;
- quaternion series whose velocity is estimated are made sign-continuous
  once, lazily, before they are cut (the eager estimators make them
  sign-continuous from the first sample on, which a chunk cannot see).

Frames are resolved once, when the graph is built, on the client: the
graph holds their values (:mod:`rbm_nb.core._frame_snapshot`), not their names,
so the tasks run on any scheduler -- threads, worker processes, workers on
other machines, whose registries are empty. **A graph is a snapshot of the
registry**: a frame registered, replaced or removed after a lazy call does
not change its result (call the function again to use the new frames).
Each task carries only the samples of each moving frame that its chunk's
time window needs (:data:`MARGIN` more on each side), so a task's size
grows with its chunk, not with the recording, and every sample of a frame
travels about once, whatever the number of tasks. The per-block function
calls the engine directly, on frames built from those values.

Nothing is computed until the caller computes the result; dask is imported
only when dask-backed data arrives.

This module is the lazy path's one entry for the facades and the door; the
work is done by its parts, one job each:

- :mod:`~rbm_nb._door.dask_chunks`: one task per time chunk (:func:`over_time`),
  the halos and margins;
- :mod:`~rbm_nb._door.dask_transforms`: transforms and velocity transforms;
- :mod:`~rbm_nb._door.dask_estimates`: velocity estimates, outlier rejection
  across chunks, the low-pass;
- :mod:`~rbm_nb._door.dask_samples`: functions of each sample alone, and
  quaternion interpolation at new times.
"""

from __future__ import annotations

from .dask_chunks import (
    GRADIENT_HALO,
    MARGIN,
    SPLINE_HALO,
    SQUAD_HALO,
    as_dataarray,
    is_dask,
    over_time,
)
from .dask_estimates import estimate, lowpass, push, reinterpolate, sign_continuous
from .dask_samples import blockwise, elementwise, qinterp
from .dask_transforms import (
    VelocityContext,
    frame_time_range,
    time_dim_of,
    transform,
    velocity_transform,
)

__all__ = [
    "GRADIENT_HALO",
    "MARGIN",
    "SPLINE_HALO",
    "SQUAD_HALO",
    "VelocityContext",
    "as_dataarray",
    "blockwise",
    "elementwise",
    "estimate",
    "frame_time_range",
    "is_dask",
    "lowpass",
    "over_time",
    "push",
    "qinterp",
    "reinterpolate",
    "sign_continuous",
    "time_dim_of",
    "transform",
    "velocity_transform",
]
