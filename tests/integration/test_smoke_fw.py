# SPDX-License-Identifier: Apache-2.0
"""First contact: pma-fw-host starts on vcan0, answers, runs the loop in lockstep."""
from __future__ import annotations


def test_boot_arm_run_in_lockstep(firmware) -> None:
    fw, node = firmware(node=3)
    hb = node.heartbeat()
    assert node.proto.state_names[hb["State"]] == "IDLE"
    assert node.get("sys.node_id") == 0            # --node overrides, the parameter keeps its value
    act = node.exchange_sample(0, 2457)           # x = 0 cm at mid-scale counts
    assert act["OutputActive"] == 0 and act["DacCounts"] == 0   # IDLE: vent
    node.set("ref.kind", 0)
    node.set("ref.offset_cm", -1.0)
    assert node.arm().result == 0
    seq = 1
    for _ in range(50):
        act = node.exchange_sample(seq, 2457)
        seq += 1
    assert act["OutputActive"] == 1
    assert node.start().result == 0
    for _ in range(200):
        node.host_heartbeat()
        act = node.exchange_sample(seq, 2457)
        seq += 1
    hb = node.heartbeat()
    assert node.proto.state_names[hb["State"]] == "RUNNING", hb
    fw.stop()
