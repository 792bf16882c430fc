"""Studies: one analysis over many recordings, on whatever dask scheduler is active.

A lab's study is many recordings (subjects x sessions) analysed alike. This
package opens them lazily, builds each one's frame tree in the task that
needs it, and maps an analysis over all of them -- on threads by default, on
a ``dask.distributed`` cluster when a ``Client`` exists -- returning one
xarray object with a ``recording`` dimension or writing one file per
recording without gathering. Long recordings can be cut into time windows
so that a task's memory depends on the window, not the recording.

Needs the ``dask`` extra (``pip install 'rbm_nb[dask]'``).
"""

from ._cluster import WORKER_SETTINGS, local_cluster
from ._sources import Recording, RecordingSource, find_sources
from ._study import Study, open_study

__all__ = [
    "WORKER_SETTINGS",
    "Recording",
    "RecordingSource",
    "Study",
    "find_sources",
    "local_cluster",
    "open_study",
]
