"""Statistics of rolls against a target distribution."""
