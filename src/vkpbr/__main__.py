"""`python -m vkpbr` is the `vkpbr` command."""

import sys

from vkpbr.app.cli import main

sys.exit(main())
