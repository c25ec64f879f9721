# SPDX-License-Identifier: Apache-2.0
"""pma_golden: the independent double-precision reference of the firmware's algorithms
(pma_reference) and the golden-vector generator (gen_vectors); installed by tools/setup.sh
(the repository's pyproject.toml)."""
