"""``python -m fsicas.cli``: the same entry point as the ``fsicas`` command."""
from . import main

__all__: list[str] = []

raise SystemExit(main())
