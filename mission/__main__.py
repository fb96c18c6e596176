"""`python -m mission` is the `auv` command."""

import sys

from mission.cli import main

sys.exit(main())
