"""How handdb's hot loops are compiled: numba, cached on disk, without the GIL.

The lifting and gap-filling kernels share one decorator. A kernel compiles on its first
call in a fresh checkout (about 15 s for lifting's, 26 s for gap filling's) and is then
loaded from ``__pycache__``. ``error_model="numpy"`` lets a division by zero give
``inf``/``nan`` as numpy does, where a Python ``ZeroDivisionError`` check would cost a
branch in every division. ``nogil`` lets the pipeline's worker threads process clips in
parallel.

Numba's cache is keyed by each kernel's own source file: a change to this decorator does
not invalidate kernels already compiled, so clear ``handdb/**/__pycache__/*.nb[ci]`` after
changing it.
"""

from __future__ import annotations

import numba

#: Decorator of every compiled kernel.
kernel = numba.njit(cache=True, nogil=True, error_model="numpy")
