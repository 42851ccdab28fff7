"""``python -m klaw_ocp`` is the ``klaw-ocp`` command."""
import sys

from .cli import main

sys.exit(main())
