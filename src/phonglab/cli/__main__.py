"""``python -m phonglab.cli``: the same as the ``phonglab`` command."""

import sys

from . import main

sys.exit(main())
