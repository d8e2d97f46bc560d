"""``python -m screening.cli``."""

import sys

from screening.cli.commands import main

if __name__ == "__main__":
    sys.exit(main())
