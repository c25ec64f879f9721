"""Simulated PMA rig for the HIL harness (see docs/rig.md)."""
