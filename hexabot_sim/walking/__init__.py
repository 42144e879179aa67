"""Legged robots walking on contact physics, for any layout of the 3-DOF leg: parameters and feasibility, the scene,
the run, its metrics and figures. A robot folder binds its parameter class (a WalkParams with its ROBOT) to these."""
