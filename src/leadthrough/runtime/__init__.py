"""Runtime: the robot interface, the control loop, recording and the excitation procedure."""
