"""The door between the public API and the engine.

Everything a user hands the frame core comes in here and leaves as checked,
kernel-ready values: arrays and DataArrays unpacked (``unpack``), the rules
for timestamps (``time``), coordinates and quaternions (``validation``),
xarray results (``xarray``), frame paths through the tree (``frame_paths``),
frames resolved into immutable values (``frame_snapshot``) and the blocks a
lazy dask computation runs (``dask_blocks``). Below it, ``_engine`` and
``_kernels`` check nothing.
"""
