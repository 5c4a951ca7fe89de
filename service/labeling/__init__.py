"""The chain window after window: one loop, the per-association steps, outcomes, statistics, one entry point."""
