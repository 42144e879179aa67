"""Controllers: given state and targets, return commands (no file I/O, no MuJoCo)."""
