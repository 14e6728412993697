"""``python -m skinhil`` runs the command line."""

import sys

from skinhil.cli import main

sys.exit(main())
