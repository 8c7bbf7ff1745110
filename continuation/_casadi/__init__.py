"""The CasADi layer: the vector field and its derivatives, lifted matrices, compiled
systems with exact sparse Jacobians bound to parameter values, functions called
zero-copy on NumPy (and ``continuation.compilation``, kept at the package top for its
public path). Imports ``_linalg`` only."""
