"""Linear algebra: cheap sparse assembly of bordered matrices, LU factors of stacks of
matrices by LAPACK, and one BLAS thread around a run. Imports no other room."""
