"""The frame core's public modules: the API of rigid-body-motion, and more.

Reference frames and their registry (``frames``; the frame's base classes
in ``frame_node``, ``frame_constructors``, ``frame_transforms``), lookups
and transforms (``lookups``, ``transforms``), estimators, quaternion and
coordinate utilities (``quaternions``, ``coordinates``, ``conversions``), the
``Transform`` value type and SE(3) algebra (``rigid_transform`` with its
scikit-robot methods in ``pose_methods``, ``se3``),
trajectory evaluation (``evaluation``), gaze geometry (``gaze``), matplotlib
plots (``plot``) and the ``DataArray.rbm`` accessor (``accessors``).

Their names are exported at the top level (``rbm.transform_points``) and each
module is also importable under its old path (``rbm_nb.frames``).
"""
