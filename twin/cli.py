"""The `twin` command: run a robot program on a cell, check a report.

    twin run PROGRAM|PROJECT_DIR [--scene SCENE] [--main NAME] [--report R.json] [--rrd R.rrd]
                     [--max-sim-time S] [--max-wall-time S] [--no-progress-limit S] [--seed N]
                     [--expect EXPECT.toml [--junit FILE.xml]] [--seeds N]
    twin check REPORT --expect EXPECT.toml [--junit FILE.xml]
    twin serve PROGRAM|PROJECT_DIR [--scene SCENE] [--fast] [--viewer] [--report R.json] ...
    twin calibrate SCENE [--camera NAME]
    twin sweep SCENE PROGRAM --seeds N [--param KEY=V1,V2,...] [--workers K] [--ray ADDRESS] [--out DIR]

A user's mistake (bad syntax, an unreachable location, a missing file) is
printed as the controller would print it, with file and line, and never as a
Python traceback.  Exit status: 0 when the program ended normally, 1 when it
stopped on an error (a runaway the watchdog stopped included), 2 when the
command line or an input file is wrong, 3 on an internal error (a bug in twin:
where it happened and how to report it).  Every file and argument is checked
before the run, so a mistake costs no simulation (docs/robustness.md).
"""

from __future__ import annotations

import argparse
import math
import os
import stat
import statistics
import sys
from pathlib import Path

from .errors import (EXIT_INPUT_ERROR, EXIT_INTERNAL_ERROR, EXIT_OK, EXIT_PROGRAM_ERROR, InputError,
                     ProgramError, internal_error_message)


# ------------------------------------------------------------------ argument values
def non_negative_int(text: str) -> int:
    """--seed: an integer >= 0 (numpy's generators take no negative seed)."""
    try:
        value = int(text, 10)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"{text} is negative (a seed is an integer >= 0)")
    return value


def positive_seconds(text: str, unit: str = " of seconds") -> float:
    """A time limit: a finite number of seconds > 0 (nan, inf, 0 and negatives refused)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number{unit}") from None
    if not math.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"{text} is not a finite number{unit} > 0")
    return value


def positive_number(text: str) -> float:
    """A ratio such as --speed: finite and > 0."""
    return positive_seconds(text, unit="")


def limit_seconds(text: str) -> float:
    """--no-progress-limit: finite seconds >= 0, 0 switching the limit off."""
    if text.strip() in ("0", "0.0"):
        return 0.0
    return positive_seconds(text)


# ------------------------------------------------------------------ files, before the run
def _kind(mode: int) -> str:
    if stat.S_ISDIR(mode):
        return "a folder"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    if stat.S_ISFIFO(mode):
        return "a FIFO"
    if stat.S_ISSOCK(mode):
        return "a socket"
    return "a regular file"


def _mode(path: str, what: str, missing: str = "no such file") -> int:
    """The file mode of an input that must exist (links followed)."""
    try:
        return os.stat(path).st_mode
    except FileNotFoundError:
        raise InputError(f"{what} {path}: {missing}") from None
    except OSError as err:
        raise InputError(f"{what} {path}: {err.strerror}") from None


def check_input_file(path: str, what: str) -> Path:
    """An input that must be a readable regular file (a FIFO would hang, a folder is no file)."""
    mode = _mode(path, what)
    if not stat.S_ISREG(mode):
        raise InputError(f"{what} {path}: is {_kind(mode)}, not a file")
    if not os.access(path, os.R_OK):
        raise InputError(f"{what} {path}: not readable (permission denied)")
    return Path(path)


def check_program(path: str) -> list[Path]:
    """A V+ file, or a GPL project folder with a readable Project.gpr; the files the run
    reads (so that no output may replace them)."""
    if stat.S_ISDIR(_mode(path, "program", missing="no such file or folder")):
        project = Path(path) / "Project.gpr"
        if not project.exists():
            raise InputError(f"program {path}: a folder without Project.gpr is not a GPL project")
        check_input_file(str(project), "GPL project file")
        return [project, *(p for p in Path(path).iterdir() if p.suffix.lower() in (".gpl", ".gpo"))]
    return [check_input_file(path, "program")]


def check_output(path: str, what: str, inputs: list[Path]) -> None:
    """An output the run will write: its folder exists and is writable, and it is not a
    folder, a device, a FIFO, nor one of the run's own input files."""
    target = Path(path)
    if path.endswith(("/", os.sep)) or target.name in ("", ".", ".."):
        raise InputError(f"{what} {path}: names a folder, not a file")
    folder = target.parent
    if not folder.is_dir():
        raise InputError(f"{what} {path}: the folder {folder} does not exist")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise InputError(f"{what} {path}: the folder {folder} is not writable")
    try:
        mode = os.stat(target).st_mode
    except FileNotFoundError:
        return
    except OSError as err:
        raise InputError(f"{what} {path}: {err.strerror}") from None
    if not stat.S_ISREG(mode):
        raise InputError(f"{what} {path}: is {_kind(mode)}; an output must be a regular file")
    for source in inputs:
        if source.exists() and os.path.samefile(source, target):
            raise InputError(f"{what} {path}: is the input file {source}; refusing to overwrite it")
    if not os.access(target, os.W_OK):
        raise InputError(f"{what} {path}: not writable (permission denied)")


def check_distinct(outputs: dict[str, str]) -> None:
    seen: dict[str, str] = {}
    for what, path in outputs.items():
        key = os.path.realpath(path)
        if key in seen:
            raise InputError(f"{what} {path}: is also the {seen[key]}")
        seen[key] = what


def validate_run(args: argparse.Namespace) -> None:
    """Every file and argument of `twin run`, before anything is simulated."""
    from .controller.sandbox import SandboxError, check_root
    from .resources import find_user_file
    from .runner import sandbox_root
    from .simulation import DEFAULT_SCENE

    # As the runner finds them: the path as given, else the bundled file of that name.
    given = args.program if isinstance(args.program, list) else [args.program]
    programs = [str(find_user_file(p)) for p in given]
    program = programs[0]
    scene = str(find_user_file(args.scene)) if args.scene is not None else str(DEFAULT_SCENE)
    inputs = [path for p in programs for path in check_program(p)]
    if len(programs) > 1 and any(Path(p).is_dir() for p in programs):
        raise InputError(f"program {program}: a GPL project folder is run alone, not with other files")
    inputs.append(check_input_file(scene, "scene"))
    if getattr(args, "expect", None):
        inputs.append(check_input_file(args.expect, "expectation file"))
    outputs = {what: path for what, path in (("report", args.report), ("recording", args.rrd),
                                             ("JUnit file", getattr(args, "junit", None))) if path}
    for what, path in outputs.items():
        check_output(path, what, inputs)
    check_distinct(outputs)
    if args.report or args.rrd:
        root = sandbox_root(program, args.report or args.rrd)
        try:
            check_root(root)
        except SandboxError as err:
            raise InputError(f"sandbox folder {err}") from None


def validate_check(args: argparse.Namespace) -> None:
    """`twin check`: the report and expectation files readable, the JUnit file writable."""
    inputs = [check_input_file(args.report, "report"), check_input_file(args.expect, "expectation file")]
    if args.junit:
        check_output(args.junit, "JUnit file", inputs)


# ------------------------------------------------------------------ commands
def _run(args: argparse.Namespace) -> int:
    from .runner import run_program

    validate_run(args)
    expect, code = _load_expectations(args)
    if code is not None:
        return code
    if args.seeds is not None:
        return _run_seeds(args, expect)
    try:
        result = run_program(
            args.program, scene=args.scene, main=args.main, report_path=args.report,
            rrd_path=args.rrd, max_sim_time=args.max_sim_time, seed=args.seed,
            max_wall_time=args.max_wall_time, no_progress_limit=args.no_progress_limit,
            progress=_show_progress(args), handle_signals=True, spawn=args.spawn, connect=args.connect,
        )
    except ProgramError as err:
        print(str(err), file=sys.stderr)
        return EXIT_INPUT_ERROR if err.code is None else EXIT_PROGRAM_ERROR
    for error in result.report.errors:
        print(ProgramError.from_dict(error), file=sys.stderr)
    report = result.report
    print(_summary(report), file=sys.stderr)
    if report.interrupted:
        return INTERRUPTED
    if expect is not None:
        return _check_run(args, report, expect)
    return EXIT_PROGRAM_ERROR if report.errors else EXIT_OK


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


def _sweep(args: argparse.Namespace) -> int:
    from .check import ExpectError, load_expect
    from .sweep import cases, parse_param, run_sweep, summarise, write_summary

    try:
        params = [parse_param(p) for p in args.param]
        expect = load_expect(args.expect) if args.expect else None
    except (ValueError, ExpectError) as e:
        print(f"twin sweep: error: {e}", file=sys.stderr)
        return 2
    for program in args.program:  # as twin run checks them, before any run starts
        check_program(program)
    check_input_file(args.scene, "scene")
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        print(f"twin sweep: error: --out {out}: not a folder", file=sys.stderr)
        return 2
    all_cases = cases(list(range(args.first_seed, args.first_seed + args.seeds)), params)
    try:
        rows = run_sweep(args.program, args.scene, all_cases, out, main=args.main, max_sim_time=args.max_sim_time,
                         expect=expect, workers=args.workers, ray_address=args.ray)
    except ProgramError as err:
        print(f"twin sweep: error: {err}", file=sys.stderr)
        return 2
    json_path, csv_path = write_summary(rows, out)
    print(summarise(rows), file=sys.stderr)
    print(f"twin sweep: summary in {json_path} and {csv_path}", file=sys.stderr)
    return 1 if any(r["status"] == "fail" for r in rows) else 0


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

    validate_run(args)
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

    validate_check(args)
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
              f"{model.K[0, 0]:.1f} px; principal point {model.principal} ({model.K[0, 2]:.1f}, {model.K[1, 2]:.1f}); "
              f"written to {path}")
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
    run.add_argument("--max-sim-time", type=positive_seconds, default=3600.0,
                     help="stop after this many simulated seconds")
    run.add_argument("--max-wall-time", type=positive_seconds, default=None,
                     help="stop after this many seconds of real time (default: no limit)")
    run.add_argument("--no-progress-limit", type=limit_seconds, default=None, metavar="S",
                     help="stop a run in which nothing moves and no signal changes for S simulated "
                          "seconds (default: the scene's [controller] no_progress_s, else 30; 0: never)")
    run.add_argument("--seed", type=non_negative_int, default=None, help="random seed (default: the scene's)")
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
    serve.add_argument("--speed", type=positive_number, default=1.0,
                       help="simulated seconds per wall second (default 1)")
    serve.add_argument("--max-sim-time", type=float, default=float("inf"), help="stop after this many simulated seconds")
    serve.add_argument("--seed", type=non_negative_int, default=None, help="random seed (default: the scene's)")
    serve.add_argument("--port", type=_port_pair, action="append", default=[], metavar="PROGRAM=REAL",
                       help="listen on loopback port REAL where the program asks for PROGRAM (0: any free "
                       "port; the ports used are printed); may be repeated")
    serve.set_defaults(handler=_serve)

    sweep = sub.add_parser("sweep", help="run a program over seeds and scene parameters, in parallel processes "
                           "or on a Ray cluster, and summarise")
    sweep.add_argument("scene", help="cell description")
    sweep.add_argument("program", nargs="+", help="V+ program files or a GPL project folder (as for twin run)")
    sweep.add_argument("--seeds", type=_positive_int, default=1, metavar="N", help="seeds per parameter set")
    sweep.add_argument("--first-seed", type=non_negative_int, default=0, metavar="S", help="the first seed (default 0)")
    sweep.add_argument("--param", action="append", default=[], metavar="KEY=V1,V2,...",
                       help="scene value by dotted key (controller.monitor_speed=50,100; an array of tables "
                       "by name or index: conveyor.infeed.speed=80,100); every combination is run; may be repeated")
    sweep.add_argument("--workers", type=_positive_int, default=None, metavar="K",
                       help="local processes (default: one per core)")
    sweep.add_argument("--ray", default=None, metavar="ADDRESS",
                       help="run on a Ray cluster instead (auto, host:port, or local); needs twin[ray]")
    sweep.add_argument("--out", default="sweep-out", help="folder for the per-run reports and the summary")
    sweep.add_argument("--main", default=None, help="program to execute (as for twin run)")
    sweep.add_argument("--max-sim-time", type=positive_seconds, default=3600.0, help="stop each run after this many simulated seconds")
    sweep.add_argument("--expect", default=None, help="expectations every run must meet (as for twin check)")
    sweep.set_defaults(handler=_sweep)

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
    try:
        args = parser.parse_args(argv)
    except SystemExit as stop:  # argparse has printed the usage and what is wrong
        return EXIT_OK if stop.code in (0, None) else EXIT_INPUT_ERROR
    try:
        return args.handler(args)
    except InputError as err:
        print(f"twin: error: {err}", file=sys.stderr)
        return EXIT_INPUT_ERROR
    except Exception as err:  # noqa: BLE001 - whatever it is, it is ours, not the user's
        print(internal_error_message(err), file=sys.stderr)
        return EXIT_INTERNAL_ERROR


if __name__ == "__main__":
    sys.exit(main())
