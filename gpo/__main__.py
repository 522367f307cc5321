"""``python -m gpo`` and the ``gpo`` script: the command line (``gpo.cli``), which Ctrl-C and SIGTERM end with exit
code 130 and no traceback from its first instant, while its modules are still being imported."""

import signal
import sys

INTERRUPTED = 130  # gpo.cli.common's, before gpo.cli can be imported


def main() -> int:
    """The command line's exit code; SIGTERM is Ctrl-C before ``gpo.cli`` takes both over."""
    signal.signal(signal.SIGTERM, signal.default_int_handler)
    try:
        from gpo.cli import main as command_line  # numpy, OpenCV, pydantic, rosbags: a second or so

        return command_line()
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return INTERRUPTED
    finally:
        for kind in (signal.SIGINT, signal.SIGTERM):  # the process is ending: a late signal changes nothing
            signal.signal(kind, signal.SIG_IGN)


if __name__ == "__main__":
    sys.exit(main())
