"""``python -m qsa``: the command line (:func:`qsa.cli.main`)."""

import sys

from qsa.cli import main

sys.exit(main())
