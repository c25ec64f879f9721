# SPDX-License-Identifier: Apache-2.0
"""Parameter files across firmware versions: a file of another parameter table is mapped by
name (dropped, renamed, clamped, what the node lacks), a file of this table or of none recorded
is checked strictly, and sys.node_id is never copied unless asked."""
from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest
from fakenode import PROTO

from pmactl import paramfile
from pmactl.cli import EXIT_FILE, EXIT_OK
from pmactl.protocol import Protocol

OTHER = {"version": "0.1.0+deadbeef", "protocol_version": 2, "param_table_hash": "00000001"}


def doc(params: dict, firmware: dict | None = OTHER, units: dict | None = None) -> dict:
    d: dict = {"format": paramfile.FORMAT, "node": 2, "params": params}
    if firmware is not None:
        d["firmware"] = firmware
    if units is not None:
        d["units"] = units
    return d


def renamed_proto() -> Protocol:
    """pmactl's table with ppc.w1_cm once called ppc.accuracy_cm."""
    params = [dataclasses.replace(p, renamed_from=("ppc.accuracy_cm",)) if p.name == "ppc.w1_cm"
              else p for p in PROTO.params]
    return Protocol(db=PROTO.db, params=params)


def test_another_tables_file_is_mapped_by_name() -> None:
    proto = renamed_proto()
    d = doc({"ppc.accuracy_cm": 0.3, "ppc.t_u_s": 1e6, "gone.param": 4, "ctrl.mode": "WARP",
             "ppc.c": 3.0, "sys.node_id": 2},
            units={"ppc.c": "furlong"})
    plan = paramfile.plan("f.json", d, proto)
    assert not plan.same_table and plan.file_firmware == "0.1.0+deadbeef"
    assert plan.renamed == [("ppc.accuracy_cm", "ppc.w1_cm")]
    t_u = proto.param("ppc.t_u_s")
    assert plan.clamped == [(t_u, 1e6, t_u.max)]
    assert any(x.startswith("gone.param: not a parameter") for x in plan.dropped)
    assert any(x.startswith("ctrl.mode:") for x in plan.dropped)
    assert any(x.startswith("ppc.c: unit 'furlong'") for x in plan.dropped)
    assert plan.node_id_skipped
    sent = {p.name: v for p, v in plan.entries}
    assert sent == {"ppc.w1_cm": pytest.approx(0.3), "ppc.t_u_s": t_u.max}
    lacking = {p.name for p in plan.lacking}
    assert "ppc.a_cm_s" in lacking and "ppc.w1_cm" not in lacking and "sys.node_id" not in lacking
    assert [p.name for p, _ in paramfile.plan("f.json", d, proto, with_node_id=True).entries
            ].count("sys.node_id") == 1


@pytest.mark.parametrize("firmware", [None, {"param_table_hash": "SAME"}])
def test_a_file_of_this_table_or_of_none_is_strict(firmware: dict | None) -> None:
    if firmware is not None:
        firmware = {"param_table_hash": f"{paramfile.table_hash(PROTO):08x}"}
    with pytest.raises(paramfile.ParamFileError) as e:
        paramfile.plan("f.json", doc({"gone.param": 1, "ppc.t_u_s": 1e6}, firmware), PROTO)
    assert "unknown parameter 'gone.param'" in e.value.problems
    assert any("ppc.t_u_s" in p and "outside" in p for p in e.value.problems)


def test_pmactl_load_reports_the_mapping_and_dry_run_sends_nothing(pmactl, fake,
                                                                  tmp_path: Path) -> None:
    n = fake(node=2)
    path = tmp_path / "old.json"
    path.write_text(json.dumps(doc({"ppc.w1_cm": 0.3, "ppc.t_u_s": 1e6, "gone.param": 4,
                                    "sys.node_id": 5})))
    r = pmactl("--node", "2", "params", "load", "--dry-run", str(path))
    assert r.code == EXIT_OK, r.err
    assert "the file is of another firmware (0.1.0+deadbeef" in r.out
    assert "clamped ppc.t_u_s = 1000000.0 to" in r.out
    assert "dropped gone.param: not a parameter of this firmware" in r.out
    assert "not in the file (" in r.out
    assert "sys.node_id not loaded" in r.out
    assert "dry run: nothing sent" in r.out and n.sets() == []
    r = pmactl("--node", "2", "params", "load", str(path))
    assert r.code == EXIT_OK
    assert n.value("ppc.t_u_s") == PROTO.param("ppc.t_u_s").max
    assert n.value("sys.node_id") == 0                     # never copied
    assert all(s["Id"] != PROTO.param("sys.node_id").id for s in n.sets())


def test_a_bad_top_level_is_still_refused(pmactl, fake, tmp_path: Path) -> None:
    fake()
    path = tmp_path / "bad.json"
    d = doc({"ppc.w1_cm": 0.3})
    d["extra"] = 1
    path.write_text(json.dumps(d))
    r = pmactl("params", "load", str(path))
    assert r.code == EXIT_FILE and "unknown top-level entries extra" in r.err
