# SPDX-License-Identifier: Apache-2.0
"""pma_tools: the repository's tools as importable modules (the repository's pyproject.toml
installs this folder under that name); each module still runs as a script."""
