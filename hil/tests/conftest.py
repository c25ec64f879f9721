# SPDX-License-Identifier: Apache-2.0
"""Markers of the harness's tests (tools/run-tests.sh chooses by them and by file):

- slow: offline runs of whole scenarios (minutes); left out of `run-tests.sh --quick`
- vcan: needs vcan0 (run under hil/with-vcan); skipped without it
"""
from __future__ import annotations

import pytest


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line("markers", "slow: offline runs of whole scenarios (minutes); not in --quick")
    config.addinivalue_line("markers", "vcan: needs vcan0 (hil/with-vcan)")
