import sys

from hexapod.cli.entry import main

sys.exit(main())
