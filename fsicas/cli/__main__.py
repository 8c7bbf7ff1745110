"""``python -m fsicas.cli``: the same entry point as the ``fsicas`` command."""
from . import main

raise SystemExit(main())
