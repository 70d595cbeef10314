"""Estimation of the operator torque: the momentum Kalman observer and the classical one."""
