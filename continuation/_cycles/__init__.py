"""Periodic orbits: orthogonal collocation (mesh, pointwise blocks, the condensed solver
of its intervals and chain), multiple shooting, Floquet multipliers, cycle curves,
symmetry and branch switching. Imports every other room."""
