# SPDX-License-Identifier: Apache-2.0
"""The package's licence metadata: what a lab checks before it adopts the tool."""
from __future__ import annotations

import tomllib
from pathlib import Path

HOST = Path(__file__).resolve().parents[1]
REPO = HOST.parent


def test_licence_is_apache_2_and_the_packaged_text_is_the_repositorys() -> None:
    meta = tomllib.loads((HOST / "pyproject.toml").read_text())["project"]
    assert meta["license"] == "Apache-2.0"
    assert meta["license-files"] == ["LICENSE"]
    # The wheel carries host/LICENSE (a package cannot reach above its own folder): it must be
    # the repository's LICENSE, byte for byte.
    assert (HOST / "LICENSE").read_bytes() == (REPO / "LICENSE").read_bytes()
    assert b"Apache License" in (REPO / "LICENSE").read_bytes()[:200]
