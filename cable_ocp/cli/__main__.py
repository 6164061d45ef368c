"""``python -m cable_ocp.cli``: the command line, as the ``cable-ocp`` script."""

import sys

from cable_ocp.entry import main

sys.exit(main())
