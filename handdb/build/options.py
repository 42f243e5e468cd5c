"""The options of a build, checked before anything runs."""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

from handdb.gapfill import METHODS as GAP_FILLING
from handdb.lifting import METHODS as LIFTING


@dataclass(frozen=True)
class BuildOptions:
    """Parameters of a build that change what is computed for a clip.

    Attributes
    ----------
    gap_fill, lift
        Override the method every clip's sidecar asks for (``None``: the sidecar's
        choice, else the default method).
    export_usd
        Write each clip's USD animation and preview images into the database.
    compare
        Lifting methods validated beside the default ones on clips with ground truth (e.g.
        ``model-fit``, about a minute per clip).
    """

    gap_fill: str | None = None
    lift: str | None = None
    export_usd: bool = True
    compare: tuple[str, ...] = ()

    def check(self) -> BuildOptions:
        """Return the options if every method they name exists.

        Raises
        ------
        UnknownNameError
            Naming the method and listing the known ones, so that a mistake on the command
            line is reported before any clip is read (never blamed on a sidecar).
        """
        if self.gap_fill is not None:
            GAP_FILLING.check(self.gap_fill)
        for method in (*((self.lift,) if self.lift is not None else ()), *self.compare):
            LIFTING.check(method)
        return self

    def as_dict(self) -> dict[str, Any]:
        """The options as JSON-ready values (``compare`` as a list)."""
        values = asdict(self)
        values["compare"] = list(self.compare)
        return values
