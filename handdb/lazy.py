"""Names a package offers before it imports what they name.

A registry's names (the lifting methods, the gap-filling methods) are wanted where their
algorithms are not: ``handdb build --help`` lists them, option checks look them up. The
algorithms pull in numba and scipy (seconds of start-up), so a package declares each entry
as a :class:`LazyFunction`, which imports its module on the first call, and re-exports its
heavy functions through :func:`lazy_attributes`, imported on first use.

>>> sqrt = LazyFunction("math:sqrt")
>>> sqrt(9.0)
3.0
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from importlib import import_module
from typing import Any


def _resolve(target: str) -> Any:
    module, _, attribute = target.partition(":")
    return getattr(import_module(module), attribute)


class LazyFunction:
    """A function named by ``"module:attribute"``, imported when first called.

    Parameters
    ----------
    target
        Where the function is, ``"package.module:name"``.
    *args
        When given, ``name`` is a factory: the function is ``name(*args)``, made once.
    """

    def __init__(self, target: str, *args: Any) -> None:
        if ":" not in target:
            raise ValueError(f"a lazy function is 'module:attribute', got '{target}'")
        self.target = target
        self.args = args
        self._function: Callable[..., Any] | None = None

    @property
    def function(self) -> Callable[..., Any]:
        """The function itself (its module is imported now if it was not yet)."""
        if self._function is None:
            found = _resolve(self.target)
            self._function = found(*self.args) if self.args else found
        return self._function

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        """Call the function with these arguments."""
        return self.function(*args, **kwargs)

    def __repr__(self) -> str:
        arguments = "".join(f", {a!r}" for a in self.args)
        return f"LazyFunction({self.target!r}{arguments})"


def lazy_attributes(package: str, table: Mapping[str, str]) -> Callable[[str], Any]:
    """A module ``__getattr__`` giving each name of ``table`` from its module on first use.

    Parameters
    ----------
    package
        The package's ``__name__``, for the error on an unknown attribute.
    table
        Exported name -> the module that defines it.
    """

    def __getattr__(name: str) -> Any:
        if name in table:
            return getattr(import_module(table[name]), name)
        raise AttributeError(f"module '{package}' has no attribute {name!r}")

    return __getattr__
