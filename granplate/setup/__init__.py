"""Set-up layer: materials, scenarios (dataclasses, TOML I/O, validation), layouts, presets.

Imports nothing of granplate but errors and version."""
