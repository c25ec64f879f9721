# SPDX-License-Identifier: Apache-2.0
"""Bad input gets a clear error and changes nothing: every option of pmactl is validated
before anything is sent (exit 2, one message naming the unit, no traceback); bad files are
exit 5. Against fake nodes on python-can's virtual bus."""
from __future__ import annotations

import json
import time
from pathlib import Path

import can
import pytest
from fakenode import PROTO, wait_until

from pmactl import PmaNode
from pmactl.cli import EXIT_FILE, EXIT_INTERFACE, EXIT_NO_REPLY, EXIT_OK, EXIT_USAGE, main
from pmactl.recording import header_row


def _usage(r, *words: str) -> None:
    assert r.code == EXIT_USAGE, (r.code, r.err)
    assert "Traceback" not in r.err
    for w in words:
        assert w in r.err, (w, r.err)


def _recording(path: Path, rows: int = 30) -> Path:
    """A small recording CSV as `pmactl record` writes it (12 columns, units in the header)."""
    lines = [",".join(header_row())]
    for i in range(rows):
        t = 0.01 * (i + 1)
        x = -1.5 + 0.01 * i
        lines.append(",".join(str(v) for v in (t, x, -1.5, x + 1.5, 1.0, 0.5, 0.0, 0.0, 300.0, 0, 0, t)))
    path.write_text("\n".join(lines) + "\n")
    return path


# ------------------------------------------------------- values the frame carries --
def test_setpoint_outside_the_dbc_range_is_refused_before_sending(pmactl, fake) -> None:
    n = fake()
    n.rows[PROTO.param("ref.kind").id].value = 6          # STREAM
    n.set_state("RUNNING")
    for args in (("5000", "--no-check"), ("1e300", "--no-check"), ("-1000.5", "--no-check"), ("5000",)):
        r = pmactl("setpoint", *args)
        _usage(r, "outside -1000..1000 cm", "nothing sent")
    time.sleep(0.05)
    assert n.setpoints == []
    r = pmactl("setpoint", "-1", "--no-check")               # inside: sent
    assert r.code == EXIT_OK and wait_until(lambda: n.setpoints == [-1.0])


def test_the_client_refuses_a_setpoint_the_frame_cannot_carry(channel) -> None:
    with can.Bus(interface="virtual", channel=channel) as bus, \
            can.Bus(interface="virtual", channel=channel) as spy:
        node = PmaNode(bus, 0, PROTO)
        for bad in (5000.0, -1e300, float("nan"), float("inf")):
            with pytest.raises(ValueError, match="set-point"):
                node.setpoint(bad)
        assert spy.recv(0.1) is None                          # nothing on the bus


def test_params_set_no_check_outside_the_frames_range(pmactl, fake) -> None:
    n = fake()
    r = pmactl("params", "set", "ppc.w1_cm", "1e300", "--no-check")
    _usage(r, "ppc.w1_cm (f32)", "outside")
    r = pmactl("params", "set", "telem.mask", "-1", "--no-check")    # u32: no negative value
    _usage(r, "telem.mask (u32)", "outside 0..")
    time.sleep(0.05)
    assert n.sets() == []
    assert [name for name, _ in n.received if name == "PARAM_REQ"] == []   # not even a GET


# ----------------------------------------------------------------------- paths --
@pytest.mark.parametrize("args", [
    ("record", ""), ("record", "r.csv", "--log", ""), ("record", " "),
    ("plot", ""), ("plot", "r.csv", "--out", ""),
    ("scope", "--csv", ""), ("scope", "--headless", "--frames", "1", "--out", ""),
    ("dbc", "-o", ""), ("params", "dump", ""), ("params", "load", ""),
    ("commission", "--w1", "0.2", "--t-u", "2", "--out", ""),
])
def test_empty_file_names_are_refused(pmactl, args, tmp_path: Path, monkeypatch) -> None:
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    r = pmactl(*args)
    _usage(r, "file name is empty")
    assert list(work.iterdir()) == []                         # nothing written (no scope-*.csv)


def test_record_to_a_directory_or_onto_itself(pmactl, fake, tmp_path: Path) -> None:
    n = fake()
    n.set_state("RUNNING")
    out = tmp_path / "out"
    out.mkdir()
    _usage(pmactl("record", str(out), "--seconds", "0.2", "-q"), "is a directory")
    assert not (tmp_path / "out.blf").exists()
    (tmp_path / "run.blf").mkdir()                            # the default frame log
    _usage(pmactl("record", str(tmp_path / "run.csv"), "--seconds", "0.2", "-q"), "run.blf", "is a directory")
    (tmp_path / "m.meta.json").mkdir()                        # the metadata
    _usage(pmactl("record", str(tmp_path / "m.csv"), "--no-log", "-q"), "m.meta.json", "is a directory")
    # two outputs on one path: the frame log would overwrite the CSV
    _usage(pmactl("record", str(tmp_path / "same.blf"), "--seconds", "0.2", "-q"), "same file")
    _usage(pmactl("record", str(tmp_path / "x.log"), "--log", str(tmp_path / "x.log"), "-q"), "same file")
    for p in (tmp_path / "same.blf", tmp_path / "x.log"):
        assert not p.exists()
    assert n.state == 3 and [name for name, _ in n.received if name == "PARAM_REQ"] == []


def test_record_relative_and_absolute_spellings_of_one_file(pmactl, tmp_path: Path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    _usage(pmactl("record", "a.log", "--log", str(tmp_path / "a.log"), "-q"), "same file")


def test_outputs_that_are_directories_or_in_no_directory(pmactl, fake, tmp_path: Path) -> None:
    n = fake()
    csv_path = _recording(tmp_path / "run.csv")
    (tmp_path / "fig.png").mkdir()
    _usage(pmactl("plot", str(csv_path), "--out", str(tmp_path / "fig"), bus=False), "fig.png", "is a directory")
    _usage(pmactl("plot", str(csv_path), "--out", str(tmp_path), bus=False), "is a directory")
    # the figure would overwrite the recording
    _usage(pmactl("plot", str(_recording(tmp_path / "r.png")), bus=False), "same file")
    (tmp_path / "d.json").mkdir()
    _usage(pmactl("dbc", "-o", str(tmp_path / "d.json")), "is a directory")
    _usage(pmactl("scope", "--csv", str(tmp_path / "d.json"), "--headless", "--frames", "1"), "is a directory")
    assert n.state == 1


# --------------------------------------------------------------------- plot meta --
@pytest.mark.parametrize("params, words", [
    ({"ppc.w1_cm": "abc", "ppc.t_u_s": -5}, ["params.ppc.w1_cm = \"abc\"", "params.ppc.t_u_s = -5", "(cm)", "(s)"]),
    ({"ppc.w1_cm": None}, ["params.ppc.w1_cm = null"]),
    ({"ppc.w1_cm": True}, ["params.ppc.w1_cm = true"]),
    ({"safety.x_min_cm": 0, "safety.x_max_cm": -3}, ["x_min_cm = 0 cm is not below"]),
    ({"safety.x_min_cm": "a", "safety.x_max_cm": 0}, ["params.safety.x_min_cm = \"a\""]),
])
def test_plot_with_bad_metadata_is_a_bad_file(pmactl, tmp_path: Path, params, words) -> None:
    csv_path = _recording(tmp_path / "good.csv")
    meta = tmp_path / "good.meta.json"
    meta.write_text(json.dumps({"controller": "PPC", "params": params}))
    r = pmactl("plot", str(csv_path), "--no-panels", bus=False)
    assert r.code == EXIT_FILE, r.err
    assert "Traceback" not in r.err and str(meta) in r.err and "--no-meta" in r.err
    for w in words:
        assert w in r.err, (w, r.err)
    assert not (tmp_path / "good.png").exists()
    r = pmactl("plot", str(csv_path), "--no-panels", "--no-meta", bus=False)
    assert r.code == EXIT_OK, r.err


def test_plot_metadata_not_an_object(pmactl, tmp_path: Path) -> None:
    csv_path = _recording(tmp_path / "good.csv")
    for text in ("[1, 2]", '{"params": [1]}', "{broken"):
        (tmp_path / "good.meta.json").write_text(text)
        r = pmactl("plot", str(csv_path), "--no-panels", bus=False)
        assert r.code == EXIT_FILE and "not a recording's metadata" in r.err, r.err


def test_plot_takes_good_metadata(pmactl, tmp_path: Path) -> None:
    csv_path = _recording(tmp_path / "good.csv")
    (tmp_path / "good.meta.json").write_text(json.dumps(
        {"controller": "PPC", "params": {"ppc.w1_cm": 0.25, "ppc.t_u_s": 0.1,
                                         "safety.x_min_cm": -3, "safety.x_max_cm": 0}}))
    r = pmactl("plot", str(csv_path), "--no-panels", bus=False)
    assert r.code == EXIT_OK, r.err
    assert "w1 = 0.25 cm" in r.out and "t_u = 0.1 s" in r.out


# ------------------------------------------------------------ numbers and units --
@pytest.mark.parametrize("args, words", [
    (("plot", "r.csv", "--dpi", "100000"), ["1..1200"]),
    (("plot", "r.csv", "--dpi", "1201"), ["1..1200"]),
    (("plot", "r.csv", "--dpi", "0"), ["1..1200"]),
    (("scope", "--dpi", "100000"), ["1..1200"]),
    (("--bitrate", "-5", "status"), ["bit/s"]),
    (("--bitrate", "0", "status"), ["bit/s"]),
    (("--bitrate", "fast", "status"), ["--bitrate", "fast"]),
    (("plot", "r.csv", "--w1", "-1"), ["-1 is not a positive number of cm"]),
    (("plot", "r.csv", "--t-u", "-1"), ["-1 is not a positive number of seconds"]),
    (("scope", "--w1", "-1"), ["-1 is not a positive number of cm"]),
    (("scope", "--fps", "nan"), ["nan is not a positive number of frames per second"]),
    (("commission", "--w1", "-1", "--t-u", "2"), ["-1 is not a positive number of cm"]),
    (("commission", "--w1", "0.2", "--t-u", "0"), ["0 is not a positive number of seconds"]),
    (("plot", "r.csv", "--band", "0", "-3"), ["--band 0 -3", "below"]),
    (("plot", "r.csv", "--band", "1", "1"), ["--band 1 1", "below"]),
    (("--channel", "", "status"), ["the channel is empty"]),
])
def test_bad_numbers_name_their_unit(pmactl, fake, tmp_path: Path, monkeypatch, args, words) -> None:
    monkeypatch.chdir(tmp_path)
    _recording(tmp_path / "r.csv")
    n = fake()
    _usage(pmactl(*args), *words)
    assert not list(tmp_path.glob("*.png"))
    assert [name for name, _ in n.received if name in ("PARAM_REQ", "COMMAND")] == []


def test_bitrate_and_channel_when_given_right(pmactl, fake) -> None:
    fake()
    assert pmactl("--bitrate", "1000000", "status").code == EXIT_OK


# ------------------------------------------------------------------ params files --
def test_params_dump_checks_its_file_before_reading_the_node(pmactl, fake, tmp_path: Path) -> None:
    n = fake()
    _usage(pmactl("params", "dump", str(tmp_path / "none" / "out.json")), "does not exist")
    (tmp_path / "dir.json").mkdir()
    _usage(pmactl("params", "dump", str(tmp_path / "dir.json")), "is a directory")
    time.sleep(0.05)
    assert [name for name, _ in n.received if name == "PARAM_REQ"] == []


def test_params_load_of_nothing_is_a_bad_file(pmactl, fake, tmp_path: Path) -> None:
    empty = tmp_path / "empty.json"
    empty.write_text('{"params": {}}')
    r = pmactl("params", "load", str(empty))                 # no node on the bus
    assert r.code == EXIT_FILE and "no parameter to load" in r.err, (r.code, r.err)
    only_id = tmp_path / "id.json"
    only_id.write_text('{"params": {"sys.node_id": 3}}')
    n = fake()
    r = pmactl("params", "load", str(only_id))
    assert r.code == EXIT_FILE and "--with-node-id" in r.err
    time.sleep(0.05)
    assert n.sets() == []


# ----------------------------------------------------------------- the bus --
@pytest.mark.parametrize("name", ["nosuch", ""])
def test_an_unknown_interface_is_a_usage_error(pmactl, name) -> None:
    r = pmactl("--interface", name, "status", bus=False)
    _usage(r, "python-can knows", "virtual", "socketcan")


def test_an_unknown_interface_from_the_environment(monkeypatch, capsys) -> None:
    monkeypatch.setenv("CAN_INTERFACE", "nosuch")
    assert main(["status"]) == EXIT_USAGE
    assert "python-can knows" in capsys.readouterr().err


def test_a_known_interface_that_fails_to_open_stays_exit_3(pmactl) -> None:
    r = pmactl("--interface", "socketcan", "--channel", "pmactl-none0", "status", bus=False)
    assert r.code == EXIT_INTERFACE


# --------------------------------------------------------------------- scope --
def test_scope_record_without_telemetry_leaves_no_file(pmactl, fake, tmp_path: Path) -> None:
    fake()                                                    # IDLE: no telemetry
    csv_path = tmp_path / "s.csv"
    r = pmactl("scope", "--headless", "--frames", "2", "--out", str(tmp_path / "f"), "--record",
               "--csv", str(csv_path))
    assert r.code == EXIT_NO_REPLY, r.err
    assert not csv_path.exists() and not (tmp_path / "s.meta.json").exists()
    assert "not kept" in r.out


# ---------------------------------------------------------------- commission --
@pytest.mark.parametrize("args, words", [
    (("--x-min", "-3", "--x-max", "0", "--x-start", "50"), ["--x-start 50 cm is outside -2.8..-0.2 cm"]),
    (("--x-min", "-3", "--x-max", "0", "--x-start", "-2.9"), ["--x-start -2.9 cm is outside"]),
    (("--x-start", "50",), ["--x-start 50 cm is outside -2.8..-0.2 cm", "safety.x_min_cm"]),   # the node's band
    (("--t-u", "1e9",), ["--t-u: ppc.t_u_s: 1e+09 s is outside"]),
    (("--w1", "150",), ["--w1: ppc.w1_cm: 150 cm is outside"]),
    (("--x-min", "-5000", "--x-max", "0"), ["--x-min: safety.x_min_cm: -5000 cm is outside -1000..1000 cm"]),
    (("--x-min", "-3", "--x-max", "1e6"), ["--x-max: safety.x_max_cm"]),
    (("--x-min", "0", "--x-max", "-3"), ["must be below"]),
    (("--x-min", "-3", "--x-max", "-2.7"), ["not wider than 2 w1"]),
])
def test_commission_checks_the_task_before_sending(pmactl, fake, args, words) -> None:
    n = fake()                                                # safety.x_min_cm..x_max_cm: -3..0
    base = {"--w1": "0.2", "--t-u": "2"}
    given = dict(zip(args[::2], args[1::2]))
    argv = [a for k, v in {**base, **given}.items() for a in (k, v)]
    r = pmactl("commission", *argv, "-q")
    _usage(r, *words)
    time.sleep(0.05)
    assert n.sets() == [] and n.state == 1
    assert [name for name, _ in n.received if name == "COMMAND"] == []


def test_commission_checks_its_output_directory_before_sending(pmactl, fake, tmp_path: Path) -> None:
    """--out is checked for every file the run will write (report.json, params.json, the
    figure) before anything is sent: a minute of measurement is not lost to it afterwards."""
    n = fake()
    (tmp_path / "plain").write_text("a file\n")
    taken = tmp_path / "taken"
    (taken / "params.json").mkdir(parents=True)               # a directory where a file goes
    for out, words in ((tmp_path / "plain", ["not a directory"]),
                       (tmp_path / "plain" / "sub", ["plain is not a directory"]),
                       (taken, ["params.json", "is a directory"])):
        r = pmactl("commission", "--w1", "0.2", "--t-u", "2", "--out", str(out), "-q")
        _usage(r, *words)
    assert not (tmp_path / "plain" / "sub").exists() and not (taken / "report.json").exists()
    time.sleep(0.05)
    assert n.sets() == [] and n.state == 1
    assert [name for name, _ in n.received if name in ("COMMAND", "PARAM_REQ")] == []
