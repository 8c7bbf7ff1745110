"""Generic continuation and bifurcation analysis of M(x,p) xdot = F(x,p) on CasADi."""
