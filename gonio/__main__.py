"""``python -m gonio`` is the ``gonio`` command."""

import sys

from gonio.cli import main

sys.exit(main())
