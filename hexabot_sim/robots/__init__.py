"""One folder per robot: its scenario modules and, in its `__init__`, the `SCENARIOS` it declares (light: no MuJoCo)."""
