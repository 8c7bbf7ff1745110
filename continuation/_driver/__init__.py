"""The driver: ``continuation()``, the PALC step iterator, Newton, the location of special
points, user hooks, settings, the recorded Branch, and the ``Problem`` interface they
drive (a curve compiled by the CasADi layer). Knows no kind of problem; imports
``_casadi`` and ``_linalg``."""
