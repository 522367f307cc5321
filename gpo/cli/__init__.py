"""The ``python -m gpo`` command line: one module per command, each its parser (``add_arguments``) and its ``run``.

python -m gpo demo [--out DIR]    figures, tables and the sample recording's odometry, written to DIR
python -m gpo simulate --preset NAME --out BAG    a simulated recording rendered into a bag
python -m gpo info BAG    topics, types, counts, rates, image sizes
python -m gpo recording [NAME ...] [--jobs N]    the cached bags of simulated presets, rendered N at a time if needed
python -m gpo sample-data [--out DIR]    the small sample files of data/
python -m gpo calibrate IMAGES... --board 7x5 --square S [--model eucm] --out calib.yaml    a camera's intrinsics
python -m gpo mount IMAGE --camera CALIB --board 7x5 --square S [--at X Y YAW] --out mount.yaml   the mount
python -m gpo config BAG [--camera CALIB] [--mount mount.yaml] --out rig.yaml   a run config from the bag, commented
python -m gpo run BAG --config RIG.yaml --out traj.tum [--method METHOD] [--topic T]    the odometry
python -m gpo run BAG ...   without --config: the config proposed from what the bag holds (as gpo config)
python -m gpo run BAG ... --write-bag OUT.bag    also a copy of the bag with the estimate as nav_msgs/Odometry
python -m gpo evaluate EST.tum GT [--gt-topic T] [--align none|origin|se2|se3|posyaw] [--plot OUT.png]
python -m gpo table3 [--route ROUTE]   the first paper's Table 3 on short1-3, on the ortho-GPI, the paper's beside
python -m gpo table4 [PATH ...]   the first paper's Table 4 on long1-3, the paper's beside, the suite's measures
python -m gpo table2 [EXPERIMENT ...]   the second paper's Table 2 over its experiments (and chapter 08's floors)
python -m gpo sweep SPEC.yaml --out DIR [--scheduler tcp://HOST:PORT] [--workers N]   many runs on Dask (gpo.batch)
python -m gpo sweep-report DIR    PNG plots of a sweep's errors against each parameter, per recording and overall

Every command checks its inputs and output paths before it works, never writes onto one of its inputs, and
writes each file to a temporary name and then renames it, the files of one result as one set
(``gpo.io.outputs.write_together``); a result it flags (an unreliable calibration, a run stopped early, interrupted,
or that measured fewer than half its frames) does not replace a file already there but goes beside it
(``NAME.flagged.EXT``), unless ``--force``. Ctrl-C and SIGTERM end a command with exit code 130 and no traceback
whenever they come; a run writes the frames it did, whatever a second signal does (``common.Interruption``). A
command module imports what only it needs (the simulator, matplotlib, Dask) inside its ``run``, so that every command
starts quickly.
"""

from __future__ import annotations

import argparse
import logging
import signal
import sys

from gpo.cameras.calibrate import CalibrationError
from gpo.cli import (
    calibrate,
    config,
    demo,
    evaluate,
    info,
    mount,
    recording,
    run,
    sample_data,
    simulate,
    sweep,
    sweep_report,
    table2,
    table3,
    table4,
)
from gpo.cli.common import EXIT_CODES, INTERRUPTED, Interruption

COMMANDS = (
    demo,
    simulate,
    info,
    sample_data,
    recording,
    calibrate,
    mount,
    config,
    run,
    table3,
    table4,
    table2,
    evaluate,
    sweep,
    sweep_report,
)
"""Every command's module, in the order ``--help`` lists them."""


def main(argv: list[str] | None = None) -> int:
    """Parse ``argv`` (default: the process's arguments), run the command, and return its exit code. Ctrl-C and
    SIGTERM (``Interruption``) end it with ``INTERRUPTED`` and no traceback, whenever they come; what gpo's modules
    log as warnings is printed on stderr, a line each."""
    interruption = Interruption()
    previous = {kind: signal.signal(kind, interruption) for kind in (signal.SIGINT, signal.SIGTERM)}
    warning_lines = logging.StreamHandler(sys.stderr)  # what gpo's modules warn of (a full cache), a line each
    warning_lines.setLevel(logging.WARNING)
    warning_lines.setFormatter(logging.Formatter("warning: %(message)s"))
    logging.getLogger("gpo").addHandler(warning_lines)
    debug = False
    try:
        parser = _parser()
        try:
            args = parser.parse_args(argv)
        except SystemExit as exit:  # usage errors (2) and --help (0), returned like every other outcome
            return exit.code if isinstance(exit.code, int) else 2
        debug = args.debug
        return args.run(args)
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return INTERRUPTED
    except Exception as error:
        if debug:
            raise
        known = isinstance(error, ValueError | OSError | CalibrationError)
        print(f"error: {error}" if known else f"error: {type(error).__name__}: {error}", file=sys.stderr)
        if not known:
            print("(--debug shows where it arose)", file=sys.stderr)
        return 1
    finally:
        logging.getLogger("gpo").removeHandler(warning_lines)
        for kind, handler in previous.items():
            signal.signal(kind, handler)


def _parser() -> argparse.ArgumentParser:
    """The command line's parser: ``--debug`` and a subcommand a module of ``COMMANDS``."""
    parser = argparse.ArgumentParser(
        prog="python -m gpo",
        description="visual odometry from the floor: the suite's commands",
        epilog=EXIT_CODES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--debug", action="store_true", help="show the traceback of an error")
    commands = parser.add_subparsers(dest="command", required=True)
    for command in COMMANDS:
        command.add_arguments(commands.add_parser(command.NAME, help=command.HELP))
        commands.choices[command.NAME].set_defaults(run=command.run)
    return parser
