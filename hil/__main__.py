# SPDX-License-Identifier: Apache-2.0
"""python -m hil: run HIL scenarios against pma-fw-host (or a board) over CAN.

    python -m hil list
    python -m hil run SCENARIO --out DIR [--quick] [--commission] [--interface I --channel C --bitrate B]
    python -m hil report DIR [DIR ...]
    python -m hil bench [--seconds S]
    python -m hil offline SCENARIO [--quick] [--controller L] [--set N=V] [--rig P=V] [--grid N=V1,V2] [--jobs N]

Exit status: 0 the run ended as the scenario expects; 1 it did not (or the run
failed); 2 bad command line or scenario file; 3 CAN interface problem;
130 interrupted (the run is stopped cleanly and its partial results written).
"""
from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
from pathlib import Path
from typing import Any

from . import scenario as scn
from .options import NOISE_LIMIT_HELP, OptionError, noise_limit, out_dir, positive_number

REPO = Path(__file__).resolve().parents[1]
WITH_VCAN = REPO / "hil" / "with-vcan"


def _bus_config(args: argparse.Namespace) -> tuple[dict[str, Any] | None, int]:
    """The python-can configuration, checked as pmactl checks it (pmactl.bus_config: the
    interface, channel and bit rate, given or from python-can's configuration); else None with
    the reason printed and the exit status: 2 for a bad value, 3 for a missing driver."""
    from pmactl.client import BadBusConfig, InterfaceError, bus_config
    try:
        return bus_config(args.interface, args.channel, args.bitrate), 0
    except InterfaceError as e:
        print(f"hil: {e}", file=sys.stderr)
        return None, 2 if isinstance(e, BadBusConfig) else 3


def _needs_guest(cfg: dict[str, Any]) -> bool:
    """True when the run must go through hil/with-vcan: a vcan channel that this
    machine does not have (no SocketCAN in the kernel, or no vcan0 and not root)."""
    if os.environ.get("PMA_HIL_INSIDE") == "1":
        return False
    if cfg.get("interface") != "socketcan" or not str(cfg.get("channel", "")).startswith("vcan"):
        return False
    return not Path(f"/sys/class/net/{cfg['channel']}").exists()


def _rerun_in_guest(argv: list[str], out: Path) -> int:
    """Runs this command again inside hil/with-vcan. Ctrl-C here asks the run inside
    to stop cleanly (a STOP file in the output directory, which the guest shares);
    a second Ctrl-C ends the guest."""
    from .runner import STOP_FILE
    env = dict(os.environ, PMA_HIL_INSIDE="1")
    cmd = [str(WITH_VCAN), sys.executable, "-m", "hil", *argv]
    proc = subprocess.Popen(cmd, env=env, cwd=os.getcwd(), start_new_session=True)
    interrupts = 0
    while True:
        try:
            return proc.wait()
        except KeyboardInterrupt:
            interrupts += 1
            if interrupts == 1:
                print("\nhil: stopping the run cleanly (Ctrl-C again to kill it)", file=sys.stderr)
                out.mkdir(parents=True, exist_ok=True)
                (out / STOP_FILE).touch()
            else:
                os.killpg(proc.pid, signal.SIGINT)
                proc.wait()
                return 130


def _interrupt(signum: int, frame: object) -> None:
    raise KeyboardInterrupt(f"signal {signum}")


def cmd_list(_: argparse.Namespace) -> int:
    for name in scn.available():
        try:
            s = scn.load(name)
            ctrls = ", ".join(c.label for c in s.controllers)
            print(f"{name:24s} {s.duration_s:6.0f} s  [{ctrls}]  {s.title}")
        except scn.ScenarioError as e:
            print(f"{name:24s} INVALID: {e}")
    return 0


def cmd_run(args: argparse.Namespace, argv: list[str]) -> int:
    from .report import print_summary, write_figures
    from .runner import RunError, Runner, RunOptions
    try:
        sc = scn.load(args.scenario)
        sc.noise_limit = noise_limit(args.noise_limit, args.commission)
        out = out_dir("--out", args.out)      # before the bus set-up and a re-run in the vcan guest
    except (scn.ScenarioError, OptionError) as e:
        print(f"hil: {e}", file=sys.stderr)
        return 2
    if args.controller:
        keep = [c for c in sc.controllers if c.label in args.controller]
        missing = set(args.controller) - {c.label for c in keep}
        if missing:
            print(f"hil: {sc.name} has no controller {', '.join(sorted(missing))} "
                  f"(it has {', '.join(c.label for c in sc.controllers)})", file=sys.stderr)
            return 2
        sc.controllers = keep
    needs = sc.needs_commissioning()
    if needs and not args.commission:
        print(f"hil: {sc.name}: lane(s) {', '.join(needs)} take their set from commissioning: add --commission "
              "(or choose other lanes with --controller)", file=sys.stderr)
        return 2
    if args.commission and not needs:
        print(f"hil: --commission: {sc.name} has no lane with commission = true", file=sys.stderr)
        return 2
    if args.board and len(sc.controllers) != 1:
        print("hil: --board drives one node: choose one controller with --controller LABEL", file=sys.stderr)
        return 2
    cfg, rc = _bus_config(args)
    if cfg is None:
        return rc
    if _needs_guest(cfg):
        return _rerun_in_guest(argv, out)
    opts = RunOptions(out=out, quick=args.quick, bus_config=cfg, board=args.board, board_node=args.node,
                      log_format=args.log_format, progress=not args.no_progress, commission=args.commission)
    # Ctrl-C and SIGTERM stop the run cleanly (even when started with SIGINT ignored,
    # as background jobs of a non-interactive shell are)
    signal.signal(signal.SIGINT, signal.default_int_handler)
    signal.signal(signal.SIGTERM, _interrupt)
    try:
        summary = Runner(sc, opts).run()
    except RunError as e:
        print(f"hil: {e}", file=sys.stderr)
        return 3 if "CAN bus" in str(e) else 1
    print_summary(summary)
    if not args.no_figures and (out / "signals.npz").exists():
        for p in write_figures(out):
            print(f"figure: {p}")
    print(f"results: {out / 'summary.json'}, {out / 'signals.npz'}, {out / summary['bus_log']}")
    if summary["interrupted"]:
        return 130
    for err in summary["errors"]:
        print(f"hil: error: {err}", file=sys.stderr)
    return 0 if summary["expect_met"] else 1


def cmd_report(args: argparse.Namespace) -> int:
    """Each run directory's summary (and figures): a directory without a readable run summary
    (or, with --figures, without its signals.npz) is a clear error, exit status 2."""
    from .report import ReportError, render_summary, write_figures
    rc = 0
    for d in args.dirs:
        try:
            text = render_summary(Path(d))
            if args.figures and not (Path(d) / "signals.npz").is_file():
                raise ReportError(f"{Path(d) / 'signals.npz'} not found (--figures needs the run's signals)")
        except ReportError as e:
            print(f"hil: {e}", file=sys.stderr)
            rc = 2
            continue
        print(text)
        if args.figures:
            try:
                for f in write_figures(Path(d)):
                    print(f"figure: {f}")
            except ReportError as e:
                print(f"hil: {e}", file=sys.stderr)
                rc = 2
    return rc


def cmd_bench(args: argparse.Namespace, argv: list[str]) -> int:
    from .bench import run_bench
    try:
        positive_number("--seconds", args.seconds, hi=3600.0, unit="s")
        out = out_dir("--out", args.out)
    except OptionError as e:
        print(f"hil bench: {e}", file=sys.stderr)
        return 2
    cfg, rc = _bus_config(args)
    if cfg is None:
        return rc
    if _needs_guest(cfg):
        return _rerun_in_guest(argv, out)
    try:
        return run_bench(cfg, args.seconds, out)
    except RuntimeError as e:
        # one line; the rest (the firmware's output) into a file beside the results
        first, _, rest = str(e).partition("\n")
        where = ""
        if rest.strip():
            try:
                out.mkdir(parents=True, exist_ok=True)
                (out / "bench-error.txt").write_text(str(e) + "\n")
                where = f" (details: {out / 'bench-error.txt'})"
            except OSError:
                pass
        print(f"hil bench: {first}{where}", file=sys.stderr)
        return 1


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    ap = argparse.ArgumentParser(prog="python -m hil", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    sub.add_parser("list", help="the scenarios in hil/scenarios")

    def can_opts(p: argparse.ArgumentParser) -> None:
        p.add_argument("--interface", help="python-can interface (default: python-can's configuration, else socketcan)")
        p.add_argument("--channel", help="CAN channel (default vcan0 for socketcan)")
        p.add_argument("--bitrate", type=int, help="bit/s, for adapters that set it (e.g. 1000000)")

    r = sub.add_parser("run", help="run a scenario")
    r.add_argument("scenario", help="a name from `python -m hil list` or a .toml path")
    r.add_argument("--out", required=True, help="output directory (summary.json, signals.npz, bus log, figures)")
    r.add_argument("--quick", action="store_true", help="the scenario's short variant (quick_duration_s)")
    r.add_argument("--controller", action="append", metavar="LABEL", help="run only this controller (repeatable)")
    r.add_argument("--commission", action="store_true",
                   help="before ARM, run `pmactl commission` over CAN on the node of each lane with "
                        "commission = true (ppc, mfac), on its own rig, and run the lane on the derived set plus "
                        "the task's own parameters; what was measured and derived goes into summary.json")
    r.add_argument("--noise-limit", type=float, metavar="K", help=NOISE_LIMIT_HELP)
    can_opts(r)
    r.add_argument("--board", action="store_true",
                   help="drive an external node (a board) in real time instead of starting pma-fw-host")
    r.add_argument("--node", type=int, default=0,
                   help="--board: the board's node id (default 0, a fresh board's sys.node_id)")
    r.add_argument("--log-format", choices=("blf", "asc"), default="blf", help="bus log format (default blf)")
    r.add_argument("--no-progress", action="store_true", help="no progress bar")
    r.add_argument("--no-figures", action="store_true", help="do not write PNG figures")

    rp = sub.add_parser("report", help="print the results of finished runs")
    rp.add_argument("dirs", nargs="+")
    rp.add_argument("--figures", action="store_true", help="(re)write the PNG figures")

    b = sub.add_parser("bench", help="lockstep steps/s over CAN vs a raw python-can round trip")
    b.add_argument("--seconds", type=float, default=5.0, help="length of each measurement [s] (default 5)")
    b.add_argument("--out", default="build/hil-bench", help="work directory (default build/hil-bench)")
    can_opts(b)

    o = sub.add_parser("offline", help="run a scenario without CAN: the firmware as a library (libpma_offline.so)",
                       description="The scenario's lanes on the real firmware (the application, control library "
                                   "and fake port as libpma_offline.so), stepped as over CAN; sweeps over "
                                   "parameters and rig values. Exit status: 0 as expected, 1 not, 2 bad options, "
                                   "3 the library is missing.")
    from .offline import add_arguments
    add_arguments(o)

    try:
        args = ap.parse_args(argv)
    except SystemExit as e:
        return int(e.code or 0)
    if args.cmd == "run" and not 0 <= args.node <= 15:
        print("hil: --node must be 0..15", file=sys.stderr)
        return 2
    if args.cmd == "list":
        return cmd_list(args)
    if args.cmd == "run":
        return cmd_run(args, argv)
    if args.cmd == "report":
        return cmd_report(args)
    if args.cmd == "offline":
        from .offline import main as offline_main
        return offline_main(args)
    return cmd_bench(args, argv)


if __name__ == "__main__":
    sys.exit(main())
