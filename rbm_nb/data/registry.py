"""Where the real example recordings live and what they must hash to.

They are the recordings the rigid-body-motion documentation uses: a subject
walking twice around a building with a RealSense T265 head tracker and a
Pupil Core eye tracker.
"""

from __future__ import annotations

# the folders' environment variables, here for the registry's readers; the
# rules are in rbm_nb._infra.folders
from .._infra.folders import CACHE_DIR_ENV, DATA_DIR_ENV

__all__ = ["BASE_URL", "CACHE_DIR_ENV", "DATA_DIR_ENV", "REGISTRY"]

BASE_URL = "https://github.com/phausamann/rbm-data/raw/main/"

# name -> (file name under BASE_URL, sha256)
REGISTRY: dict[str, tuple[str, str]] = {
    "head": (
        "head.nc",
        "874eddaa51bf775c7311f0046613c6f969adef6e34fe4aea2e1248a75ed3fee3",
    ),
    "left_eye": (
        "left_eye.nc",
        "56d5488fb8d3ff08450663ed0136ac659c1d51eb5340a7e3ed52f5ecf019139c",
    ),
    "right_eye": (
        "right_eye.nc",
        "b038c4cb2f6932e4334f135cdf7e24ff9c3b5789977b2ae0206ba80acf54c647",
    ),
    "rosbag": (
        "example.bag",
        "8d27f5e554f5a0e02e0bec59b60424e582f6104380f96c3f226b4d85c107f2bc",
    ),
}
