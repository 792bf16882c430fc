"""The frame engine: lookups and transforms on resolved frames.

This layer sits between the public facades (:mod:`rbm_nb.frames`,
:mod:`rbm_nb.transforms`, :mod:`rbm_nb.lookups`) and the numba kernels
(:mod:`rbm_nb._kernels`). Everything here receives frames that are already
resolved (``ReferenceFrame`` objects, never names) and arrays that already
went through the door (:mod:`rbm_nb._door.unpack`). Of a frame it reads one
immutable value, ``frame.data`` (:mod:`~rbm_nb._engine.frame_data`), and
keys its caches by such values; it never imports :mod:`rbm_nb.frames`, so
the import graph stays a tree of layers:

    facades (frames, transforms, lookups, estimators, ...)
      -> _engine (chain, transform, twist, at_time, velocity)
        -> _time, _door, _validation, errors
          -> _kernels -> _config

Modules:

* ``frame_data``: the value a frame hands the engine;
* ``chain``: the chain of frames between two frames, timestamp matching,
  resampling and composition;
* ``transform``: points, vectors and quaternions from one frame to another;
* ``velocity``: finite-difference velocities of sampled series;
* ``twist``: velocity lookups and velocity transforms (three-term formulas);
* ``at_time``: point-in-time lookups (tf2 style, no extrapolation).
"""
