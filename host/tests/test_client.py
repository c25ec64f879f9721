# SPDX-License-Identifier: Apache-2.0
"""The client library (what the HIL harness uses): bus configuration, the protocol
tables against the firmware's sources, PmaNode, the telemetry grouper and recorder,
parameter files and recordings."""
from __future__ import annotations

import json
import math
import os
import re
import time
from pathlib import Path

import can
import numpy as np
import pytest
from fakenode import PROTO, UNKNOWN_ID, wait_until

from pmactl import (
    NoReply,
    PmaNode,
    SetRejected,
    TelemetryGrouper,
    TelemetryRecorder,
    bus_config,
    load_protocol,
    paramfile,
)
from pmactl.client import DEFAULT_CHANNEL, InterfaceError, internal_labels
from pmactl.protocol import HEARTBEAT_FLAGS, RESULT_MEANINGS, to_f32
from pmactl.recording import COLUMNS, Recording, RecordingError, header_row, metrics, read_recording

HOST = Path(__file__).resolve().parents[1]     # host/
REPO = HOST.parent                              # the repository


# ------------------------------------------------------------ configuration --
def test_defaults_only_what_is_unset(monkeypatch: pytest.MonkeyPatch) -> None:
    assert bus_config() == {"interface": "socketcan", "channel": DEFAULT_CHANNEL}
    assert bus_config(channel="can1") == {"interface": "socketcan", "channel": "can1"}
    assert bus_config(bitrate=500000)["bitrate"] == 500000
    monkeypatch.setenv("CAN_INTERFACE", "virtual")
    cfg = bus_config()
    assert cfg["interface"] == "virtual" and "channel" not in cfg   # no vcan0 for other interfaces
    monkeypatch.setenv("CAN_CHANNEL", "bench")
    monkeypatch.setenv("CAN_BITRATE", "250000")
    assert bus_config() == {"interface": "virtual", "channel": "bench", "bitrate": 250000}
    assert bus_config(interface="socketcan", channel="can0")["channel"] == "can0"


def test_canrc_and_context(monkeypatch: pytest.MonkeyPatch) -> None:
    rc = Path(os.environ["HOME"], ".canrc")
    rc.write_text("[default]\ninterface = virtual\nchannel = rig\nbitrate = 1000000\n"
                  "[bench2]\ninterface = virtual\nchannel = second\n")
    assert bus_config() == {"interface": "virtual", "channel": "rig", "bitrate": 1000000}
    assert bus_config(context="bench2")["channel"] == "second"
    monkeypatch.setenv("CAN_CHANNEL", "from-env")             # the environment beats the file
    assert bus_config()["channel"] == "from-env"


def test_unknown_interface() -> None:
    with pytest.raises(InterfaceError, match="Unknown interface type"):
        bus_config(interface="nonsense")


# ---------------------------------------------------------------- protocol --
def test_heartbeat_flags_match_the_firmware() -> None:
    app_h = (REPO / "firmware/app/app.h").read_text()
    defines = {int(v, 16).bit_length() - 1: n for n, v in
               re.findall(r"#define PMA_HB_(\w+)\s+0x([0-9A-Fa-f]+)u", app_h)}
    assert defines == HEARTBEAT_FLAGS


def test_every_result_has_a_meaning() -> None:
    assert set(PROTO.status_names.values()) == set(RESULT_MEANINGS)
    assert PROTO.status_text(-20).startswith("STATE (-20): not allowed")
    assert PROTO.status_text(-99) == "status -99 (-99)"


def test_package_data_is_the_firmwares() -> None:
    """pmactl reads the firmware's own files (an editable install: from the repository; a
    wheel: its copies, test_wheel.py), never a copy kept in host/."""
    from pmactl.protocol import data_files
    files = data_files()
    assert files["dbc"].read_bytes() == (REPO / "firmware/protocol/pma_proto.dbc").read_bytes()
    assert files["params"].read_bytes() == (REPO / "firmware/app/params.toml").read_bytes()
    assert not (HOST / "src/pmactl/data").exists() or not any((HOST / "src/pmactl/data").iterdir())


def test_param_check() -> None:
    w1 = PROTO.param("ppc.w1_cm")
    assert w1.check("0.3") == 0.3 and isinstance(w1.check(1), float)
    mode = PROTO.param("ctrl.mode")
    assert mode.check("mfac") == 2 and mode.check(3.0) == 3 and mode.check("0x1") == 1
    pol = PROTO.param("act.polarity")
    assert pol.check("-1") == -1
    for p, bad in ((w1, 0.0), (w1, float("inf")), (w1, True), (w1, [1]), (mode, 9), (mode, 1.5),
                   (pol, -2), (PROTO.param("telem.mask"), "1e40")):
        with pytest.raises(ValueError):
            p.check(bad)
    assert w1.same(0.2, to_f32(0.2)) and not w1.same(0.2, 0.21)
    assert mode.text(1) == "PPC" and w1.text(to_f32(0.2)) == "0.2"


# ------------------------------------------------------------------ client --
@pytest.fixture
def client(channel: str):
    bus = can.Bus(interface="virtual", channel=channel)
    yield PmaNode(bus, 0, load_protocol(), timeout_s=3.0)
    bus.shutdown()


def test_api_used_by_the_integration_tests(client, fake) -> None:
    """The calls tests/integration and tools/ make keep working."""
    fake()
    assert client.proto.state_names[client.heartbeat()["State"]] == "IDLE"
    assert client.get("ppc.w1_cm") == pytest.approx(0.2)
    assert client.set("ppc.t_u_s", 6) == 6.0
    assert client.info("ppc.w1_cm") == (pytest.approx(0.0001), 100.0, pytest.approx(0.2))
    assert client.ids()[-1] == UNKNOWN_ID
    assert client.arm().result == 0 and client.start().result == 0
    client.host_heartbeat(1)
    assert client.stop().state == 2
    assert client.select_controller("PID").result == 0
    assert client.select_reference(3).result == 0


def test_set_rejected_carries_code_and_kept_value(client, fake) -> None:
    n = fake()
    n.set_state("ARMED")
    with pytest.raises(SetRejected) as e:
        client.set("act.p0_kpa", 250)
    assert (e.value.code, e.value.name, e.value.current) == (-20, "STATE", 300.0)
    assert e.value.param is not None and e.value.param.name == "act.p0_kpa"


@pytest.mark.parametrize("name, value, message", [
    ("ppc.w1_cm", float("inf"), r"ppc\.w1_cm \(f32\): inf is outside .*nothing sent"),
    ("ppc.w1_cm", 1e39, r"ppc\.w1_cm \(f32\): 1e\+39 is outside"),
    ("ppc.w1_cm", "abc", r"ppc\.w1_cm"),
    ("ppc.w1_cm", None, r"ppc\.w1_cm: None is not a number"),
    ("ppc.w1_cm", True, r"ppc\.w1_cm: True is not a number"),
    ("ctrl.mode", 2.5, r"ctrl\.mode is an integer parameter: 2\.5"),
    ("ctrl.mode", float("nan"), r"ctrl\.mode is an integer parameter: nan"),
    ("telem.mask", 2**40, r"telem\.mask \(u32\): 1099511627776 is outside 0\.\.4294967295"),
    ("telem.mask", -1, r"telem\.mask \(u32\): -1 is outside 0\.\.4294967295"),
])
def test_set_refuses_what_no_frame_can_carry_and_sends_nothing(client, fake, name, value, message) -> None:
    """A value the SET frame cannot carry (an infinity, beyond float32, a fraction or a number
    beyond its type for an integer parameter, not a number at all) is a ValueError that names
    the parameter, and nothing is sent; a NaN for an f32 parameter goes out and the node refuses
    it (NOT_FINITE), as every range check is the node's."""
    fake()
    before = client.get(name)
    with pytest.raises(ValueError, match=message):
        client.set(name, value)
    assert client.get(name) == before


def test_an_unknown_command_or_state_or_an_argument_beyond_a_byte_is_refused_before_sending(client, fake) -> None:
    fake()
    with pytest.raises(KeyError, match=r"no command 'FLY'; known: .*ARM"):
        client.command("FLY")
    with pytest.raises(ValueError, match=r"bytes \(0\.\.255\), got 3 and 300"):
        client.command("START", 300)
    with pytest.raises(KeyError, match=r"no state 'FLYING'; known: .*IDLE"):
        client.wait_state("FLYING", timeout_s=0.1)
    assert client.proto.state_names[client.heartbeat()["State"]] == "IDLE"


def test_param_table(client, fake) -> None:
    fake(overrides={"ppc.t_u_s": {"min": 0.5}})
    table = {i.name: i for i in client.param_table()}
    assert table["ppc.t_u_s"].min == 0.5 and table["ppc.t_u_s"].unit == "s"
    assert table[f"#{UNKNOWN_ID}"].param is None and table[f"#{UNKNOWN_ID}"].value == 7


def test_load_values_skips_unchanged(client, fake) -> None:
    n = fake()
    entries = paramfile.validate("t", {"params": {"ppc.w1_cm": 0.2, "ppc.t_u_s": 4}}, PROTO)
    report = client.load_values(entries)
    assert [p.name for p in report.unchanged] == ["ppc.w1_cm"]
    assert [(p.name, old, new) for p, old, new in report.changed] == [("ppc.t_u_s", 2.0, 4.0)]
    assert len(n.sets()) == 1


def test_keep_alive_sends_host_heartbeats_while_waiting(client, fake) -> None:
    n = fake()
    hb_id = PROTO.frame_id("HOST_HEARTBEAT", 0)
    sent: list[float] = []
    client.raw_listeners.append(
        lambda m: sent.append(time.monotonic()) if m.arbitration_id == hb_id and not m.is_rx else None)
    client.host_heartbeat_s = 0.05
    deadline = time.monotonic() + 30.0
    while len(sent) < 6 and time.monotonic() < deadline:
        client.receive(0.2)                  # returns early when a heartbeat is due
    assert len(sent) == 6
    assert wait_until(lambda: n.host_heartbeats == 6), n.host_heartbeats
    client.host_heartbeat_s = None
    client.receive(0.2)
    assert len(sent) == 6
    # rate-limited: with a long period, many receives send one heartbeat (the first is due now)
    client._next_host_heartbeat = 0.0
    client.host_heartbeat_s = 1000.0
    for _ in range(5):
        client.receive(0.02)
    assert len(sent) == 7


def test_listeners_see_frames_a_request_consumes(client, fake) -> None:
    fake()
    seen: list[str] = []
    raw: list[can.Message] = []
    client.frame_listeners.append(lambda name, node, sig, msg: seen.append(name))
    client.raw_listeners.append(raw.append)
    client.get("ppc.w1_cm")
    assert "PARAM_RESP" in seen
    assert any(not m.is_rx for m in raw) and any(m.is_rx for m in raw)


def test_wait_for_times_out(client) -> None:
    with pytest.raises(NoReply, match="no HEARTBEAT from node 0 within 0.1 s"):
        client.heartbeat(timeout_s=0.1)


# --------------------------------------------------------------- telemetry --
def _frames(t_ms: int, mask: int = 0x1F) -> list[tuple[str, dict]]:
    all_frames = [("TELEM_A", {"TimeMs": t_ms, "XCm": -1.0}), ("TELEM_B", {"XrCm": -1.5, "ECm": 0.5}),
                  ("TELEM_C", {"U": 2.0, "VCmS": 0.1}), ("TELEM_D", {"Internal1": 0.3, "Internal2": 0.4}),
                  ("TELEM_E", {"PressureKpa": 302.0, "CtrlFlags": 1, "Breaches": 3})]
    return [f for bit, f in enumerate(all_frames) if mask >> bit & 1]


def test_grouper_groups_by_the_preceding_telem_a() -> None:
    g = TelemetryGrouper(period_ms=10)
    rows = []
    stream = _frames(10)[2:] + _frames(20) + _frames(30)[:3] + _frames(40) + _frames(60) + [
        ("TELEM_B", {"XrCm": 0.0, "ECm": 0.0})]
    for i, (name, sig) in enumerate(stream):
        rows += g.feed(name, sig, float(i))
    rows += g.flush()
    assert [r.t_s for r in rows] == [0.02, 0.03, 0.04, 0.06]
    assert rows[0].values == {"t": 0.02, "x": -1.0, "xr": -1.5, "e": 0.5, "u": 2.0, "v": 0.1,
                              "internal1": 0.3, "internal2": 0.4, "p": 302.0, "ctrl_flags": 1, "breaches": 3}
    assert rows[1].frames == {"TELEM_A", "TELEM_B", "TELEM_C"}
    assert g.rows == 4 and g.incomplete == 1
    assert g.orphans == 3 + 1      # before the first TELEM_A; a repeat after a complete row
    assert g.lost == 1             # 40 -> 60 ms


def test_grouper_with_a_mask() -> None:
    g = TelemetryGrouper(mask=0b00101)
    out = []
    for name, sig in _frames(10, 0b00101):
        out += g.feed(name, sig, 0.0)
    assert len(out) == 1 and out[0].frames == {"TELEM_A", "TELEM_C"} and g.incomplete == 0


def test_recorder_api(client, fake, tmp_path: Path) -> None:
    n = fake()
    n.set_state("ARMED")
    client.wait_state("ARMED", timeout_s=5.0)     # a heartbeat sent before set_state may still be queued
    progress = []
    rec = TelemetryRecorder(client, tmp_path / "r.csv", tmp_path / "r.blf", tmp_path / "r.meta.json")
    s = rec.run(samples=60, start=True, progress=progress.append, progress_every_s=0.1)
    assert s.rows == 60 and s.incomplete == 0 and s.lost == 0 and s.stop_reason == "60 samples recorded"
    assert s.max_abs_e_cm is not None and s.breaches == 0
    assert len(progress) >= 1 and progress[-1].rows == s.rows
    assert rec.params["ctrl.mode"] == 1
    rec2 = read_recording(tmp_path / "r.csv")
    assert len(rec2) == s.rows and rec2.names["internal1"] == "lambda1" and rec2.units["internal2"] == "cm/s"
    meta = json.loads((tmp_path / "r.meta.json").read_text())
    assert meta["params"]["ref.kind"] == "HOLD" and meta["summary"]["final_state"] is not None


def test_internal_labels() -> None:
    assert internal_labels("PPC") == (("lambda1", "cm"), ("lambda2", "cm/s"))
    assert internal_labels("OFF")[0] == ("internal1", "-")
    assert header_row()[6] == "internal1 [-]" and len(header_row()) == len(COLUMNS)


def test_read_recording_rejects_other_csv(tmp_path: Path) -> None:
    p = tmp_path / "r.csv"
    p.write_text(",".join(header_row()).replace("x [cm]", "x [mm]") + "\n")
    with pytest.raises(RecordingError, match=r"column 'x \[mm\]'"):
        read_recording(p)


# ----------------------------------------------------------- parameter files --
def test_f32_short() -> None:
    assert paramfile.f32_short(to_f32(0.2)) == 0.2
    assert paramfile.f32_short(to_f32(-0.0030525)) == -0.0030525
    assert paramfile.f32_short(to_f32(1e-6)) == 1e-6
    for v in (0.1, 1 / 3, 123456.789, 3.4e38):
        assert to_f32(paramfile.f32_short(to_f32(v))) == to_f32(v)


def test_param_file_round_trip(tmp_path: Path) -> None:
    values = {p.id: (to_f32(float(p.default)) if p.type == "f32" else int(p.default)) for p in PROTO.params}
    path = tmp_path / "all.json"
    paramfile.write(str(path), PROTO, values, 3)
    entries = paramfile.load(str(path), PROTO)
    assert len(entries) == len(PROTO.params)
    for p, v in entries:
        assert p.same(v, values[p.id]), p.name


def test_metrics() -> None:
    import numpy as np
    t = np.arange(1, 401) * 0.01                       # 4 s
    e = 2.0 * np.exp(-t / 0.3)
    e[250] = 0.25                                      # one excursion at t = 2.51 s
    data = {c.key: np.full(len(t), np.nan) for c in COLUMNS}
    data.update(t=t, e=e, v=-e / 0.3, u=np.where(t < 1, 100.0 * e, 1.0), breaches=np.arange(len(t)) // 10)
    rec = Recording(Path("x.csv"), data, {}, {})
    m = metrics(rec, w1_cm=0.3, t_u_s=2.0)
    assert m.time_to_band_s == pytest.approx(0.57)       # first t with 2 exp(-t/0.3) < 0.3
    assert m.converge_peak_v_cm_s == pytest.approx(2 * np.exp(-0.01 / 0.3) / 0.3)
    assert m.max_abs_e_after_tu_cm == pytest.approx(0.25)
    assert m.breaches == 39
    m = metrics(rec, w1_cm=0.2, t_u_s=2.0)
    assert m.time_to_band_s == pytest.approx(2.52)       # after the excursion
    assert metrics(rec, w1_cm=1e-9).time_to_band_s is None
    lines = m.lines(0.2, 2.0)
    assert lines[1] == "|e| < w1 = 0.2 cm from t = 2.520 s on (t_u = 2 s)"


def test_figures_count_a_nan_sample_as_outside_and_say_none_for_never() -> None:
    """The one rule of pmactl/figures.py, which recordings and the HIL summary share."""
    from pmactl import figures

    t = np.arange(10) * 0.1
    e = np.array([0.5, 0.1, 0.1, np.nan, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1])
    assert figures.time_to_band(t, e, 0.2) == pytest.approx(0.4)          # the NaN is outside
    assert figures.samples_outside_from(t, e, 0.2, 0.0) == 2
    assert figures.rmste_from(t, e, 0.1) == pytest.approx(0.1)             # the NaN left out
    assert figures.max_abs_from(t, e, None) == pytest.approx(0.5)
    assert figures.time_to_band(t, np.full(10, 0.5), 0.2) is None          # never
    assert figures.rmste_from(t, e, 5.0) is None and figures.max_abs_from(t, e, 5.0) is None
    assert math.isnan(figures.rmste(t, e, [(5.0, 6.0)])[0])               # a window without samples
