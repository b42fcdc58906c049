"""The base every layer stands on: errors, numerical tolerances and safe file output."""
