"""How the gap-filling hot loops are compiled: numba, cached on disk, without the GIL.

The same decorator as the lifting kernels' (:mod:`handdb.lifting.compiled`), declared here
so that gap filling does not import the lifting package. A kernel compiles on its first call
in a fresh checkout (a few seconds) and is then loaded from ``__pycache__``.
``error_model="numpy"`` lets a division by zero give ``inf``/``nan`` as numpy does.
"""

from __future__ import annotations

import numba

#: Decorator of every compiled gap-filling kernel.
kernel = numba.njit(cache=True, nogil=True, error_model="numpy")
