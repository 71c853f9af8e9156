"""``python -m adparm``: the same command line as ``adparm``."""

import sys

from .cli import main

sys.exit(main())
