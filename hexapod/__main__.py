"""``python -m hexapod``: the same as the ``hexapod`` command."""

import sys

from hexapod.cli import main

sys.exit(main())
