"""The `twin` command: run a robot program on a cell, check a report.

    twin run PROGRAM|PROJECT_DIR [--scene SCENE] [--main NAME] [--report R.json] [--rrd R.rrd]
                     [--max-sim-time S] [--seed N] [--expect EXPECT.toml [--junit FILE.xml]]
                     [--seeds N]
    twin check REPORT --expect EXPECT.toml [--junit FILE.xml]
    twin serve PROGRAM|PROJECT_DIR [--scene SCENE] [--fast] [--viewer] [--report R.json] ...
    twin calibrate SCENE [--camera NAME]

A user's mistake (bad syntax, an unreachable location, a missing file) is
printed as the controller would print it, with file and line, and never as a
Python traceback.  Exit status: 0 when the program ended normally, 1 when it
stopped on an error, 2 when the command line or an input file is wrong.
"""

from __future__ import annotations

import argparse
import statistics
import sys

from .errors import ProgramError


def _run(args: argparse.Namespace) -> int:
    from .runner import run_program

    expect, code = _load_expectations(args)
    if code is not None:
        return code
    if args.seeds is not None:
        return _run_seeds(args, expect)
    try:
        result = run_program(
            args.program, scene=args.scene, main=args.main, report_path=args.report,
            rrd_path=args.rrd, max_sim_time=args.max_sim_time, seed=args.seed,
            progress=_show_progress(args), handle_signals=True, spawn=args.spawn, connect=args.connect,
        )
    except ProgramError as err:
        print(str(err), file=sys.stderr)
        return 2 if err.code is None else 1
    for error in result.report.errors:
        print(ProgramError.from_dict(error), file=sys.stderr)
    report = result.report
    print(_summary(report), file=sys.stderr)
    if report.interrupted:
        return INTERRUPTED
    if expect is not None:
        return _check_run(args, report, expect)
    return 1 if report.errors else 0


INTERRUPTED = 130   # the shell's status for a command stopped by Ctrl-C (128 + SIGINT)


def _summary(report) -> str:
    """'twin: 185.1 s simulated in 9.4 s (19.7x real time); 101 parts: bin 100, nest 1;
    no part dropped; no errors; cycle time 1.824 s (median)'."""
    rate = report.sim_time_s / report.wall_time_s if report.wall_time_s > 0 else float("inf")
    regions = ", ".join(f"{name} {count}" for name, count in report.regions.items() if count)
    dropped = [p["id"] for p in report.parts if p["dropped"]]
    shown = ", ".join(map(str, dropped[:10])) + (", ..." if len(dropped) > 10 else "")
    errors = len(report.errors)
    return (
        ("twin: interrupted at " if report.interrupted else "twin: ")
        + f"{report.sim_time_s:.1f} s simulated in {report.wall_time_s:.1f} s "
        f"({rate:.1f}x real time); {len(report.parts)} parts: {regions or 'none placed'}; "
        + (f"{len(dropped)} dropped (part{'s' if len(dropped) > 1 else ''} {shown})" if dropped
           else "no part dropped")
        + f"; {errors or 'no'} error{'' if errors == 1 else 's'}"
        + (" (" + "; ".join(e["message"] for e in report.errors[:3]) + (", ..." if errors > 3 else "") + ")"
           if errors else "")
        + (f"; cycle time {statistics.median(report.cycle_times_s):.3f} s (median)"
           if report.cycle_times_s else "")
    )


def _show_progress(args: argparse.Namespace) -> bool:
    """The progress line: on a terminal only, and not with --quiet."""
    return not args.quiet and sys.stderr.isatty()


def _add_run_options(run: argparse.ArgumentParser) -> None:
    """`twin run` options for CI: run and check in one command, several seeds at once."""
    run.add_argument("--expect", default=None, metavar="EXPECT.toml",
                     help="check the report against these expectations after the run (exit status: the check's)")
    run.add_argument("--junit", default=None, metavar="FILE.xml", help="with --expect: also write JUnit XML")
    run.add_argument("--spawn", action="store_true", help="also stream the run to a Rerun viewer started for it")
    run.add_argument("--connect", default=None, metavar="ADDR",
                     help="also stream the run to the Rerun viewer at this address "
                          "(e.g. rerun+http://127.0.0.1:9876/proxy)")
    run.add_argument("--quiet", action="store_true",
                     help="no progress line (it is shown only on a terminal, for runs over a few seconds)")
    run.add_argument("--seeds", type=_positive_int, default=None, metavar="N",
                     help="run N feeder seeds (--seed and the next N-1; default from 0) in parallel processes "
                          "and summarise the failures by seed")


def _positive_int(text: str) -> int:
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, got {value}")
    return value


def _load_expectations(args: argparse.Namespace) -> tuple[dict | None, int | None]:
    """The expectation file, read and validated before the run (a typo costs no run);
    (None, 2) with the reason on standard error when it is wrong."""
    from .check import ExpectError, load_expect

    if args.junit and not args.expect:
        print("twin run: error: --junit needs --expect", file=sys.stderr)
        return None, 2
    if args.expect is None:
        return None, None
    try:
        return load_expect(args.expect), None
    except ExpectError as e:
        print(f"twin run: error: {e}", file=sys.stderr)
        return None, 2


def _check_run(args: argparse.Namespace, report, expect: dict) -> int:
    from .check import _safe_junit, evaluate, print_outcomes

    outcomes = evaluate(report, expect)
    if args.junit and not _safe_junit(args.junit, outcomes, report=report):
        return 2
    return print_outcomes(outcomes, args.report or " ".join(map(str, args.program)))


def _run_seeds(args: argparse.Namespace, expect: dict | None) -> int:
    from .seeds import run_seeds, summarise

    first = args.seed if args.seed is not None else 0
    outcomes = run_seeds(args.program, list(range(first, first + args.seeds)), scene=args.scene, main=args.main,
                         max_sim_time=args.max_sim_time, report=args.report, expect=expect)
    print(summarise(outcomes), file=sys.stderr)
    return 1 if any(o.failures for o in outcomes) else 0


def _port_pair(text: str) -> tuple[int, int]:
    program, sep, real = text.partition("=")
    try:
        pair = int(program), int(real)
    except ValueError:
        pair = None
    if not sep or pair is None or not all(0 <= p <= 65535 for p in pair):
        raise argparse.ArgumentTypeError(f"{text!r}: expected PROGRAM=REAL port numbers, e.g. 10100=0")
    return pair


def _serve(args: argparse.Namespace) -> int:
    """Keep the cell running for client software (twin/serve.py)."""
    from .serve import serve_program

    try:
        result = serve_program(args.program, scene=args.scene, main=args.main, report_path=args.report,
                               rrd_path=args.rrd, viewer=args.viewer, fast=args.fast, speed=args.speed,
                               seed=args.seed, max_sim_time=args.max_sim_time, ports=dict(args.port))
    except ProgramError as err:
        print(str(err), file=sys.stderr)
        return 2 if err.code is None else 1
    for error in result.report.errors:
        print(ProgramError.from_dict(error), file=sys.stderr)
    return 1 if result.report.errors else 0


def _check(args: argparse.Namespace) -> int:
    from .check import main_check

    argv = [args.report, "--expect", args.expect]
    if args.junit:
        argv += ["--junit", args.junit]
    return main_check(argv)


def _calibrate(args: argparse.Namespace) -> int:
    from .vision.calibrate import calibrate_scene

    try:
        done = calibrate_scene(args.scene, args.camera)
    except (ValueError, OSError, ProgramError) as err:
        print(f"twin calibrate: {err}", file=sys.stderr)
        return 2
    for config, model, path in done:
        print(f"camera {config.name}: {model.points} target sightings, residual {model.residual_mm:.3f} mm RMS "
              f"({model.residual_max_mm:.3f} mm max, {model.residual_px:.3f} px); focal length "
              f"{model.K[0, 0]:.1f} px; written to {path}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="twin", description="Run robot programs on a digital twin of the cell.")
    sub = parser.add_subparsers(dest="command", required=True)

    run = sub.add_parser("run", help="run a V+ program or a GPL project on a cell")
    run.add_argument("program", nargs="+", help="V+ program files (.pg, .v2; loaded together, the first "
                     "file's first program starts) or a GPL project folder (with Project.gpr)")
    run.add_argument("--scene", default=None, help="cell description (default: scenes/scara_pick.toml)")
    run.add_argument("--main", default=None, help="program to execute (default: the first .PROGRAM; "
                     "GPL: the start procedure of Project.gpr)")
    run.add_argument("--report", default=None, help="write the placement report (JSON) here")
    run.add_argument("--rrd", default=None, help="write a Rerun recording here")
    run.add_argument("--max-sim-time", type=float, default=3600.0, help="stop after this many simulated seconds")
    run.add_argument("--seed", type=int, default=None, help="random seed (default: the scene's)")
    _add_run_options(run)
    run.set_defaults(handler=_run)

    serve = sub.add_parser("serve", help="keep a server program (V+ TCP server, GPL TCP Command Server) "
                           "running on its cell for client software, in real time")
    serve.add_argument("program", help="V+ program file or GPL project folder")
    serve.add_argument("--scene", default=None, help="cell description (default: scenes/scara_pick.toml)")
    serve.add_argument("--main", default=None, help="program to execute (as for twin run)")
    serve.add_argument("--report", default=None, help="write the placement report (JSON) here at the end")
    serve.add_argument("--rrd", default=None, help="also write a Rerun recording here")
    serve.add_argument("--viewer", action="store_true", help="stream to a live Rerun viewer (spawned)")
    serve.add_argument("--fast", action="store_true", help="run as fast as possible, not in real time")
    serve.add_argument("--speed", type=float, default=1.0, help="simulated seconds per wall second (default 1)")
    serve.add_argument("--max-sim-time", type=float, default=float("inf"), help="stop after this many simulated seconds")
    serve.add_argument("--seed", type=int, default=None, help="random seed (default: the scene's)")
    serve.add_argument("--port", type=_port_pair, action="append", default=[], metavar="PROGRAM=REAL",
                       help="listen on loopback port REAL where the program asks for PROGRAM (0: any free "
                       "port; the ports used are printed); may be repeated")
    serve.set_defaults(handler=_serve)

    check = sub.add_parser("check", help="check a report against expectations")
    check.add_argument("report")
    check.add_argument("--expect", required=True)
    check.add_argument("--junit", default=None, help="also write a JUnit XML report")
    check.set_defaults(handler=_check)

    calibrate = sub.add_parser("calibrate", help="calibrate a cell's cameras from images (docs/vision.md)")
    calibrate.add_argument("scene", help="cell description with [[camera]] and [camera.calibration]")
    calibrate.add_argument("--camera", default=None, help="only this camera")
    calibrate.set_defaults(handler=_calibrate)
    return parser


def _version() -> str:
    """The installed distribution's version (the package's own when run from a checkout)."""
    from importlib.metadata import PackageNotFoundError, version

    from . import __version__
    try:
        return version("twin")
    except PackageNotFoundError:
        return __version__


def _add_global_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--version", action="version", version=f"twin {_version()}")


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    _add_global_options(parser)
    args = parser.parse_args(argv)
    return args.handler(args)


if __name__ == "__main__":
    sys.exit(main())
