"""Analytic kinematics in pure numpy: DH transforms, forward kinematics, Jacobians, inverse kinematics."""
