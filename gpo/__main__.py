"""``python -m gpo``: the command line (``gpo.cli``)."""

import sys

from gpo.cli import main

if __name__ == "__main__":
    sys.exit(main())
