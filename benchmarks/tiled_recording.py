"""The example head/eye recording tiled in time to any length (issue 35's benchmarks).

    from tiled_recording import tiled_head_eye
    head, left_eye, right_eye = tiled_head_eye(hours=1.0)

Every variable of the three datasets (head 200 Hz, eyes ~340 Hz, NaN rows
kept) is repeated end to end, each copy shifted by the recording's span plus
5 ms, until the recording lasts at least ``hours`` (0: as recorded, 5.5 min
for the real one). Read from ``RBM_NB_DATA_DIR`` like
:func:`rbm_nb.explorer.load_head_eye`.
"""

from __future__ import annotations

import numpy as np


def tiled(datasets, hours: float):
    """``datasets`` (sharing one clock) repeated in time to at least ``hours``."""
    import xarray as xr

    if hours <= 0:
        return list(datasets)
    first = min(ds.time.values[0] for ds in datasets)
    last = max(ds.time.values[-1] for ds in datasets)
    period = (last - first) + np.timedelta64(5, "ms")
    tiles = int(
        np.ceil(hours * 3600e9 / period.astype("timedelta64[ns]").astype(np.int64))
    )
    shifts = (np.arange(tiles) * period).astype("timedelta64[ns]")
    out = []
    for ds in datasets:
        time = (ds.time.values[None, :] + shifts[:, None]).ravel()
        data_vars = {
            name: (var.dims, np.concatenate([var.values] * tiles, axis=0), var.attrs)
            for name, var in ds.data_vars.items()
        }
        coords = {name: ds[name] for name in ds.coords if name != "time"}
        tiled_ds = xr.Dataset(
            data_vars, coords={**coords, "time": time}, attrs=ds.attrs
        )
        if _read_only(ds):
            _freeze(tiled_ds)  # as the loader gave the recording: read-only
        out.append(tiled_ds)
    return out


def _read_only(ds) -> bool:
    return all(not var.values.flags.writeable for var in ds.data_vars.values())


def _freeze(ds) -> None:
    """Every array of ``ds`` read-only down to its owner (what the loaders do,
    ``rbm_nb._infra.frozen.freeze_dataset``; written out here so that
    ``--compare`` runs this file against trees without it)."""
    for var in ds.variables.values():
        node = np.asarray(var.values)
        while isinstance(node, np.ndarray):
            node.setflags(write=False)
            node = node.base


def tiled_head_eye(hours: float):
    """(head, left_eye, right_eye) of the example recording, tiled to ``hours``."""
    from rbm_nb.app import explorer

    head, left_eye, right_eye, _ = explorer.load_head_eye()
    return tuple(tiled((head, left_eye, right_eye), hours))


def loaded_bytes(datasets) -> int:
    """Bytes of the datasets' own arrays (variables and coordinates)."""
    return int(sum(ds.nbytes for ds in datasets))
