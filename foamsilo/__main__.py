"""``python -m foamsilo``."""

import sys

from foamsilo.cli import main

sys.exit(main())
