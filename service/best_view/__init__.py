"""Best view around the mathematics of ``formulations.best_view``: cost tables, camera-mode markers."""
