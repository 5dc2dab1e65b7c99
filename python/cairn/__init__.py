"""cairn: SLAM, pose-graph optimisation and trajectory evaluation from Python.

The classes and functions are those of the C++ library (``cairn._cairn``, bound with pybind11);
arrays go in and out as numpy arrays (poses N x 4 x 4 float64, points N x 3 float32). Errors in
input files raise :class:`cairn.ParseError`, a ``ValueError`` that keeps the file and line.
See docs/use_from_python.md.
"""

from ._cairn import *  # noqa: F401,F403
from ._cairn import __version__  # noqa: F401
