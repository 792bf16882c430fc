"""The door between the public API and the engine.

Everything a user hands the frame core comes in here and leaves as checked,
kernel-ready values: the arguments of a transform (``inputs``: arrays laid out
as the engine's blocks, frames resolved, one entry per dask block), arrays
and DataArrays unpacked (``unpack``: the one axis and dim rules), the other
facades' arrays (``shapes``: fixed trailing shapes, an axis of a given
length; ``poses``: rotation and homogeneous matrices), the velocity
estimators' series and every velocity's options (``series``), coordinates
and quaternions checked (``validation``), xarray results (``xarray``), frame paths through the tree
(``frame_paths``) and the blocks a lazy dask computation runs
(``dask_blocks``). Each facade of :mod:`rbm_nb.core` makes one call here
and gets a frozen, checked value back: ``inputs.arguments`` (transforms),
``estimators`` (velocity series, vector pairs, ICP), ``coordinates``,
``quaternions`` (qinv, qmul, qmean, qinterp, rotate_vectors,
from_euler_angles), ``poses`` (the se3 functions), ``shapes`` (the
conversions), ``lookups`` (frames resolved, options checked, a static chain refused
for a velocity; the times a lookup is asked at checked against its chain by
``at_times``) and ``evaluation`` (``ape``/``rpe``'s
trajectories matched and options checked, ``umeyama_alignment``'s points); ``tests/core/test_one_door_call.py`` counts. Timestamps become the engine's tracks
(:mod:`rbm_nb._engine.time`) here too. Below it, ``_engine`` and ``_kernels``
refuse only what shows once they have computed (a velocity's samples left
after missing rows or outliers), nothing else.
"""
