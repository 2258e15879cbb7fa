"""``python -m drive_link.cli``: the ``drive-link`` command."""

import sys

from .main import main

__all__ = ["main"]

if __name__ == "__main__":
    sys.exit(main())
