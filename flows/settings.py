"""Prefect settings handdb runs its flows with."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

from prefect.settings import PREFECT_FLOWS_HEARTBEAT_FREQUENCY, temporary_settings


@contextlib.contextmanager
def quick_flows() -> Iterator[None]:
    """Run flows without the heartbeat thread, whose join costs about 1 s per flow run."""
    with temporary_settings({PREFECT_FLOWS_HEARTBEAT_FREQUENCY: None}):
        yield
