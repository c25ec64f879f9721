# SPDX-License-Identifier: Apache-2.0
"""pma-fw-host's command line: --help (0), bad options (2), start-up
failures such as a missing interface or an unusable storage file (1, with a
clear message), and the signals that stop it (0)."""
from __future__ import annotations

import signal
import subprocess

import pytest
from conftest import CHANNEL, FW_HOST
from test_fw_lib import STATE, drain, query_state


def run(*args: str, timeout: float = 10.0) -> subprocess.CompletedProcess:
    return subprocess.run([str(FW_HOST), *args], capture_output=True, text=True, timeout=timeout)


def test_help() -> None:
    r = run("--help")
    assert r.returncode == 0, r
    assert r.stdout.startswith("Usage: pma-fw-host --can IFACE"), r.stdout
    for opt in ("--can", "--node", "--storage", "--lockstep", "--watchdog-ms", "--verbose",
                "--test-nvm-cut-after", "--test-nvm-cut-permille", "--test-stall-after-ticks"):
        assert opt in r.stdout, opt
    assert r.stderr == ""
    assert run("--can", CHANNEL, "--help").returncode == 0


@pytest.mark.parametrize("args,message", [
    ([], "--can IFACE is required"),
    (["--lockstep"], "--can IFACE is required"),
    (["--can"], "needs a value"),
    (["--can", CHANNEL, "--bogus"], "unknown option --bogus"),
    (["--can", CHANNEL, "-x"], "unknown option"),
    (["--can", CHANNEL, "--lockstep=1"], "unknown option"),
    (["--can", CHANNEL, "extra"], "unexpected argument 'extra'"),
    (["--can", CHANNEL, "--node", "16"], "--node wants 0..15"),
    (["--can", CHANNEL, "--node", "-1"], "--node wants 0..15"),
    (["--can", CHANNEL, "--node", "x"], "--node wants 0..15"),
    (["--can", CHANNEL, "--node", "3x"], "--node wants 0..15"),
    (["--can", CHANNEL, "--node", ""], "--node wants 0..15"),
    (["--can", CHANNEL, "--node"], "needs a value"),
    (["--can", CHANNEL, "--watchdog-ms", "0"], "--watchdog-ms wants 1..60000"),
    (["--can", CHANNEL, "--watchdog-ms", "60001"], "--watchdog-ms wants 1..60000"),
    (["--can", CHANNEL, "--test-nvm-cut-after", "-1"], "--test-nvm-cut-after"),
    (["--can", CHANNEL, "--test-nvm-cut-permille", "1001"], "--test-nvm-cut-permille wants 0..1000"),
    (["--can", CHANNEL, "--test-stall-after-ticks", "-5"], "--test-stall-after-ticks"),
])
def test_bad_options_exit_2(args, message) -> None:
    r = run(*args)
    assert r.returncode == 2, (args, r)
    assert message in r.stderr, (args, r.stderr)
    assert r.stdout == ""


@pytest.mark.parametrize("iface,words", [
    ("vcan9", ["vcan9", "No such device"]),
    ("lo", ["lo"]),
    ("averyveryverylongname0", ["averyveryverylongname0"]),
])
def test_unusable_interface_exits_1(iface, words) -> None:
    r = run("--can", iface, "--lockstep")
    assert r.returncode == 1, r
    for w in words:
        assert w in r.stderr, r.stderr
    assert r.stderr.startswith("pma-fw-host: "), r.stderr


def test_unusable_storage_exits_1(tmp_path, firmware, bus) -> None:
    wrong = tmp_path / "short.bin"
    wrong.write_bytes(b"\xff" * 100)
    r = run("--can", CHANNEL, "--storage", str(wrong))
    assert r.returncode == 1 and "short.bin" in r.stderr and "bytes" in r.stderr, r
    assert wrong.read_bytes() == b"\xff" * 100, "a file of another geometry must not be touched"
    r = run("--can", CHANNEL, "--storage", str(tmp_path / "no" / "such" / "dir" / "nvm.bin"))
    assert r.returncode == 1 and "nvm.bin" in r.stderr, r
    # a storage file in use by another running node
    shared = tmp_path / "shared.bin"
    fw, node = firmware(node=9, storage=shared)
    r = run("--can", CHANNEL, "--node", "10", "--storage", str(shared))
    assert r.returncode == 1 and "in use by another process" in r.stderr, r
    assert query_state(node) == STATE["IDLE"]
    fw.stop()


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_signals_stop_with_status_0(firmware, bus, sig) -> None:
    drain(bus)
    fw, node = firmware(node=9, wait_heartbeat=False)
    node.wait_for("HEARTBEAT", lambda s: s["State"] == STATE["BOOT"], timeout_s=10)
    query_state(node)                                   # the main loop runs
    fw.proc.send_signal(sig)
    assert fw.wait(10) == 0, fw.output()
    fw.stop()


def test_sigterm_right_after_the_boot_heartbeat(firmware, bus) -> None:
    """The usage text: exit status 0 when stopped by SIGINT/SIGTERM. A
    supervisor that stops the node as soon as it has announced itself (the
    BOOT heartbeat) must get 0 too."""
    statuses = []
    for _ in range(3):
        drain(bus)
        fw, node = firmware(node=9, wait_heartbeat=False)
        node.wait_for("HEARTBEAT", lambda s: s["State"] == STATE["BOOT"], timeout_s=10)
        fw.proc.send_signal(signal.SIGTERM)
        statuses.append(fw.wait(10))
        fw.stop(expect_status=None)
    # Regression (a bug found by this test, now fixed): pma_fw_host.c installs its SIGINT/SIGTERM handlers only after
    # pma_app_init() (which sends the BOOT heartbeat) and the start-up
    # message, so a SIGTERM in that window kills the process (status -15).
    # Fix: install the handlers before pma_hal_init().
    assert statuses == [0, 0, 0], statuses
