"""How the lifting hot paths are compiled: numba, cached on disk, without the GIL.

A kernel compiles on its first call in a fresh checkout (about 15 s for all of them) and
is then loaded from ``__pycache__``. ``error_model="numpy"`` lets a division by zero give
``inf``/``nan`` as numpy does, where a Python ``ZeroDivisionError`` check would cost a
branch in every division. ``nogil`` lets the pipeline's worker threads lift clips in
parallel.
"""

from __future__ import annotations

import numba

#: Decorator of every compiled kernel.
kernel = numba.njit(cache=True, nogil=True, error_model="numpy")
