"""The live explorer: the model in a browser (``fsicas explore``, docs/explore.md), a
Panel app that shows what the library's analyses compute, tier by tier: the instant
eigen-analysis, the onset, the boundary map as a background job. Needs the ``explore``
extra (panel, bokeh, param)."""

__all__ = ["serve"]


def serve(*args, **kwargs):
    """:func:`fsicas.explore.server.serve` (Panel is imported only when serving)."""
    from .server import serve as run
    return run(*args, **kwargs)
