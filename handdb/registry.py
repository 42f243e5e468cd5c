"""Named entries of one kind: input formats, gap-filling methods, lifting methods.

Every registry of handdb is a :class:`Registry`, filled in one place (its package's
``__init__``), so what is registered never depends on which module happened to be
imported first. A name is registered once; asking for a name that is not there raises
:class:`~handdb.errors.UnknownNameError`, whose message lists the names that are.

>>> methods = Registry[str]("greeting")
>>> methods.add("hello", "Hello!")
'Hello!'
>>> methods["hello"]
'Hello!'
>>> "bye" in methods
False
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Generic, TypeVar

from handdb.errors import RegistryError, UnknownNameError

T = TypeVar("T")


class Registry(Generic[T]):
    """Entries of one ``kind`` by name, in the order they were added.

    Parameters
    ----------
    kind
        What an entry is, for messages (``"lifting method"``).
    """

    def __init__(self, kind: str) -> None:
        self.kind = kind
        self._entries: dict[str, T] = {}

    def add(self, name: str, entry: T) -> T:
        """Register ``entry`` under ``name`` and return it.

        Raises
        ------
        RegistryError
            If ``name`` is already registered.
        """
        if name in self._entries:
            raise RegistryError(f"{self.kind} '{name}' is registered twice")
        self._entries[name] = entry
        return entry

    def __getitem__(self, name: str) -> T:
        try:
            return self._entries[name]
        except KeyError:
            raise UnknownNameError(self.kind, name, self.names()) from None

    def __contains__(self, name: object) -> bool:
        return name in self._entries

    def __iter__(self) -> Iterator[str]:
        return iter(self._entries)

    def __len__(self) -> int:
        return len(self._entries)

    def names(self) -> tuple[str, ...]:
        """Registered names, in the order they were added."""
        return tuple(self._entries)

    def values(self) -> tuple[T, ...]:
        """Registered entries, in the order they were added."""
        return tuple(self._entries.values())

    def check(self, name: str) -> str:
        """Return ``name`` if it is registered, else raise :class:`UnknownNameError`."""
        self[name]
        return name
