"""Equilibria and their codimension-one curves (Hopf, fold): their augmented systems,
generalized eigenvalues and the first Lyapunov coefficient. Imports ``_driver``,
``_casadi`` and ``_linalg``."""
