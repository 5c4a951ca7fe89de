"""Scenarios on labeled recordings: simulators, the demo scene, scores, plots and the integrality corpus."""
