"""Prefect orchestration of handdb: thin flows over the library in ``handdb/``.

Importing this package sets Prefect defaults that must be in place before Prefect starts
(values already in the environment win): a start-up timeout long enough for the temporary
local server (13-17 s on a new database, measured), no analytics, a quiet server log,
and logs that reach the Prefect API from INFO while the terminal shows only warnings and
errors. Prefect's loggers take ``PREFECT_LOGGING_LEVEL``, and below it a record reaches no
handler at all (a WARNING there leaves every run's page saying "This run didn't generate
logs"); the console handler's own level (``PREFECT_LOGGING_HANDLERS_CONSOLE_LEVEL``, from
Prefect's ``logging.yml``) is what keeps the terminal quiet.
"""

import os

_PREFECT_DEFAULTS = {
    "PREFECT_SERVER_EPHEMERAL_STARTUP_TIMEOUT_SECONDS": "90",
    "PREFECT_SERVER_ANALYTICS_ENABLED": "false",
    "PREFECT_SERVER_LOGGING_LEVEL": "CRITICAL",
    "PREFECT_LOGGING_LEVEL": "INFO",
    "PREFECT_LOGGING_HANDLERS_CONSOLE_LEVEL": "WARNING",
}

for _name, _value in _PREFECT_DEFAULTS.items():
    os.environ.setdefault(_name, _value)
