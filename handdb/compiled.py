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

#: Decorator of a small kernel that other kernels call in their inner loops: numba inlines
#: it into each caller (at its IR, before LLVM), so no call is made per use and the
#: caller's loop is optimised across it. The arithmetic and its order stay the kernel's
#: own, so results are the same to the last bit; only compile time grows.
inline_kernel = numba.njit(cache=True, nogil=True, error_model="numpy", inline="always")
