"""Reading motion data from files: OptiTrack Motive CSV exports, netCDF.

Rosbags are read and written by :mod:`rbm_nb.ros`; every reader raises
:class:`FileFormatError` (a ValueError) for a truncated or corrupt file.
"""

from ._files import FileFormatError, load_netcdf
from .optitrack import load_optitrack

__all__ = ["FileFormatError", "load_netcdf", "load_optitrack"]
