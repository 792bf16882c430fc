"""File plumbing shared by the readers and writers: format errors, netCDF loading."""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import xarray as xr


class FileFormatError(ValueError):
    """A file is truncated, corrupt or not in the format it should be in.

    The message names the file and what is wrong with it.
    """


def load_netcdf(path: str | os.PathLike, *, hint: str = "") -> xr.Dataset:
    """Load a netCDF file into memory as an :class:`xarray.Dataset`.

    Raises
    ------
    FileNotFoundError
        If the file does not exist.
    FileFormatError
        If it is not a readable netCDF file; the message names it (and ends
        with ``hint``).
    """
    import xarray as xr

    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"netCDF file {path} does not exist")
    try:
        return xr.load_dataset(path)
    except Exception as err:  # netCDF4/HDF5 raise OSError, RuntimeError, ValueError...
        message = f"{path} is not a readable netCDF file ({type(err).__name__}: {err})"
        raise FileFormatError(f"{message}; {hint}" if hint else message) from err
