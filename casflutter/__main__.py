"""``python -m casflutter``: the ``casflutter`` command."""

import sys

from .cli import main

sys.exit(main())
