"""fgcal: multi-camera extrinsic calibration of legged robots on a factor graph.

The C++ library from Python (docs/python.md lists the API):

- geometry: ``fgcal.so3`` and ``fgcal.se3`` on numpy 3x3 / 4x4 matrices
  (tangent [w v], right perturbation T ⊕ xi = T Exp(xi)), and keys;
- the solver: Values, NoiseModel, robust kernels, the library's factors,
  PythonFactor (a factor written in Python), FactorGraph, optimize, Marginals,
  check_factor_jacobians;
- robots and cameras: RobotModel, KinematicChain, CameraModel, CharucoTarget,
  CharucoDetector, estimate_pose, render_board;
- the pipeline: simulate, calibrate, evaluate.

Errors of fgcal's own are fgcal.Error: InputError (bad input, also a
ValueError; the command line's exit code 2) and DataError (data that cannot
support a result, also a RuntimeError; exit code 1), with the message the
command line prints.

numpy is needed to call into the library, not to import it.
"""

from ._version import __version__
from ._fgcal import *  # noqa: F401,F403  (the names are listed in _fgcal and docs/python.md)
from ._fgcal import Error, InputError, DataError, so3, se3  # noqa: F401  (named for readers and linters)

import sys as _sys

# `import fgcal.se3` and `from fgcal.so3 import exp` work like for any submodule.
_sys.modules[__name__ + ".se3"] = se3
_sys.modules[__name__ + ".so3"] = so3
del _sys
