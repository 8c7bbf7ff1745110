"""The bifurcation diagram: branches continued and switched onto recursively (diagram)."""
