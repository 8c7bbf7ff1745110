"""``python -m fsicas``: the same as the ``fsicas`` command."""
from .console import main

__all__: list[str] = []

raise SystemExit(main())
