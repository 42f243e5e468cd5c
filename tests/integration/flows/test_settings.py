"""Prefect settings for flows: one API for every process that runs tasks."""

import urllib.request

from handdb_flows.settings import shared_api
from prefect.settings import PREFECT_API_URL, temporary_settings


def test_shared_api_publishes_this_process_server_and_restores_the_settings():
    assert not PREFECT_API_URL.value()
    with shared_api() as api_url:
        assert PREFECT_API_URL.value() == api_url
        with urllib.request.urlopen(f"{api_url}/health", timeout=10) as response:
            assert response.status == 200
    assert not PREFECT_API_URL.value()


def test_shared_api_keeps_a_configured_server():
    configured = "http://prefect.example:4200/api"
    with temporary_settings({PREFECT_API_URL: configured}), shared_api() as api_url:
        assert api_url == configured
        assert PREFECT_API_URL.value() == configured
