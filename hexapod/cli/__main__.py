import sys

from hexapod.cli.main import main

sys.exit(main())
