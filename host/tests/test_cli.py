# SPDX-License-Identifier: Apache-2.0
"""Every pmactl command against fake nodes on python-can's virtual bus: its output, its
errors and its exit status (host/README.md lists them)."""
from __future__ import annotations

import csv
import json
import time
from pathlib import Path

import can
import pytest
from fakenode import PROTO, STATE, UNKNOWN_ID, wait_until

from pmactl import cli, paramfile
from pmactl.cli import EXIT_FILE, EXIT_INTERFACE, EXIT_NO_REPLY, EXIT_OK, EXIT_REFUSED, EXIT_USAGE, main


# ------------------------------------------------------------ bus, help, errors --
def test_help_lists_commands_and_exit_codes(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--help"]) == 0
    out = capsys.readouterr().out
    for cmd in ("scan", "status", "params", "arm", "disarm", "start", "stop", "estop", "clear-faults",
                "restart", "controller", "reference", "setpoint", "record", "plot", "monitor", "scope", "dbc"):
        assert cmd in out
    for code in ("0 ", "1 ", "2 ", "3 ", "4 ", "5 "):
        assert f"\n  {code}" in out
    assert main(["params", "--help"]) == 0
    assert "restore-defaults" in capsys.readouterr().out


def test_version_names_the_tool_and_the_protocol(capsys: pytest.CaptureFixture[str]) -> None:
    import importlib.metadata
    assert main(["--version"]) == EXIT_OK
    out = capsys.readouterr().out.strip()
    assert out == (f"pmactl {importlib.metadata.version('pmactl')} "
                   f"(protocol {PROTO.version}, DBC VERSION \"{PROTO.db.version}\")")
    header = (Path(__file__).resolve().parents[2] / "firmware/protocol/generated/pma_proto_version.h")
    assert f"#define PMA_PROTO_VERSION {PROTO.version}u" in header.read_text()
    repo_version = (Path(__file__).resolve().parents[2] / "VERSION").read_text().strip()
    assert importlib.metadata.version("pmactl") == repo_version


def test_bad_command_line_is_exit_2(pmactl) -> None:
    for args in (["frobnicate"], ["params"], ["--node", "16", "status"], ["--timeout", "-1", "status"],
                 ["setpoint", "nan"], ["record"], ["scan", "--seconds", "zero"]):
        r = pmactl(*args)
        assert r.code == EXIT_USAGE, args
        assert "error" in r.err


def test_no_interface_is_exit_3(pmactl) -> None:
    # an interface name python-can does not have is a bad value (exit 2), with the valid ones
    r = pmactl("--interface", "no-such-interface", "status", bus=False)
    assert r.code == EXIT_USAGE
    assert "no-such-interface" in r.err and "python-can knows" in r.err
    # socketcan on a channel that does not exist (or a kernel without SocketCAN): python-can
    # raises on open
    r = pmactl("--interface", "socketcan", "--channel", "pmactl-none0", "status", bus=False)
    assert r.code == EXIT_INTERFACE
    assert "cannot open CAN interface socketcan pmactl-none0" in r.err


def test_no_reply_is_exit_4(pmactl, fake) -> None:
    r = pmactl("status")                                   # nobody on the bus
    assert r.code == EXIT_NO_REPLY
    assert "no HEARTBEAT from node 0 within 3 s" in r.err
    fake(answer=False)                                     # heartbeats, but no replies
    r = pmactl("params", "get", "ppc.w1_cm")
    assert r.code == EXIT_NO_REPLY and "no PARAM_RESP from node 0" in r.err
    r = pmactl("arm")
    assert r.code == EXIT_NO_REPLY and "no COMMAND_ACK from node 0" in r.err
    r = pmactl("--node", "3", "status")                    # another node id: nobody answers
    assert r.code == EXIT_NO_REPLY and "node 3" in r.err


def test_global_options_after_the_command(pmactl, fake) -> None:
    fake(node=4)
    r = pmactl("status", "--node", "4")
    assert r.code == EXIT_OK and "node 4" in r.out


def test_env_config_is_honoured(fake, channel, monkeypatch, capsys) -> None:
    fake()
    monkeypatch.setenv("CAN_INTERFACE", "virtual")
    monkeypatch.setenv("CAN_CHANNEL", channel)
    assert main(["status"]) == EXIT_OK
    assert f"node 0 on virtual {channel}" in capsys.readouterr().out


def test_canrc_is_honoured(fake, channel, capsys) -> None:
    import os
    fake()
    Path(os.environ["HOME"], ".canrc").write_text(f"[default]\ninterface = virtual\nchannel = {channel}\n")
    assert main(["status"]) == EXIT_OK
    assert f"virtual {channel}" in capsys.readouterr().out
    # the command line wins over the file
    assert main(["--channel", "elsewhere", "--timeout", "0.3", "status"]) == EXIT_NO_REPLY


# ------------------------------------------------------------------ scan, status --
def test_scan_lists_every_node(pmactl, fake) -> None:
    fake(node=0)
    b = fake(node=5)
    b.set_state("FAULT", "SENSOR_TIMEOUT")
    r = pmactl("scan", "--seconds", "1.0")              # 20 heartbeat periods of the fakes
    assert r.code == EXIT_OK
    lines = r.out.splitlines()
    assert lines[0].split() == ["node", "state", "fault", "controller", "reference", "firmware",
                                "unique", "id", "flags"]
    assert lines[1].split()[:5] == ["0", "IDLE", "NONE", "PPC", "HOLD"]
    assert lines[2].split()[:5] == ["5", "FAULT", "SENSOR_TIMEOUT", "PPC", "HOLD"]
    assert "2 node(s)" in lines[-1]


def test_scan_without_nodes_is_exit_4(pmactl) -> None:
    r = pmactl("scan", "--seconds", "0.2")
    assert r.code == EXIT_NO_REPLY and "no node heartbeat" in r.err


def test_status_decodes_everything(pmactl, fake) -> None:
    n = fake()
    n.set_state("FAULT", "POSITION_LIMIT")
    r = pmactl("status")
    assert r.code == EXIT_OK
    assert "state        FAULT" in r.out
    assert "fault        POSITION_LIMIT (2)" in r.out
    assert "flags        0x0052 PLANT_BRIDGE PARAMS_DEFAULT SENSOR_VALID" in r.out
    assert "controller   PPC (1)" in r.out
    assert "reference    HOLD (0)" in r.out
    assert "reset cause  POWER_ON (1)" in r.out


# ---------------------------------------------------------------------- counters --
def test_counters_reads_every_status_value_by_name(pmactl, fake) -> None:
    n = fake(status_values={"LAST_RULE": 12, "RX_OVERRUNS": 0, "RX_DEFERRED": 0, "RX_DROPPED": 3,
                            "FRAMES_BAD": 0, "TICKS": 98765, "FRAMES_RX": 56, "GUARANTEE_LOST_TICKS": 77,
                            "GUARANTEE_LOST_AT_MS": 4321, "BARRIER_BREACHES": 5})
    r = pmactl("counters")
    assert r.code == EXIT_OK, r.err
    rows = {line.split()[0]: line.split(None, 1)[1] for line in r.out.splitlines() if line.strip()}
    assert list(rows) == ["LAST_RULE", "RX_OVERRUNS", "RX_DEFERRED", "RX_DROPPED", "FRAMES_BAD", "TICKS",
                          "FRAMES_RX", "GUARANTEE_LOST_TICKS", "GUARANTEE_LOST_AT_MS", "BARRIER_BREACHES"]
    assert rows["TICKS"] == "98765" and rows["RX_DROPPED"] == "3"
    assert rows["LAST_RULE"].startswith("rule 12")
    assert rows["GUARANTEE_LOST_TICKS"] == "77" and rows["GUARANTEE_LOST_AT_MS"] == "4321 ms after START"
    n.status_values["GUARANTEE_LOST_AT_MS"] = 0xFFFFFFFF
    r = pmactl("counters", "guarantee_lost_at_ms", "TICKS")
    assert r.code == EXIT_OK
    assert r.out.split() == ["GUARANTEE_LOST_AT_MS", "never", "(the", "guarantee", "holds)", "TICKS", "98765"]


def test_counters_refuses_an_unknown_name_before_sending(pmactl, fake) -> None:
    n = fake()
    before = sum(1 for name, _ in n.received if name == "PARAM_REQ")
    r = pmactl("counters", "TICKS", "NO_SUCH_COUNTER")
    assert r.code == EXIT_USAGE and "no status value NO_SUCH_COUNTER" in r.err
    assert sum(1 for name, _ in n.received if name == "PARAM_REQ") == before


def test_counters_of_a_node_without_get_status(pmactl, fake) -> None:
    fake(status_values=None)            # firmware before GET_STATUS: UNKNOWN_COMMAND
    r = pmactl("counters", "TICKS")
    assert r.code == EXIT_REFUSED and "UNKNOWN_COMMAND" in r.err


# ------------------------------------------------------------------------ params --
def test_params_list_shows_what_the_node_reports(pmactl, fake) -> None:
    fake(overrides={"ppc.w1_cm": {"max": 50.0}})            # the node's range, not the table's
    r = pmactl("params", "list")
    assert r.code == EXIT_OK
    rows = {line.split()[1]: line.split() for line in r.out.splitlines()[1:] if line[:1] == " " or line[:1].isdigit()}
    assert rows["ppc.w1_cm"][2:8] == ["0.2", "cm", "0.0001", "50", "0.2", "stopped"]
    assert rows["ctrl.mode"][2:8] == ["PPC", "-", "OFF", "OPEN_LOOP", "PPC", "stopped"]
    assert rows["safety.host_timeout_ms"][3] == "ms"
    assert rows[f"#{UNKNOWN_ID}"][3] == "?"
    assert "unknown to this pmactl" in r.out
    r = pmactl("params", "list", "ppc")
    names = [line.split()[1] for line in r.out.splitlines()[1:]]
    assert names == ["ppc.w1_cm", "ppc.t_u_s"]
    r = pmactl("params", "list", "*.x_m*_cm")
    assert [line.split()[1] for line in r.out.splitlines()[1:]] == ["safety.x_min_cm", "safety.x_max_cm"]
    assert pmactl("params", "list", "nosuchgroup").code == EXIT_USAGE


def test_params_list_marks_changed_values(pmactl, fake) -> None:
    fake()
    assert pmactl("params", "set", "ppc.t_u_s", "6").code == EXIT_OK
    r = pmactl("params", "list", "ppc.t_u_s")
    assert r.out.splitlines()[1].split()[2] == "6*"


def test_params_get(pmactl, fake) -> None:
    fake()
    r = pmactl("params", "get", "ctrl.mode", "ppc.w1_cm", "act.polarity", "36")
    assert r.code == EXIT_OK
    assert r.out.splitlines() == ["ctrl.mode = PPC (1)", "ppc.w1_cm = 0.2 cm", "act.polarity = 1",
                                  "ppc.t_u_s = 2 s"]
    r = pmactl("params", "get", "ppc.w1")
    assert r.code == EXIT_USAGE and "did you mean ppc.w1_cm" in r.err
    r = pmactl("params", "get", "ppc.a_cm_s")                # in the table, not on this node
    assert r.code == EXIT_REFUSED and "UNKNOWN_ID (-18)" in r.err


def test_params_set(pmactl, fake) -> None:
    n = fake()
    r = pmactl("params", "set", "ppc.w1_cm", "0.3")
    assert r.code == EXIT_OK and r.out.strip() == "ppc.w1_cm = 0.3 cm (was 0.2)"
    assert n.value("ppc.w1_cm") == pytest.approx(0.3)
    r = pmactl("params", "set", "ctrl.mode", "mfac")                   # enumerations by name
    assert r.code == EXIT_OK and r.out.strip() == "ctrl.mode = MFAC (was PPC)"
    assert pmactl("params", "set", "ref.kind", "3").code == EXIT_OK    # or by number
    assert n.value("ref.kind") == 3


def test_params_set_bad_values_send_nothing(pmactl, fake) -> None:
    n = fake()
    for args, msg in ((("ppc.w1_cm", "300"), "outside 0.0001..100 cm"),
                      (("ppc.w1_cm", "nan"), "not finite"),
                      (("ppc.w1_cm", "wide"), "is not a number"),
                      (("ctrl.mode", "FAST"), "one of OFF, PPC, MFAC, PID, OPEN_LOOP"),
                      (("telem.mask", "2.5"), "not an unsigned integer"),
                      (("telem.mask", "-1"), "outside 0..31"),
                      (("nosuch.param", "1"), "unknown parameter")):
        r = pmactl("params", "set", *args)
        assert r.code == EXIT_USAGE, args
        assert msg in r.err, (args, r.err)
    time.sleep(0.05)
    assert n.sets() == []


def test_params_set_rejected_by_the_node(pmactl, fake) -> None:
    n = fake()
    assert pmactl("arm").code == EXIT_OK
    r = pmactl("params", "set", "act.p0_kpa", "250")      # access idle, node ARMED
    assert r.code == EXIT_REFUSED
    assert "node 0 rejected set act.p0_kpa = 250: STATE (-20)" in r.err
    assert "act.p0_kpa stays 300" in r.err
    assert n.value("act.p0_kpa") == 300
    # --no-check leaves the checks to the node: its codes come back
    r = pmactl("params", "set", "--no-check", "ppc.w1_cm", "300")
    assert r.code == EXIT_REFUSED and "RANGE (-3)" in r.err
    r = pmactl("params", "set", "--no-check", "ppc.w1_cm", "nan")
    assert r.code == EXIT_REFUSED and "NOT_FINITE (-2)" in r.err
    r = pmactl("params", "set", "--no-check", "telem.mask", "-1")   # cannot be encoded as u32
    assert r.code == EXIT_USAGE


def test_params_save_restore_revert(pmactl, fake) -> None:
    n = fake(storage=False)
    r = pmactl("params", "save")
    assert r.code == EXIT_REFUSED and "NOT_IMPLEMENTED (-8)" in r.err
    n.storage = True
    r = pmactl("params", "revert")
    assert r.code == EXIT_REFUSED and "NO_RECORD (-15)" in r.err
    assert pmactl("params", "set", "ppc.t_u_s", "6").code == EXIT_OK
    assert pmactl("params", "save").code == EXIT_OK
    assert pmactl("params", "restore-defaults").code == EXIT_OK
    assert n.value("ppc.t_u_s") == 2
    r = pmactl("params", "revert")
    assert r.code == EXIT_OK and "loaded from storage" in r.out
    assert n.value("ppc.t_u_s") == 6
    assert pmactl("arm").code == EXIT_OK
    r = pmactl("params", "save")
    assert r.code == EXIT_REFUSED and "STATE (-20)" in r.err


# ------------------------------------------------------------- parameter files --
def test_dump_and_load_json(pmactl, fake, tmp_path: Path) -> None:
    n = fake()
    path = tmp_path / "p.json"
    r = pmactl("params", "dump", str(path))
    assert r.code == EXIT_OK and f"16 parameters of node 0 written to {path}" in r.out
    doc = json.loads(path.read_text())
    assert doc["format"] == "pmactl-params 1" and doc["node"] == 0
    assert doc["params"]["ctrl.mode"] == "PPC"
    assert doc["params"]["ppc.w1_cm"] == 0.2            # shortest text of the single
    assert doc["units"]["ppc.w1_cm"] == "cm"
    assert f"#{UNKNOWN_ID}" not in doc["params"]
    assert doc["firmware"]["param_table_hash"] == f"{paramfile.table_hash(PROTO):08x}"
    # nothing differs: nothing sent (sys.node_id is never loaded unless asked)
    r = pmactl("params", "load", str(path))
    assert r.code == EXIT_OK and "0 set, 15 unchanged, 0 rejected" in r.out
    assert "sys.node_id not loaded (--with-node-id loads it)" in r.out
    r = pmactl("params", "load", "--with-node-id", str(path))
    assert r.code == EXIT_OK and "0 set, 16 unchanged, 0 rejected" in r.out
    assert n.sets() == []
    doc["params"]["ppc.w1_cm"] = 0.3
    doc["params"]["ctrl.mode"] = "MFAC"
    path.write_text(json.dumps(doc))
    r = pmactl("params", "load", "--dry-run", str(path))
    assert r.code == EXIT_OK and "would set ctrl.mode = MFAC (now PPC)" in r.out and n.sets() == []
    r = pmactl("params", "load", str(path))
    assert r.code == EXIT_OK
    assert "set ctrl.mode = MFAC (was PPC)" in r.out and "set ppc.w1_cm = 0.3 cm (was 0.2)" in r.out
    assert "2 set, 13 unchanged, 0 rejected" in r.out
    assert n.value("ctrl.mode") == 2
    r = pmactl("params", "load", "--send-all", str(path))
    assert "15 set" in r.out


def test_dump_to_stdout(pmactl, fake) -> None:
    fake()
    r = pmactl("params", "dump", "-")
    assert r.code == EXIT_OK
    assert json.loads(r.out)["params"]["ref.kind"] == "HOLD"


def test_load_reports_each_rejected_set(pmactl, fake, tmp_path: Path) -> None:
    n = fake()
    assert pmactl("arm").code == EXIT_OK
    path = tmp_path / "p.json"
    path.write_text(json.dumps({"params": {"act.p0_kpa": 250, "safety.x_min_cm": -2.5, "ppc.t_u_s": 6}}))
    r = pmactl("params", "load", str(path))
    assert r.code == EXIT_REFUSED
    assert "rejected set act.p0_kpa = 250: STATE (-20)" in r.err
    assert "rejected set safety.x_min_cm = -2.5: STATE (-20)" in r.err
    assert "set ppc.t_u_s = 6 s (was 2)" in r.out                 # the others are still sent
    assert "1 set, 0 unchanged, 2 rejected" in r.out
    assert n.value("ppc.t_u_s") == 6


@pytest.mark.parametrize("content, problems", [
    ("{not json", ["not valid JSON"]),
    ("[1, 2]", ["not a mapping"]),
    ('{"params": 3}', ["no 'params' mapping"]),
    ('{"format": "other 2", "params": {}}', ["format 'other 2'"]),
    ('{"params": {"ppc.w1_cm": 300, "nosuch": 1, "ctrl.mode": "FAST", "telem.mask": true, '
     '"ppc.t_u_s": 6}, "units": {"ppc.t_u_s": "ms"}, "extra": 1}',
     ["ppc.w1_cm: 300 cm is outside 0.0001..100 cm", "unknown parameter 'nosuch'",
      "ctrl.mode: 'FAST' is not one of", "telem.mask: True is not", "ppc.t_u_s: unit 'ms' in the file",
      "unknown top-level entries extra"]),
])
def test_load_bad_file_sends_nothing(pmactl, fake, tmp_path: Path, content: str, problems: list[str]) -> None:
    n = fake()
    path = tmp_path / "bad.json"
    path.write_text(content)
    r = pmactl("params", "load", str(path))
    assert r.code == EXIT_FILE, r.err
    assert "bad file (nothing sent)" in r.err
    for problem in problems:
        assert problem in r.err, (problem, r.err)
    time.sleep(0.05)
    assert n.sets() == []
    assert n.value("ppc.t_u_s") == 2


def test_load_missing_or_unknown_file_type(pmactl, fake, tmp_path: Path) -> None:
    fake()
    r = pmactl("params", "load", str(tmp_path / "none.json"))
    assert r.code == EXIT_FILE and "cannot read" in r.err
    r = pmactl("params", "load", str(tmp_path / "p.ini"))
    assert r.code == EXIT_FILE and "unknown file type '.ini'" in r.err
    # a file that cannot be written: refused before the node is read (as record, dbc, scope)
    r = pmactl("params", "dump", str(tmp_path / "no-dir" / "p.json"))
    assert r.code == EXIT_USAGE and "directory" in r.err and "does not exist" in r.err


def test_yaml_files(pmactl, fake, tmp_path: Path) -> None:
    from pmactl import paramfile
    fake()
    path = tmp_path / "p.yaml"
    if not paramfile.yaml_available():
        r = pmactl("params", "dump", str(path))
        assert r.code == EXIT_FILE and "YAML needs PyYAML" in r.err
        return
    assert pmactl("params", "dump", str(path)).code == EXIT_OK
    assert "ppc.w1_cm: 0.2" in path.read_text()
    path.write_text(path.read_text().replace("ppc.w1_cm: 0.2", "ppc.w1_cm: 0.25"))
    r = pmactl("params", "load", str(path))
    assert r.code == EXIT_OK and "set ppc.w1_cm = 0.25 cm" in r.out


# ---------------------------------------------------------------------- commands --
def test_state_commands(pmactl, fake) -> None:
    n = fake()
    r = pmactl("arm")
    assert r.code == EXIT_OK and r.out.strip() == "node 0: ARM OK, state ARMED"
    r = pmactl("start")
    assert r.code == EXIT_OK and r.out.splitlines()[0] == "node 0: START OK, state RUNNING"
    assert "HOST_HEARTBEAT_LOST" in r.out and "500 ms" in r.out       # the warning
    r = pmactl("stop")
    assert r.code == EXIT_OK and r.out.strip() == "node 0: STOP OK, state ARMED"
    r = pmactl("disarm")
    assert r.code == EXIT_OK and r.out.strip() == "node 0: DISARM OK, state IDLE"
    r = pmactl("stop")
    assert r.code == EXIT_REFUSED
    assert r.err.strip() == ("pmactl: error: node 0 refused STOP: STATE (-20): not allowed in the "
                             "node's current state (see the parameter's access class)")
    n.set_state("FAULT", "SENSOR_RANGE")
    r = pmactl("arm")
    assert r.code == EXIT_REFUSED and "FAULT (-23): refused because a fault is latched" in r.err
    r = pmactl("clear-faults")
    assert r.code == EXIT_OK and r.out.strip() == "node 0: CLEAR_FAULTS OK, state IDLE"


def test_arm_without_sensor_sample(pmactl, fake) -> None:
    fake(sensor=False)
    r = pmactl("arm")
    assert r.code == EXIT_REFUSED
    assert "refused ARM: NOT_READY (-5): no position yet" in r.err


def test_estop(pmactl, fake) -> None:
    n = fake()
    r = pmactl("estop")
    assert r.code == EXIT_OK and r.out.strip() == "node 0: ESTOP sent, state FAULT (ESTOP)"
    assert ("ESTOP", {}) in n.received


def test_restart_waits_for_the_node_and_says_what_was_lost(pmactl, fake) -> None:
    n = fake(storage=True)
    assert pmactl("params", "set", "ppc.w1_cm", "0.5").code == EXIT_OK   # not saved
    r = pmactl("restart")
    assert r.code == EXIT_OK, r.err
    assert "node 0: restarted in" in r.out and "IDLE, reset cause SOFTWARE" in r.out
    assert "unsaved parameter changes discarded" in r.out
    assert n.value("ppc.w1_cm") == pytest.approx(0.2) and n.reset_cause == 3         # the default again


def test_restart_refused_with_the_output_active_sends_nothing(pmactl, fake) -> None:
    n = fake()
    n.set_state("ARMED")
    r = pmactl("restart")
    assert r.code == EXIT_REFUSED and "node 0 is ARMED: disarm it first" in r.err
    assert not [m for m, _ in n.received if m == "COMMAND"]
    assert n.state == STATE["ARMED"]


def test_estop_all(pmactl, fake) -> None:
    a, b = fake(node=0), fake(node=9)
    b.set_state("ARMED")
    r = pmactl("estop", "--all")
    assert r.code == EXIT_OK
    assert "node 0: FAULT (ESTOP)" in r.out and "node 9: FAULT (ESTOP)" in r.out
    assert "ESTOP_ALL sent: 2 node(s) in FAULT" in r.out
    assert ("ESTOP_ALL", {}) in a.received and ("ESTOP_ALL", {}) in b.received


def test_estop_unconfirmed_is_exit_4(pmactl, fake) -> None:
    fake(heartbeats=False)
    r = pmactl("estop")
    assert r.code == EXIT_NO_REPLY


def test_controller_and_reference(pmactl, fake) -> None:
    n = fake()
    r = pmactl("controller", "pid")
    assert r.code == EXIT_OK and r.out.strip() == "node 0: controller PID (at the next START), state IDLE"
    assert n.value("ctrl.mode") == 3
    r = pmactl("reference", "CASE3")
    assert r.code == EXIT_OK and n.value("ref.kind") == 5
    r = pmactl("controller")
    assert r.out.strip() == "controller PID (ctrl.mode; one of OFF, PPC, MFAC, PID, OPEN_LOOP)"
    r = pmactl("reference", "square")
    assert r.code == EXIT_USAGE and "HOLD, STEP, RAMP, SINE, CASE1, CASE3, STREAM" in r.err
    n.set_state("RUNNING")
    r = pmactl("controller", "mfac")
    assert r.code == EXIT_REFUSED and "refused SELECT_CONTROLLER: STATE (-20)" in r.err


def test_setpoint(pmactl, fake) -> None:
    n = fake()
    r = pmactl("setpoint", "-1.2")
    assert r.code == EXIT_REFUSED and "IDLE with reference HOLD" in r.err
    assert n.setpoints == []
    n.rows[PROTO.param("ref.kind").id].value = 6          # STREAM
    n.set_state("RUNNING")
    r = pmactl("setpoint", "-4")
    assert r.code == EXIT_USAGE and "outside the constraint band (-3, 0) cm" in r.err
    r = pmactl("setpoint", "-1.25")
    assert r.code == EXIT_OK and r.out.strip() == "node 0: set-point -1.25 cm sent"
    assert wait_until(lambda: n.setpoints == [-1.25]), n.setpoints


# ------------------------------------------------------------------- record, plot --
def _read_csv(path: Path) -> tuple[list[str], list[list[str]]]:
    with path.open() as f:
        rows = list(csv.reader(f))
    return rows[0], rows[1:]


def test_record_running_node(pmactl, fake, tmp_path: Path) -> None:
    n = fake()
    n.set_state("RUNNING")
    out = tmp_path / "run.csv"
    # 80 telemetry ticks: longer than safety.host_timeout_ms (500 ms = 50 ticks of the fake)
    r = pmactl("record", str(out), "--samples", "80", "--quiet")
    assert r.code == EXIT_OK, r.err
    header, rows = _read_csv(out)
    assert header == ["t [s]", "x [cm]", "xr [cm]", "e [cm]", "u [input unit]", "v [cm/s]",
                      "lambda1 [cm]", "lambda2 [cm/s]", "p [kPa]", "ctrl_flags [-]", "breaches [-]",
                      "rx_time [s]"]
    assert len(rows) == 80
    for row in rows:
        assert all(cell != "" for cell in row), row                # every group complete
        x, xr, e = float(row[1]), float(row[2]), float(row[3])
        assert e == pytest.approx(x - xr, abs=1e-6)               # the frames of one tick
    times = [float(row[0]) for row in rows]
    assert times == sorted(times)
    assert "recorded 80 rows" in r.out and "80 samples recorded" in r.out and "lost rows 0" in r.out
    # the host heartbeat kept the node RUNNING past safety.host_timeout_ms
    assert n.host_heartbeats >= 1 and n.state == 3
    # the frame log: a python-can BLF file with the telemetry and our host heartbeats
    log = tmp_path / "run.blf"
    msgs = list(can.BLFReader(str(log)))
    ids = {m.arbitration_id for m in msgs}
    assert PROTO.frame_id("TELEM_A", 0) in ids and PROTO.frame_id("HOST_HEARTBEAT", 0) in ids
    meta = json.loads((tmp_path / "run.meta.json").read_text())
    assert meta["controller"] == "PPC" and meta["params"]["ppc.w1_cm"] == pytest.approx(0.2)
    assert meta["units"]["ppc.w1_cm"] == "cm"
    assert meta["summary"]["rows"] == len(rows)


def test_record_start_asc_log_and_samples(pmactl, fake, tmp_path: Path) -> None:
    n = fake()
    n.set_state("ARMED")
    out = tmp_path / "run.csv"
    r = pmactl("record", str(out), "--start", "--samples", "15", "--log", str(tmp_path / "run.asc"), "-q")
    assert r.code == EXIT_OK, r.err
    _, rows = _read_csv(out)
    assert len(rows) == 15
    assert float(rows[0][0]) == pytest.approx(0.01)              # from the first tick after START
    assert "15 samples recorded" in r.out
    msgs = list(can.ASCReader(str(tmp_path / "run.asc")))
    assert any(m.arbitration_id == PROTO.frame_id("COMMAND", 0) for m in msgs)
    assert wait_until(lambda: n.state == 2)                      # STOP at the end: ARMED again


def test_record_mask_leaves_cells_empty(pmactl, fake, tmp_path: Path) -> None:
    n = fake()
    n.rows[PROTO.param("telem.mask").id].value = 0b00011        # TELEM_A and TELEM_B only
    n.set_state("RUNNING")
    out = tmp_path / "run.csv"
    assert pmactl("record", str(out), "--samples", "20", "--no-log", "-q").code == EXIT_OK
    _, rows = _read_csv(out)
    assert rows and all(row[4] == "" and row[1] != "" and row[3] != "" for row in rows)
    assert not (tmp_path / "run.blf").exists()


def test_record_errors(pmactl, fake, tmp_path: Path) -> None:
    out = str(tmp_path / "run.csv")
    r = pmactl("record", out, "--log", str(tmp_path / "x.txt"))
    assert r.code == EXIT_USAGE and ".blf, .asc or .log" in r.err
    r = pmactl("record", str(tmp_path / "nodir" / "run.csv"))
    assert r.code == EXIT_USAGE and "does not exist" in r.err
    n = fake()
    r = pmactl("record", out, "--seconds", "0.2")
    assert r.code == EXIT_REFUSED and "node 0 is IDLE, not RUNNING" in r.err
    r = pmactl("record", out, "--start", "--seconds", "0.2")
    assert r.code == EXIT_REFUSED and "not ARMED" in r.err
    n.rows[PROTO.param("telem.decimation").id].value = 0
    n.set_state("RUNNING")
    r = pmactl("record", out, "--seconds", "0.2")
    assert r.code == EXIT_REFUSED and "telem.decimation = 0" in r.err


def test_record_without_telemetry_is_exit_4(pmactl, fake, tmp_path: Path) -> None:
    n = fake(telem_s=10.0)                       # RUNNING, but the first telemetry is 10 s away
    n.set_state("RUNNING")
    n.telem_ticks = 0
    r = pmactl("record", str(tmp_path / "r.csv"), "--seconds", "3", "-q")
    assert r.code == EXIT_NO_REPLY and "no telemetry from node 0" in r.err
    n.set_state("ARMED")                         # --start: the node is stopped again
    r = pmactl("record", str(tmp_path / "r.csv"), "--start", "--seconds", "3", "-q")
    assert r.code == EXIT_NO_REPLY
    assert wait_until(lambda: n.state == 2)


def test_record_stops_when_the_node_faults(pmactl, fake, tmp_path: Path) -> None:
    n = fake()
    n.set_state("ARMED")
    out = tmp_path / "run.csv"
    # without host heartbeats the node faults after safety.host_timeout_ms (500 ms: the fake
    # counts 50 telemetry ticks of 10 ms from START, however slow the machine)
    r = pmactl("record", str(out), "--start", "--seconds", "30", "--no-host-heartbeat", "-q")
    assert r.code == EXIT_REFUSED, r.out + r.err
    assert "node 0 left RUNNING: FAULT (HOST_HEARTBEAT_LOST)" in r.out
    assert n.host_heartbeats == 0
    _, rows = _read_csv(out)
    assert len(rows) == 50
    # a node that faults before its first telemetry row is still "left RUNNING" (exit 1),
    # not "no telemetry" (exit 4)
    n.set_state("ARMED")
    n.wire_break_at_tick = 0
    r = pmactl("record", str(out), "--start", "--seconds", "30", "-q")
    assert r.code == EXIT_REFUSED, r.out + r.err
    assert "recorded 0 rows" in r.out and "left RUNNING: FAULT (SENSOR_WIRE_BREAK)" in r.out


def test_record_progress_display(pmactl, fake, tmp_path: Path) -> None:
    n = fake()
    n.set_state("RUNNING")
    r = pmactl("record", str(tmp_path / "run.csv"), "--seconds", "1.2")
    assert r.code == EXIT_OK
    assert "recording" in r.err and "rows" in r.err and "x -1." in r.err


def test_plot(pmactl, fake, tmp_path: Path) -> None:
    n = fake()
    n.set_state("RUNNING")
    out = tmp_path / "run.csv"
    assert pmactl("record", str(out), "--samples", "40", "-q").code == EXIT_OK
    r = pmactl("plot", str(out), bus=False)
    assert r.code == EXIT_OK, r.err
    written = [Path(line) for line in r.out.splitlines() if line.endswith(".png")]
    assert [p.name for p in written] == ["run.png", "run_a_position.png", "run_b_error.png",
                                         "run_c_velocity.png", "run_d_input.png", "run_e_pressure.png"]
    for p in written:
        assert p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # the numbers, with w1 and t_u from run.meta.json (PPC defaults: 0.2 cm, 2 s)
    assert "|e| < w1 = 0.2 cm from t = " in r.out and "(t_u = 2 s)" in r.out
    assert "over t >= t_u = 2 s: max |e| -" in r.out          # the recording is shorter than t_u
    assert "barrier clamps (breaches) 0" in r.out
    r = pmactl("plot", str(out), "--out", str(tmp_path / "fig" / "case"), "--w1", "0.3",
               "--band", "-3", "0", "--t-u", "0.1", "--no-meta", "--no-panels", bus=False)
    assert r.code == EXIT_OK and (tmp_path / "fig" / "case.png").exists()
    assert not (tmp_path / "fig" / "case_b_error.png").exists()
    assert "|e| < w1 = 0.3 cm from t = " in r.out and "over t >= t_u = 0.1 s: max |e| 0." in r.out


def test_plot_bad_file_is_exit_5(pmactl, tmp_path: Path) -> None:
    bad = tmp_path / "bad.csv"
    bad.write_text("a,b,c\n1,2,3\n")
    r = pmactl("plot", str(bad), bus=False)
    assert r.code == EXIT_FILE and "3 columns" in r.err
    r = pmactl("plot", str(tmp_path / "none.csv"), bus=False)
    assert r.code == EXIT_FILE and "cannot read" in r.err
    from pmactl.recording import header_row
    empty = tmp_path / "empty.csv"
    empty.write_text(",".join(header_row()) + "\n")
    r = pmactl("plot", str(empty), bus=False)
    assert r.code == EXIT_FILE and "no rows" in r.err
    garbage = tmp_path / "garbage.csv"
    garbage.write_text(",".join(header_row()) + "\n" + ",".join(["x"] * 12) + "\n")
    r = pmactl("plot", str(garbage), bus=False)
    assert r.code == EXIT_FILE


# ----------------------------------------------------------------------- monitor --
def wait_monitor_sees(bus: can.BusABC, nodes: tuple[int, ...]) -> None:
    """Returns once a `pmactl monitor --host-heartbeat` is up (its HOST_HEARTBEAT to node 0 is
    on the bus) and has had a heartbeat of every node since: tests act on that, never on a
    timer (a loaded machine may take longer than any sleep to start the monitor)."""
    for wanted in (PROTO.frame_id("HOST_HEARTBEAT", 0), *(PROTO.frame_id("HEARTBEAT", n) for n in nodes)):
        while (m := bus.recv(10.0)) is not None and m.arbitration_id != wanted:
            pass


def test_monitor(pmactl, fake, channel) -> None:
    import threading
    a = fake(node=0)
    b = fake(node=2)
    bus = can.Bus(interface="virtual", channel=channel)

    def later() -> None:
        wait_monitor_sees(bus, (0, 2))
        a.set_state("FAULT", "SENSOR_WIRE_BREAK")
        wait_monitor_sees(bus, (0,))
        b.heartbeats = False

    t = threading.Thread(target=later, daemon=True)
    t.start()
    # --seconds (wall time): room for node 2's silence (--silent-after) to be noticed
    r = pmactl("monitor", "--seconds", "3", "--silent-after", "0.4", "--host-heartbeat")
    t.join()
    bus.shutdown()
    assert r.code == EXIT_OK
    lines = r.out.splitlines()
    assert lines[0].startswith("watching virtual")
    text = "\n".join(lines)
    assert "node 0   IDLE, controller PPC, reference HOLD, flags PLANT_BRIDGE" in text
    assert "node 2   IDLE" in text
    assert "node 0   FAULT SENSOR_WIRE_BREAK (4)" in text
    assert "node 0   state IDLE -> FAULT" in text
    assert "node 2   silent: no heartbeat for" in text
    assert lines[-1] == "2 node(s) seen: 0 FAULT (SENSOR_WIRE_BREAK), 2 IDLE"


def test_monitor_host_heartbeat_keeps_a_node_running(pmactl, fake) -> None:
    n = fake()
    n.set_state("RUNNING")
    r = pmactl("monitor", "--seconds", "0.8", "--host-heartbeat")
    assert r.code == EXIT_OK
    assert n.state == 3 and n.host_heartbeats >= 1
    # without them the node faults (the fake: 50 telemetry ticks after the last one)
    assert wait_until(lambda: n.state == STATE["FAULT"])
    r = pmactl("monitor", "--seconds", "0.8", "--every")
    assert "node 0   FAULT, fault HOST_HEARTBEAT_LOST" in r.out
    assert r.out.count("heartbeat ") >= 2


def test_monitor_reports_estop_and_refusals(pmactl, fake, channel) -> None:
    import threading
    fake()

    bus = can.Bus(interface="virtual", channel=channel)

    def later() -> None:
        wait_monitor_sees(bus, (0,))                          # ... in state IDLE
        bus.send(can.Message(arbitration_id=PROTO.frame_id("COMMAND", 0), data=b"\x04\x00",
                             is_extended_id=False))        # STOP while IDLE: refused
        bus.send(can.Message(arbitration_id=0, data=b"", is_extended_id=False))

    t = threading.Thread(target=later, daemon=True)
    t.start()
    # --seconds: long enough for the node's answers to come after the frames (wall time)
    r = pmactl("monitor", "--seconds", "3", "--host-heartbeat")
    t.join()
    bus.shutdown()
    assert "refused STOP: STATE (-20)" in r.out
    assert "bus      ESTOP_ALL on the bus" in r.out
    assert "FAULT ESTOP (1)" in r.out


def test_exit_codes_are_documented() -> None:
    readme = (Path(__file__).resolve().parents[1] / "README.md").read_text()
    for code in (cli.EXIT_OK, cli.EXIT_REFUSED, cli.EXIT_USAGE, cli.EXIT_INTERFACE, cli.EXIT_NO_REPLY,
                 cli.EXIT_FILE, cli.EXIT_INTERRUPTED):
        assert f"| {code} |" in readme
        assert f"  {code} " in cli.EXIT_CODES_HELP
