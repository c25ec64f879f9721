# SPDX-License-Identifier: Apache-2.0
"""Simulated PMA rig for the HIL harness (see docs/rig.md)."""
