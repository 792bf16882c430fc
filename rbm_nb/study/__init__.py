"""Studies: one analysis over many recordings, on whatever dask scheduler is active.

A lab's study is many recordings (subjects x sessions) analysed alike. This
package opens them lazily, builds each one's frame tree in the task that
needs it, and maps an analysis over all of them -- on threads by default, on
a ``dask.distributed`` cluster when a ``Client`` exists -- returning one
xarray object with a ``recording`` dimension or writing one file per
recording without gathering. Long recordings can be cut into time windows
so that a task's memory depends on the window, not the recording.

Needs the ``dask`` extra (``pip install 'rbm_nb[dask]'``).

On a cluster that already runs (a lab server, an HPC job started with
dask-jobqueue, Kubernetes), connect a client to its scheduler before
mapping -- ``distributed.Client("tls://scheduler-host:8786",
security=...)`` -- and :meth:`Study.map` runs there. Each worker needs
rbm_nb with the ``dask`` extra (the same version as the client: tasks call
its functions), the packages the analysis imports, and read access to the
study's files at the same paths (a shared file system); in-memory
recordings travel with the tasks instead. Nothing needs to be registered
on the workers: ``frames`` builds each recording's frames in its task, and
rbm_nb's lazy array functions carry the frames their graphs need as
values, resolved when the graph is built (see :mod:`rbm_nb._door.dask_blocks`).
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
